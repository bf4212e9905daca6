// SPDX-License-Identifier: MIT
// Speed caps from the path's turning, so that each axis's acceleration stays
// within its limit on curves and through joins (docs/motion.md, "Each axis
// on curves").
//
// The motion loop limits the path's tangential acceleration to a. An axis
// also sees the centripetal part v²·κ (κ = x'', the second derivative of the
// position by path length, perpendicular to the path), and
// |a_t·t_i + v²·κ_i| ≤ √(a² + (v²·|κ|)²), so every axis keeps its limit A
// while v²·|κ| stays within the turn budget C = √(A² − a²). TurnCaps
// measures κ on the unit moves themselves, as second differences over
// chords of m = 4, 8, 16 and 32 moves
//
//     d = (p[c+m] − p[c]) − (p[c] − p[c−m])        (whole steps per axis)
//
// (the shorter chords leave out the 2 steps per axis that rounding the
// points to steps can make; the longest counts all), and turns each chord
// that binds into a speed cap for its 2m moves. The cap is kept as a braking
// distance (B(n) ≤ cap, which the loop compares with the braking distance it
// already keeps), so the tick loop compares and adds only; the divisions
// happen here, when a move is pushed, and only for chords whose turning
// binds (a threshold computed at configuration skips the others).
//
// A move's cap is final once every chord that covers it has been measured,
// 2·32 − 1 moves after it; until then the loop treats the end of the final
// moves as a point where it must be able to stop. Final caps are kept as
// regions (runs of moves under one cap) in a small deque ordered so that its
// front is the one that binds now (the minimum of start + cap over what is
// ahead; a region that another one dominates is dropped). docs/motion.md,
// "Each axis on curves", has the derivation and the proof.
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"

// FDSURF_DEVICE_TURN_CAPS=0 builds the class below without caps (a device
// that must save 6 KB of flash and 400 B of RAM: the Arduino Uno); the
// device then holds each axis's limit by a lower top speed alone
// (ToTickLimits(), docs/motion.md "A device without turn caps").
#ifndef FDSURF_DEVICE_TURN_CAPS
#define FDSURF_DEVICE_TURN_CAPS 1
#endif

namespace fdsurf {
namespace motion {

/// ⌊√n⌋ for any 64-bit n, by bisection on the root (32 rounds: at
/// configuration only).
uint64_t FloorSqrt(uint64_t n);

#if FDSURF_DEVICE_TURN_CAPS

class TurnCaps {
 public:
  /// Chords of 4 << k moves, k = 0..kChords-1.
  static constexpr int kChords = 4;
  static constexpr uint16_t kMaxChord = 4u << (kChords - 1);
  /// Moves pushed but not final yet: those a chord still to come may cover.
  static constexpr uint16_t kPendingMoves = 2 * kMaxChord - 1;
  /// A power of two: the tick indexes the ring with a mask (a Cortex-M0
  /// has no divide instruction).
  static constexpr uint8_t kMaxRegions = 8;
  /// Caps are kept as one-byte codes of B_c/a with three significant bits
  /// (Coarsen() in turn_caps.cc), ordered as the values; this one is none.
  static constexpr uint8_t kNoCap = 0xFF;
  /// No constraint (a distance or braking bound larger than any).
  static constexpr uint64_t kUnbounded = ~0ull;

  /// For each chord, the doubled turn at or below which its cap cannot bind
  /// (divides 64-bit numbers: ToTickLimits() calls it, outside any lock).
  static void SkipThresholds(uint32_t turn_budget, uint32_t top_speed, uint32_t (&skip)[kChords]);
  /// The largest top speed (2^-24 steps per tick) at which no chord's cap
  /// can bind on any path of unit moves, for `turn_budget` (as above; 0:
  /// none, returns 2^24): ⌊√(budget·2^26/3)⌋, from the shortest chord's
  /// largest turn (docs/motion.md, "A device without turn caps"). Below it
  /// the caps change nothing, so a device without them keeps each axis
  /// within its limit by this top speed alone.
  static uint32_t TopSpeedNoChordBinds(uint32_t turn_budget);
  /// `turn_budget`: the largest centripetal acceleration, 2^-24 steps per
  /// tick² (TickLimits::turn_budget; 0: nothing is capped); `accel` a;
  /// `top_speed` the larger speed limit; `skip` from SkipThresholds().
  /// Forgets everything (call at rest with nothing buffered). No division.
  void Configure(uint32_t turn_budget, uint32_t accel, uint32_t top_speed,
                 const uint32_t (&skip)[kChords]);
  /// Forgets the moves and regions; the path coordinate restarts at 0.
  void Clear();

