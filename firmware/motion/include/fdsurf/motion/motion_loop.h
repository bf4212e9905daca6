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
};

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
};

/// Converts limits to per-tick units. Returns false when they cannot be
/// served: max_rate or travel_rate of 0 or above tick_hz, or an
/// acceleration below 2^-24 steps per tick² (too small to represent at this
/// tick rate) or above either speed limit per tick.
bool ToTickLimits(const MotionLimits& limits, TickLimits* out);

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

  /// Sets the limits used from now on; call only when AtRest() and Empty().
  /// The speed limit is limits.max_speed while the pen is down and
  /// limits.travel_speed while it is up; it changes only where the loop
  /// passes a pen event, which it always does at rest (docs/motion.md).
  void Configure(const TickLimits& limits) { limits_ = limits; }
  FDSURF_NODISCARD const TickLimits& limits() const { return limits_; }

  /// The most pen events buffered at once. The loop stops at every pen
  /// event, so it never needs the path beyond the next one; holding at most
  /// this many keeps the length of each run between them in a small ring,
  /// and passing a pen event in Tick() costs a few instructions instead of a
  /// walk over the buffer (which, at 64-bit additions, cost an AVR 33 000
  /// cycles with 256 entries).
  static constexpr uint8_t kMaxPenEvents = 4;

  /// Appends an entry; false (and nothing changes) when Full().
  bool Push(uint8_t entry);
  /// No room for an entry of any kind: the buffer is full, or it holds
  /// kMaxPenEvents pen events.
  FDSURF_NODISCARD bool Full() const { return count_ == capacity_ || stops_ == kMaxPenEvents; }
  FDSURF_NODISCARD bool Empty() const { return count_ == 0; }
  FDSURF_NODISCARD uint16_t Count() const { return count_; }
  /// At rest, not waiting for the pen, nothing buffered.
  FDSURF_NODISCARD bool Idle() const { return count_ == 0 && speed_ == 0 && pen_wait_ == 0; }

  /// Advances one tick: updates the speed, executes at most one unit move or
  /// one pen change, and reports what to output.
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
  FDSURF_NODISCARD bool HeldAtPause() const { return pausing_ && speed_ == 0 && pen_wait_ == 0; }

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

 private:
  FDSURF_NODISCARD uint8_t At(uint16_t offset) const { return storage_[(head_ + offset) & mask_]; }
  void Pop();
  static uint32_t LengthOf(uint8_t move);

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
  TickLimits limits_ = {0, 1, 0, 0};
  int32_t position_[3] = {0, 0, 0};
  uint32_t moves_ = 0;
  bool pen_down_ = false;
  bool stopping_ = false;
  bool pausing_ = false;
};

}  // namespace motion
}  // namespace fdsurf
