// SPDX-License-Identifier: MIT
// The motion loop: a lookahead buffer of unit moves and pen events, and the
// per-tick velocity profile that turns them into step pulses.
//
// The path arrives as *unit moves*: each moves every axis by -1, 0 or +1 motor
// step (the step-exact forward-difference paths of fdsurf/adaptive.h produce
// exactly that). Every tick executes at most one unit move, so no axis ever
// steps twice in a tick. The path speed v (in 2^-24 steps of path length per
// tick) follows a trapezoidal profile built from additions only:
//
//   v is always a whole multiple of a (the acceleration per tick²), and
//   B = a·n(n−1)/2 for v = n·a is the distance needed to come to rest from v
//   (B(n+1) = B(n) + v, so B is kept with one addition per change of v).
//
// Each tick the loop takes the highest of v + a, v, v − a that still lets it
// stop before the next point where it must be at rest (a pen event, or the
// end of what is buffered): v' + B(v') ≤ distance available. If v was
// feasible on the previous tick, v − a is feasible now, so the loop can always
// stop in time; it never needs to know the future beyond its buffer.
// The choice is made once per slice of S ticks (MotionLimits::slice_ticks)
// and held over them, tested on the slice's last tick, which then keeps the
// rule on every tick of it; the ticks in between only add.
// With axis limits, speed caps on curves (TurnCaps) are points and stretches
// of the path with a braking bound of their own, kept the same way.
// docs/motion.md gives the proof and the units.
//
// Threading: Push() is called by the producer (main loop), Tick() by the step
// timer. They share the buffer's counters; on an MCU wrap Push() in a critical
// section (it is a few instructions). In the simulator both run in one thread.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/motion/entry.h"
#include "fdsurf/motion/turn_caps.h"

namespace fdsurf {
namespace motion {

/// Limits in the machine's units (steps, seconds).
struct MotionLimits {
  /// Ticks per second of the step timer.
  uint32_t tick_hz;
  /// Largest path speed with the pen down, steps per second; ≤ tick_hz.
  uint32_t max_rate;
  /// Path acceleration, steps per second².
  uint32_t accel;
  /// Rest after a pen change, milliseconds.
  uint16_t pen_delay_ms;
  /// Largest path speed with the pen up (travel), steps per second; ≤ tick_hz.
  uint32_t travel_rate;
  /// Each axis's acceleration limit, steps per second², the centripetal
  /// part on curves included; above `accel` (what is left over makes the
  /// turn budget), or 0: the axis is not limited beyond the path's `accel`.
  uint32_t axis_accel[3];
  /// Ticks per *slice*, the period at which the loop chooses whether to
  /// accelerate, cruise or brake (a power of two, 1..kMaxSliceTicks; 0
  /// counts as 1). Between two choices a tick only adds and steps, so an
  /// MCU's step interrupt pays for the 64-bit profile once per slice
  /// (docs/motion.md, "Slices").
  uint8_t slice_ticks;
};

/// The most ticks per slice (TickLimits::slice_shift ≤ 4).
constexpr uint8_t kMaxSliceTicks = 16;

/// The same limits per tick, as the loop uses them.
struct TickLimits {
  /// Largest speed with the pen down, 2^-24 steps per tick (≤ 2^24: one
  /// unit move per tick).
  uint32_t max_speed;
  /// Acceleration, 2^-24 steps per tick², ≥ 1, rounded down (conservative).
  uint32_t accel;
  uint32_t pen_delay_ticks;
  /// Largest speed with the pen up, 2^-24 steps per tick (≤ 2^24).
  uint32_t travel_speed;
  /// The largest centripetal acceleration (2^-24 steps per tick²) the turn
  /// caps allow: ⌊√(A² − a²)⌋ for the smallest axis limit A per tick (at
  /// most 2^24) and the path's a, so that √(a² + budget²) ≤ A bounds every
  /// axis (docs/motion.md); 0: no axis is limited.
  uint32_t turn_budget;
  /// TurnCaps::SkipThresholds() of the budget and the larger speed limit.
  uint32_t turn_skip[TurnCaps::kChords];
  /// log2 of MotionLimits::slice_ticks, 0..4.
  uint8_t slice_shift;
};

/// Converts limits to per-tick units. Returns false when they cannot be
/// served: max_rate or travel_rate of 0 or above tick_hz, slice_ticks not a
/// power of two up to kMaxSliceTicks, an acceleration below 2^-24 steps per
/// tick² (too small to represent at this tick rate) or above either speed
/// limit per tick, or an axis limit (not 0) that does not
/// exceed the path's acceleration per tick (AxisLimitServable()). Built
/// without turn caps (FDSURF_DEVICE_TURN_CAPS=0), it lowers both speed
/// limits to TurnCaps::TopSpeedNoChordBinds() of the turn budget, and
/// returns false when that is below the acceleration.
bool ToTickLimits(const MotionLimits& limits, TickLimits* out);

/// Whether an axis limit of `axis_accel` steps/s² leaves a turn budget over
/// the path's `accel` at `tick_hz`: its value per tick, rounded down, must be
/// above the path's.
bool AxisLimitServable(uint32_t axis_accel, uint32_t accel, uint32_t tick_hz);

/// What one tick did.
struct TickOutput {
  /// Axes that step this tick, and which of them towards negative.
  uint8_t step_mask;
  uint8_t negative_mask;
  /// 1: put the pen down now, -1: lift it now, 0: no change.
  int8_t pen;
  /// Commands whose last entry was passed this tick (0 or more).
  uint8_t commands_done;
};

class MotionLoop {
 public:
  /// `storage` holds `capacity` entries (a power of two, 2..32768); the loop
  /// does not own it. Starts at rest at position 0 with the pen up.
  MotionLoop(uint8_t* storage, uint16_t capacity);