  /// What becomes final with one entry: `length` more of the path (2^-24
  /// steps), when `capped` under the braking bound `braking` (B_c, a
  /// multiple of a, worked out when measuring so that the commit only adds),
  /// and with `stop` a stop region at its end.
  struct Final {
    /// At most kPendingMoves moves' length (< 2^31).
    uint32_t length;
    uint64_t braking;
    bool capped;
    bool stop;
  };

  // Each entry is measured, then committed. Measuring is the costly half and
  // touches nothing At() reads, so an MCU does it with the step interrupt
  // enabled and masks it only for Commit() (a few additions). Every Final
  // is committed before the next measurement.

  /// Measures a unit move, `length` = LengthOfMove(move); returns the move
  /// that becomes final (the one kPendingMoves back, or none yet).
  Final Measure(uint8_t move, uint32_t length);
  /// Makes every measured move final (the pending ones as one region under
  /// their lowest cap) and starts a new window: no chord spans this point.
  /// With `stop`, the loop must also come down to the lowest speed (a) here:
  /// the path may turn any way after it (used when the producer has nothing
  /// more for now; a pen event needs no stop, the loop rests there anyway).
  Final MeasureAll(bool stop);
  /// Makes `final` final: extends the final moves and appends its regions.
  /// Needs HasRoom() beforehand.
  void Commit(const Final& final);
  /// Room for what the next Commit() may add (two regions).
  FDSURF_NODISCARD bool HasRoom() const { return count_ + 2 < kMaxRegions; }
  /// Moves measured that are not final yet.
  FDSURF_NODISCARD bool HasPending() const { return final_end_ != pushed_end_; }

  /// What the caps allow at path coordinate `position` (which only grows,
  /// except that a pause may take it back to the start of the head move).
  struct Bounds {
    /// The braking distance B(n') the next speed may have (inside a region).
    uint64_t braking;
    /// Path coordinate bounding x + v' + B(n'): the end of the final moves
    /// or the key of the next region, whichever is first.
    uint64_t limit;
  };
  /// Drops the regions that end at or before `position`, then returns the
  /// bounds there. Called on every tick: the bounds are kept until the
  /// position reaches the next region boundary or a new region comes, so
  /// most ticks cost one comparison. (A pause that takes the position
  /// back keeps a started region's bound in force: stricter, never looser.)
  Bounds At(uint64_t position) {
    if (position >= valid_until_) Recompute(position);
    return bounds_;
  }

 private:
  /// 16 bytes (the Mega's RAM is counted): a region is at most 2^32 − 1
  /// long (a longer run starts a new one) and B_c + a is clamped below 2^32
  /// (a lower cap, conservative) when measured.
  struct Region {
    uint64_t start;
    uint32_t length;
    /// B_c + a, B_c a multiple of a: inside the region B(n') ≤ B_c, ahead of
    /// it v' + B(n') ≤ key − position with key = start + reach.
    uint32_t reach;
    FDSURF_NODISCARD uint64_t End() const { return start + length; }
    FDSURF_NODISCARD uint64_t Key() const { return start + reach; }
  };
  static constexpr uint16_t kHistory = 2 * kMaxChord;
  /// What rounding alone can add to a chord's turn: each point of a
  /// step-exact path is the exact point rounded to whole steps (within half
  /// a step on each axis, plus the engine's error of a hundredth), and d
  /// weighs three points 1, 2, 1. The chords shorter than the longest allow
  /// it; the longest does not.
  static constexpr int kRoundingTurn = 2;
  /// The rounding chord k's turn leaves out on each axis: kRoundingTurn for
  /// the shorter chords, none for the longest (it counts all of it).
  static int8_t RoundingOf(int chord) {
    return chord == kChords - 1 ? 0 : static_cast<int8_t>(kRoundingTurn);
  }

  /// The cap (code of B_c/a) of a chord whose doubled turn exceeds its
  /// skip threshold, `length` its shorter half, or kNoCap (the 64-bit half
  /// of the test: rarely reached, so out of Measure()'s common path).
  FDSURF_NODISCARD uint8_t CapOf(uint32_t doubled_turn, uint32_t length) const;
  /// Measures chord kChord (m = 4·2^kChord moves ending at the newest one,
  /// which the window holds whole) and, past its skip threshold, Bind()s it.
  template <int kChord>
  void MeasureChord();
  /// The cap of a chord of m moves with `doubled_turn`, applied to the 2m
  /// newest moves' pending caps (the rare half of MeasureChord()).
  void Bind(uint16_t m, uint16_t doubled_turn);
  /// The length of the `count` moves that end `back` moves before the
  /// newest (only for a chord past its skip threshold).
  FDSURF_NODISCARD uint32_t LengthOfMoves(uint16_t back, uint16_t count) const;
  FDSURF_NODISCARD Final FinalOf(uint32_t length, uint8_t cap, bool stop) const;
  void AppendRegion(uint64_t start, uint64_t end, uint64_t braking);
  void Recompute(uint64_t position);
  void ResetWindow();

