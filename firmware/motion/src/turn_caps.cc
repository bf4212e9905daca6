// SPDX-License-Identifier: MIT
#include "fdsurf/motion/turn_caps.h"

#include "fdsurf/motion/entry.h"

namespace fdsurf {
namespace motion {

uint64_t FloorSqrt(uint64_t n) {
  uint64_t low = 0;
  uint64_t high = 1ull << 32;  // high² > n
  while (high - low > 1) {
    const uint64_t middle = low + (high - low) / 2;
    if (middle * middle <= n) {
      low = middle;
    } else {
      high = middle;
    }
  }
  return low;
}

uint32_t TurnCaps::TopSpeedNoChordBinds(uint32_t turn_budget) {
  if (turn_budget == 0) return uint32_t{1} << kLengthFracBits;
  // A chord of m moves binds when its doubled turn T exceeds
  // 2·budget·(h²/2^24)/top², h ≥ m·2^24 (a move is at least a step long).
  // Per axis the turn is at most 2m, less the rounding allowance r, and
  // T ≤ 4·(2m − r) over three axes: T/m² is largest for m = 4, r = 2
  // (24/16), so top² ≤ 2·budget·2^24·16/24 = budget·2^26/3 binds nowhere.
  // budget ≤ 2^24 (ToTickLimits caps it), so the product is below 2^51.
  return static_cast<uint32_t>(FloorSqrt((static_cast<uint64_t>(turn_budget) << 26) / 3));
}

}  // namespace motion
}  // namespace fdsurf

#if FDSURF_DEVICE_TURN_CAPS

// Measure()'s per-chord work is inlined on every target: avr-gcc at -Os
// would call it, and pass what are constants as arguments.
#define FDSURF_CAPS_INLINE inline __attribute__((always_inline))