  /// Sets the limits used from now on; call only when Idle().
  /// The speed limit is limits.max_speed while the pen is down and
  /// limits.travel_speed while it is up; it changes only where the loop
  /// passes a pen event, which it always does at rest (docs/motion.md).
  /// With turn budgets, the speed on curves is capped so that each axis
  /// keeps its limit (TurnCaps). A few dozen stores, no division (an MCU
  /// calls it with the step interrupt masked).
  void Configure(const TickLimits& limits);
  FDSURF_NODISCARD const TickLimits& limits() const { return limits_; }

  /// The most pen events buffered at once. The loop stops at every pen
  /// event, so it never needs the path beyond the next one; holding at most
  /// this many keeps the length of each run between them in a small ring,
  /// and passing a pen event in Tick() costs a few instructions instead of a
  /// walk over the buffer (which, at 64-bit additions, cost an AVR 33 000
  /// cycles with 256 entries).
  static constexpr uint8_t kMaxPenEvents = 4;

  /// Appends an entry; false (and nothing changes) when Full(). With turn
  /// budgets, a move is measured for the caps (a few dozen additions; a
  /// division only where the path turns enough to bind), and the loop
  /// plans only up to TurnCaps::kPendingMoves moves before the newest until
  /// a pen event or Flush() makes the rest final.
  bool Push(uint8_t entry) {
    if (Full()) return false;
    return Push(Prepare(entry));
  }

  /// Push() in two halves, for a producer that shares the loop with an
  /// interrupt: Prepare() does the measuring, touching nothing Tick() reads,
  /// so it runs with the interrupt enabled; Push(prepared), a few additions,
  /// under the lock. Prepare() only when !Full() (Tick() never makes the
  /// loop full), and push each prepared entry before preparing the next.
  struct PreparedEntry {
    uint8_t entry;
    TurnCaps::Final final;
  };
  PreparedEntry Prepare(uint8_t entry);
  bool Push(const PreparedEntry& prepared);

  /// The producer has nothing more for now: makes every buffered move final
  /// and brings the path down to speed a at the end of them (the path may
  /// go on in any direction). Returns false, doing nothing, when Full();
  /// does nothing when no move waits. Without turn budgets there is nothing
  /// to do. In two halves as Push(): FlushPending() says whether there is
  /// anything to do, PrepareFlush() (only then, and when !Full()) measures,
  /// CommitFlush() applies under the lock.
  bool Flush() {
    if (!FlushPending()) return true;
    if (Full()) return false;
    CommitFlush(PrepareFlush());
    return true;
  }
  FDSURF_NODISCARD bool FlushPending() const { return caps_.HasPending(); }
  TurnCaps::Final PrepareFlush() { return caps_.MeasureAll(true); }
  void CommitFlush(const TurnCaps::Final& final) { caps_.Commit(final); }
  /// No room for an entry of any kind: the buffer is full, or it holds
  /// kMaxPenEvents pen events, or the caps have no room for more regions.
  FDSURF_NODISCARD bool Full() const {
    return count_ == capacity_ || stops_ == kMaxPenEvents || !caps_.HasRoom();
  }
  FDSURF_NODISCARD bool Empty() const { return count_ == 0; }
  FDSURF_NODISCARD uint16_t Count() const { return count_; }
  /// At rest, not waiting for the pen, nothing buffered.
  FDSURF_NODISCARD bool Idle() const {
    return count_ == 0 && speed_ == 0 && pen_wait_ == 0 && slice_left_ == 0;
  }

  /// Advances one tick: at the start of a slice chooses whether the slice's
  /// ticks accelerate, cruise or brake (the 64-bit profile), then changes
  /// the speed by at most a, advances by it, executes at most one unit move
  /// or one pen change, and reports what to output. Inside a slice a tick is
  /// a few 32-bit additions.
  TickOutput Tick();

  /// Decelerates to rest along the buffered path as fast as the limits
  /// allow, then drops whatever is left. Stopped() tells when that is done.
  void Stop() {
    stopping_ = true;
    pausing_ = false;
  }
  FDSURF_NODISCARD bool Stopping() const { return stopping_; }