  // Configuration.
  uint32_t budget_ = 0;
  uint32_t accel_ = 1;
  uint32_t top_speed_ = 0;
  /// A budget is set; without one every move is final at once.
  bool limited_ = false;
  /// A chord of kind k binds only if its doubled turn exceeds skip_[k]
  /// (clamped to 16 bits: a doubled turn is at most 256).
  uint16_t skip_[kChords] = {};
  /// Bit k: chord k's threshold is below its largest doubled turn, so it
  /// may bind; the others are not measured.
  uint8_t binding_chords_ = 0;

  // The window of recent moves (since the last MeasureAll()).
  /// The moves, and the position after each (per axis, in whole steps
  /// modulo 256: a chord's turn p[t] − 2·p[t−m] + p[t−2m] is at most 2m ≤ 64
  /// in magnitude, so it comes out exact in 8-bit arithmetic), in rings
  /// indexed by a mask. The slot before the window's first move holds its
  /// start, position 0.
  uint8_t history_[kHistory] = {};
  int8_t positions_[kHistory][3] = {};
  /// Per pending move, the lowest cap of the chords measured so far.
  uint8_t pending_cap_[kHistory] = {};
  /// The newest move's slot.
  uint8_t newest_ = 0;
  /// Moves in the window, counted up to kHistory + 1.
  uint16_t in_window_ = 0;
  /// The position after the newest move (modulo 256).
  int8_t position_[3] = {};

  /// Where the measured moves end (the producer's alone) and where the final
  /// ones end (written by Commit(), read by the tick).
  uint64_t pushed_end_ = 0;
  uint64_t final_end_ = 0;
  Region regions_[kMaxRegions] = {};
  /// At()'s answer, good while the position is below valid_until_.
  Bounds bounds_ = {kUnbounded, 0};
  uint64_t valid_until_ = 0;
  /// The key in bounds_.limit (kUnbounded: none), so that Commit() can move
  /// the limit with the final end without a recomputation.
  uint64_t next_key_ = ~0ull;
  uint8_t first_ = 0;
  uint8_t count_ = 0;
};

#else
/// A device built without turn caps (FDSURF_DEVICE_TURN_CAPS=0, the Arduino
/// Uno's firmware: they are 6 KB of its 32): nothing is measured, every move
/// is final at once, and no region binds. ToTickLimits() keeps each axis
/// within its limit instead by a top speed at which no chord could bind
/// (TopSpeedNoChordBinds()); the same interface, so MotionLoop is unchanged.
class TurnCaps {
 public:
  static constexpr int kChords = 4;
  static constexpr uint64_t kUnbounded = ~0ull;
  /// As the capped class's (the same derivation).
  static uint32_t TopSpeedNoChordBinds(uint32_t turn_budget);
  static void SkipThresholds(uint32_t /*turn_budget*/, uint32_t /*top_speed*/,
                             uint32_t (&skip)[kChords]) {
    for (uint32_t& threshold : skip) threshold = 0;
  }
  void Configure(uint32_t /*turn_budget*/, uint32_t /*accel*/, uint32_t /*top_speed*/,
                 const uint32_t (&/*skip*/)[kChords]) {}
  void Clear() {}
  struct Final {
    uint32_t length;
    uint64_t braking;
    bool capped;
    bool stop;
  };
  Final Measure(uint8_t /*move*/, uint32_t length) { return Final{length, 0, false, false}; }
  Final MeasureAll(bool /*stop*/) { return Final{0, 0, false, false}; }
  void Commit(const Final& /*final*/) {}
  FDSURF_NODISCARD bool HasRoom() const { return true; }
  FDSURF_NODISCARD bool HasPending() const { return false; }
  struct Bounds {
    uint64_t braking;
    uint64_t limit;
  };
  /// No bound: the loop's own (the end of the buffer, the next pen event).
  FDSURF_NODISCARD Bounds At(uint64_t /*position*/) const { return Bounds{kUnbounded, kUnbounded}; }
};
#endif  // FDSURF_DEVICE_TURN_CAPS

}  // namespace motion
}  // namespace fdsurf