namespace fdsurf {
namespace motion {
namespace {

// The step of a unit move on the axis whose two bits `bits` are (bit 0: it
// steps, bit 1: towards negative): −1, 0 or +1. The caller shifts by a
// constant: on an AVR a shift by a variable count is a loop.
int8_t StepOfBits(uint8_t bits) {
  if ((bits & 1) == 0) return 0;
  return (bits & 2) != 0 ? -1 : 1;
}

// The turn of a chord beyond what rounding can make on each axis
// (`rounding`), doubled: for e1 ≥ e2 ≥ e3 ≥ 0, e1 + (e2 + e3)/2 ≥
// √(e1² + e2² + e3²) (as e1·(e2 + e3) ≥ e2² + e3²), so 2·e1 + e2 + e3
// bounds twice the Euclidean norm of that vector in integers.
uint16_t DoubledTurn(const int8_t (&turn)[3], int8_t rounding) {
  uint8_t largest = 0;
  uint16_t sum = 0;
  for (const int8_t axis_turn : turn) {
    const int8_t magnitude = axis_turn < 0 ? static_cast<int8_t>(-axis_turn) : axis_turn;
    const uint8_t excess = magnitude > rounding ? static_cast<uint8_t>(magnitude - rounding) : 0;
    sum = static_cast<uint16_t>(sum + excess);
    if (excess > largest) largest = excess;
  }
  return static_cast<uint16_t>(largest + sum);  // ≤ 4·64
}

// B_c/a rounded down to three significant bits, as a one-byte code that
// orders as the values: 0..7 as they are, then 8·(s + 1) + (v >> s) − 8 for
// v >> s in 8..15. Neighbouring moves on a smooth curve then share one
// region (a cap at most 1/8 lower; conservative). The largest code is
// 8·29 + 7 = 239, below kNoCap.
uint8_t Coarsen(uint32_t units) {
  if (units < 8) return static_cast<uint8_t>(units);
  uint8_t shift = 0;
  while ((units >> shift) >= 16) ++shift;
  return static_cast<uint8_t>(8 * (shift + 1) + (units >> shift) - 8);
}

uint64_t UnitsOf(uint8_t code) {
  if (code < 8) return code;
  return static_cast<uint64_t>(8 + code % 8) << (code / 8 - 1);
}

}  // namespace

void TurnCaps::SkipThresholds(uint32_t turn_budget, uint32_t top_speed, uint32_t (&skip)[kChords]) {
  const uint64_t top_squared = static_cast<uint64_t>(top_speed) * top_speed;
  for (int k = 0; k < kChords; ++k) {
    // Every move is at least 2^24 long, so a chord of m moves has
    // h²/2^24 ≥ m²·2^24 and its cap² = 2·budget·(h²/2^24)/T is at least top²
    // (no cap) while the doubled turn T ≤ 2·budget·m²·2^24 / top².
    const uint64_t m = 4u << k;
    const uint64_t bound =
        top_squared == 0 ? ~0ull : ((2ull * turn_budget * m * m) << kLengthFracBits) / top_squared;
    skip[k] = bound > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(bound);
  }
}

void TurnCaps::Configure(uint32_t turn_budget, uint32_t accel, uint32_t top_speed,
                         const uint32_t (&skip)[kChords]) {
  accel_ = accel == 0 ? 1 : accel;
  top_speed_ = top_speed;
  budget_ = turn_budget;
  limited_ = turn_budget != 0;
  binding_chords_ = 0;
  for (int k = 0; k < kChords; ++k) {
    // A doubled turn is at most 4·(2m − rounding) (|d| ≤ 2m on each axis):
    // a chord whose threshold is at or above that never binds, and is not
    // measured at all; 16 bits hold every threshold that matters.
    skip_[k] = skip[k] > 0xFFFFu ? 0xFFFFu : static_cast<uint16_t>(skip[k]);
    const uint32_t most = 4u * ((8u << k) - static_cast<uint32_t>(RoundingOf(k)));
    if (skip[k] < most) binding_chords_ = static_cast<uint8_t>(binding_chords_ | (1u << k));
  }
  Clear();
}

void TurnCaps::Clear() {
  ResetWindow();
  pushed_end_ = 0;
  final_end_ = 0;
  first_ = 0;
  count_ = 0;
  valid_until_ = 0;
}

void TurnCaps::ResetWindow() {
  in_window_ = 0;
  for (int axis = 0; axis < 3; ++axis) {
    position_[axis] = 0;
    positions_[newest_][axis] = 0;  // the window's start, before its first move
  }
}

uint8_t TurnCaps::CapOf(uint32_t doubled_turn, uint32_t length) const {
  // v²·(turn/h²) ≤ budget in steps: v² ≤ 2·budget·(h²/2^24) / doubled_turn,
  // h the shorter half of the chord in 2^-24 steps (≤ 32·√3·2^24 < 2^30, so
  // h²/2^24 < 2^36, and times 2·budget ≤ 2^25 this fits in 64 bits).
  const uint64_t h_squared = (static_cast<uint64_t>(length) * length) >> kLengthFracBits;
  const uint64_t speed_squared = 2ull * budget_ * h_squared / doubled_turn;
  const uint64_t top_squared = static_cast<uint64_t>(top_speed_) * top_speed_;
  if (speed_squared >= top_squared) return kNoCap;
  // B(n) ≤ (cap² − top·a) / 2a implies n·a ≤ cap (B(n) = v(v − a)/2a and
  // cap ≤ top); counted in whole units of a, rounded down.
  const uint64_t slack = static_cast<uint64_t>(top_speed_) * accel_;
  if (speed_squared <= slack) return 0;
  const uint64_t units = (speed_squared - slack) / (2ull * accel_) / accel_;
  return Coarsen(units > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(units));
}

uint32_t TurnCaps::LengthOfMoves(uint16_t back, uint16_t count) const {
  uint32_t length = 0;  // ≤ 32·√3·2^24 < 2^30
  for (uint16_t k = 0; k < count; ++k) {
    length += LengthOfMove(history_[(newest_ + kHistory - back - k) & (kHistory - 1)]);
  }
  return length;
}

template <int kChord>
FDSURF_CAPS_INLINE void TurnCaps::MeasureChord() {
  static_assert(kChord >= 0 && kChord < kChords, "a chord of the four");
  constexpr uint16_t m = 4u << kChord;
  constexpr uint8_t kSlotMask = kHistory - 1;
  if ((binding_chords_ & (1u << kChord)) == 0) return;
  // Its turn d = p[t] − 2·p[t−m] + p[t−2m]; for the longest chord p[t−2m]
  // is in the newest move's slot, not yet overwritten.
  const int8_t(&middle)[3] = positions_[(newest_ + kHistory - m) & kSlotMask];
  const int8_t(&start)[3] = positions_[(newest_ + kHistory - 2 * m) & kSlotMask];
  const int8_t turn[3] = {
      static_cast<int8_t>(position_[0] - 2 * middle[0] + start[0]),
      static_cast<int8_t>(position_[1] - 2 * middle[1] + start[1]),
      static_cast<int8_t>(position_[2] - 2 * middle[2] + start[2]),
  };
  // Most chords end here, in 8- and 16-bit arithmetic.
  const uint16_t doubled_turn = DoubledTurn(turn, RoundingOf(kChord));
  if (doubled_turn > skip_[kChord]) Bind(m, doubled_turn);
}

void TurnCaps::Bind(uint16_t m, uint16_t doubled_turn) {
  const uint32_t ahead = LengthOfMoves(0, m);
  const uint32_t behind = LengthOfMoves(m, m);
  const uint8_t cap = CapOf(doubled_turn, ahead < behind ? ahead : behind);
  if (cap == kNoCap) return;
  for (uint16_t back = 0; back < 2 * m; ++back) {
    uint8_t& slot_cap = pending_cap_[(newest_ + kHistory - back) & (kHistory - 1)];
    if (cap < slot_cap) slot_cap = cap;
  }
}

TurnCaps::Final TurnCaps::Measure(uint8_t move, uint32_t length) {
  AddLength(&pushed_end_, length);
  // No axis limit: nothing to measure, and no move needs to wait.
  if (!limited_) return Final{length, 0, false, false};
  static_assert((kHistory & (kHistory - 1)) == 0, "the rings are indexed by a mask");
  constexpr uint8_t kSlotMask = kHistory - 1;
  newest_ = static_cast<uint8_t>((newest_ + 1) & kSlotMask);
  const uint16_t n = static_cast<uint16_t>(in_window_ + 1);  // moves in the window with this one
  in_window_ = n > kHistory ? kHistory + 1 : n;
  history_[newest_] = move;
  pending_cap_[newest_] = kNoCap;
  // The position after this move (its steps read with constant shifts).
  int8_t* const position = position_;
  position[0] = static_cast<int8_t>(position[0] + StepOfBits(move));
  position[1] = static_cast<int8_t>(position[1] + StepOfBits(static_cast<uint8_t>(move >> 2)));
  position[2] = static_cast<int8_t>(position[2] + StepOfBits(static_cast<uint8_t>(move >> 4)));

  // Each chord of m moves that the window holds whole (none longer when
  // one is not) and that can bind, with constant m: on an AVR the chord's
  // indices are then immediate operands.
  if (n >= 2 * 4) {
    MeasureChord<0>();
    if (n >= 2 * 8) {
      MeasureChord<1>();
      if (n >= 2 * 16) {
        MeasureChord<2>();
        if (n >= 2 * 32) MeasureChord<3>();
      }
    }
  }
  for (int axis = 0; axis < 3; ++axis) positions_[newest_][axis] = position[axis];
  // The move kPendingMoves back is covered by no chord still to come.
  if (n <= kPendingMoves) return Final{0, 0, false, false};
  const uint8_t final_slot = static_cast<uint8_t>((newest_ + kHistory - kPendingMoves) & kSlotMask);
  return FinalOf(LengthOfMove(history_[final_slot]), pending_cap_[final_slot], false);
}

TurnCaps::Final TurnCaps::MeasureAll(bool stop) {
  // The pending moves: the newest min(n, kPendingMoves).
  const uint16_t pending = in_window_ < kPendingMoves ? in_window_ : kPendingMoves;
  uint8_t lowest = kNoCap;
  for (uint16_t back = 0; back < pending; ++back) {
    const uint8_t cap = pending_cap_[(newest_ + kHistory - back) % kHistory];
    if (cap < lowest) lowest = cap;
  }
  ResetWindow();
  // At most kPendingMoves moves: below 63·√3·2^24 < 2^31.
  return FinalOf(static_cast<uint32_t>(pushed_end_ - final_end_), lowest, stop && limited_);
}

void TurnCaps::Recompute(uint64_t position) {
  while (count_ > 0 && regions_[first_].End() <= position) {
    first_ = static_cast<uint8_t>((first_ + 1) & (kMaxRegions - 1));
    --count_;
  }
  bounds_ = Bounds{kUnbounded, final_end_};
  valid_until_ = kUnbounded;
  next_key_ = kUnbounded;
  if (count_ == 0) return;
  const Region& front = regions_[first_];
  uint8_t ahead = 0;
  if (front.start <= position) {
    bounds_.braking = front.reach - accel_;
    valid_until_ = front.End();
    ahead = 1;
  } else {
    valid_until_ = front.start;
  }
  if (count_ > ahead) {
    next_key_ = regions_[(first_ + ahead) & (kMaxRegions - 1)].Key();
    if (next_key_ < bounds_.limit) bounds_.limit = next_key_;
  }
}

void TurnCaps::Commit(const Final& final) {
  const uint64_t start = final_end_;
  AddLength(&final_end_, final.length);
  if (final.capped && final.length > 0) AppendRegion(start, final_end_, final.braking);
  // One unit of length long, so that it is still in force on the tick after
  // the loop reaches it (HasRoom() beforehand leaves room for both).
  if (final.stop) AppendRegion(final_end_, final_end_ + 1, 0);
  // The final end moved: At()'s limit with it (AppendRegion() has made At()
  // recompute if a new region came; a longer one keeps the bounds).
  bounds_.limit = final_end_ < next_key_ ? final_end_ : next_key_;
}

TurnCaps::Final TurnCaps::FinalOf(uint32_t length, uint8_t cap, bool stop) const {
  if (cap == kNoCap) return Final{length, 0, false, stop};
  uint64_t braking = UnitsOf(cap) * accel_;
  // Region::reach = B_c + a below 2^32: a lower multiple of a (a lower cap).
  const uint64_t most = (0xFFFFFFFFull - accel_) / accel_ * accel_;
  if (braking > most) braking = most;
  return Final{length, braking, true, stop};
}

void TurnCaps::AppendRegion(uint64_t start, uint64_t end, uint64_t braking) {
  const uint32_t reach = static_cast<uint32_t>(braking + accel_);  // < 2^32 (FinalOf)
  const uint64_t key = start + reach;
  if (count_ > 0) {
    Region& back = regions_[(first_ + count_ - 1) & (kMaxRegions - 1)];
    // The same cap right after: one longer region (nothing ahead of it
    // changes; its key, start + B_c + a, stays), while it fits.
    if (back.End() == start && back.reach == reach && end - back.start <= 0xFFFFFFFFu) {
      // At() holds the bounds until `start` only when this is the started
      // front region (any other front starts before it, or ends earlier).
      if (valid_until_ == start) valid_until_ = end;
      back.length = static_cast<uint32_t>(end - back.start);
      return;
    }
  }
  valid_until_ = 0;  // At() recomputes
  // A region behind with a key at or above this one's is dominated: ahead of
  // it and inside it, this key's bound is the tighter (docs/motion.md).
  while (count_ > 0 && regions_[(first_ + count_ - 1) & (kMaxRegions - 1)].Key() >= key) --count_;
  regions_[(first_ + count_) & (kMaxRegions - 1)] =
      Region{start, static_cast<uint32_t>(end - start), reach};
  ++count_;
}

}  // namespace motion
}  // namespace fdsurf

#endif  // FDSURF_DEVICE_TURN_CAPS