  /// Decelerates to rest along the buffered path as Stop() does, but keeps
  /// the buffer and holds there (no entry, pen event or not, is passed)
  /// until Resume(), which accelerates from rest again where it stopped. A
  /// pause during a pen delay lets the delay run out first. No step is lost
  /// or repeated: the position within the head move is kept.
  void Pause() {
    if (!stopping_) pausing_ = true;
  }
  void Resume() { pausing_ = false; }
  FDSURF_NODISCARD bool Pausing() const { return pausing_; }
  /// Paused and at rest: nothing moves until Resume().
  FDSURF_NODISCARD bool HeldAtPause() const {
    return pausing_ && speed_ == 0 && pen_wait_ == 0 && slice_left_ == 0;
  }

  /// Forgets the buffer and the motion state (the caller has made sure the
  /// machine is at rest). Position and counters are kept.
  void Clear();

  FDSURF_NODISCARD const int32_t* position() const { return position_; }
  void set_position(const int32_t (&position)[3]);
  FDSURF_NODISCARD bool pen_down() const { return pen_down_; }
  /// Path speed now, 2^-24 steps per tick.
  FDSURF_NODISCARD uint32_t speed() const { return speed_; }
  /// Unit moves executed since construction (wraps).
  FDSURF_NODISCARD uint32_t moves() const { return moves_; }
  /// Slices begun since construction (wraps): the ticks that ran the
  /// profile's choice (ChooseSlice()).
  FDSURF_NODISCARD uint32_t slices() const { return slices_; }

 private:
  FDSURF_NODISCARD uint8_t At(uint16_t offset) const { return storage_[(head_ + offset) & mask_]; }
  void Pop();
  /// What the first tick of a slice does before it moves: passes the
  /// entries that are not moves (a pen event at rest ends the tick), ends a
  /// stop or pause at rest, and chooses the slice. false: the tick does not
  /// move.
  bool StartSlice(TickOutput* out);
  /// The profile's choice at the start of a slice (docs/motion.md,
  /// "Slices"): sets ramp_ (or a creep) and braking_ as of the slice's end;
  /// returns log2 of the slice's ticks (the board's slice, or one tick).
  uint8_t ChooseSlice(bool braking);
  /// The tests of ChooseSlice() for a slice of 2^shift ticks, with D =
  /// `available` and B_c = `caps_braking` (docs/motion.md, "Slices").
  FDSURF_NODISCARD bool Accelerates(uint8_t shift, uint64_t available, uint64_t caps_braking) const;
  FDSURF_NODISCARD bool HasRoom(uint8_t shift, uint64_t available, uint64_t caps_braking) const;
  uint8_t Accelerate(uint8_t shift);
  /// Passes the pen event at the head (popped), at rest.
  void PassPenEvent(bool down, TickOutput* out);

  uint8_t* storage_;
  uint16_t capacity_;
  uint16_t mask_;
  uint16_t head_ = 0;
  uint16_t count_ = 0;
  /// Pen events in the buffer.
  uint8_t stops_ = 0;
  /// Length of the buffered moves before the first pen event (or all of
  /// them), less what the head move has covered of it.
  uint64_t distance_ = 0;
  /// runs_[(first_run_ + k) % kMaxPenEvents]: the length of the moves after
  /// the k-th buffered pen event, up to the next one (or the end).
  uint64_t runs_[kMaxPenEvents] = {};
  uint8_t first_run_ = 0;
  /// Progress into the head move.
  uint32_t phase_ = 0;
  uint32_t speed_ = 0;
  /// Distance needed to come to rest from speed_: a·n(n−1)/2.
  uint64_t braking_ = 0;
  uint32_t pen_wait_ = 0;
  /// Ticks of the current slice still to run, and what each does to the
  /// speed: +1 adds a, 0 keeps it, -1 takes a off (down to rest).
  uint8_t slice_left_ = 0;
  int8_t ramp_ = 0;
  /// A creep from rest (speed 0) over the distance left, less than a, in a
  /// slice of one tick; else 0.
  uint32_t creep_ = 0;
  /// a·S(S−1)/2 for the slice's S ticks: what a slice's ramp adds to the
  /// distance beyond S times its first speed (set by Configure(); below
  /// 120·2^24, as a ≤ 2^24 and S ≤ 16).
  uint32_t ramp_distance_ = 0;
  TickLimits limits_ = {0, 1, 0, 0, 0, {0, 0, 0, 0}, 0};
  /// Path coordinate (2^-24 steps since Clear()) where the head move starts;
  /// the loop is at head_start_ + phase_.
  uint64_t head_start_ = 0;
  TurnCaps caps_;
  int32_t position_[3] = {0, 0, 0};
  uint32_t moves_ = 0;
  uint32_t slices_ = 0;
  bool pen_down_ = false;
  bool stopping_ = false;
  bool pausing_ = false;
};

}  // namespace motion
}  // namespace fdsurf
