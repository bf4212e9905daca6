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

namespace fdsurf {
namespace motion {
namespace {

// The step of axis `axis` in a unit move: −1, 0 or +1.
int8_t StepOf(uint8_t move, int axis) {
  const uint8_t bits = static_cast<uint8_t>(move >> (2 * axis));
  if ((bits & 1) == 0) return 0;
  return (bits & 2) != 0 ? -1 : 1;
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
  for (int k = 0; k < kChords; ++k) skip_[k] = skip[k];
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
  newest_ = 0;
  for (int k = 0; k < kChords; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      ahead_[k][axis] = 0;
      behind_[k][axis] = 0;
    }
    ahead_length_[k] = 0;
    behind_length_[k] = 0;
  }
}

uint8_t TurnCaps::CapOf(int chord, const int8_t (&turn)[3], uint32_t length) const {
  // Per axis, the turn beyond what rounding can make (the longest chord
  // counts all of it), then a bound on the Euclidean norm of that vector:
  // for e1 ≥ e2 ≥ e3 ≥ 0, e1 + (e2 + e3)/2 ≥ √(e1² + e2² + e3²) (as
  // e1·(e2 + e3) ≥ e2² + e3²); doubled, to stay in integers.
  const int rounding = chord == kChords - 1 ? 0 : kRoundingTurn;
  uint32_t largest = 0;
  uint32_t sum = 0;
  for (const int8_t axis_turn : turn) {
    const int magnitude = axis_turn < 0 ? -axis_turn : axis_turn;
    const uint32_t excess = magnitude > rounding ? static_cast<uint32_t>(magnitude - rounding) : 0;
    sum += excess;
    if (excess > largest) largest = excess;
  }
  const uint32_t doubled_turn = largest + sum;  // 2·e1 + e2 + e3
  if (doubled_turn <= skip_[chord]) return kNoCap;
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

TurnCaps::Final TurnCaps::Measure(uint8_t move, uint32_t length) {
  pushed_end_ += length;
  // No axis limit: nothing to measure, and no move needs to wait.
  if (!limited_) return Final{length, 0, false, false};
  static_assert((kHistory & (kHistory - 1)) == 0, "the history ring is indexed by a mask");
  constexpr uint8_t kSlotMask = kHistory - 1;
  const uint8_t slot = static_cast<uint8_t>((newest_ + 1) & kSlotMask);
  if (in_window_ > 0) newest_ = slot;
  const uint16_t n = static_cast<uint16_t>(in_window_ + 1);  // moves in the window with this one
  // The moves 4, 8, …, 2·kMaxChord back: chord k's middle is 4·2^k back and
  // the one leaving its `behind` 8·2^k back, chord k + 1's middle. Each is
  // decoded once (its steps and length; 0 where the window does not reach
  // it), not once per chord and axis: this runs for every unit move, and on
  // an AVR the per-chord decoding was a fifth of the main loop.
  int8_t steps[kChords + 1][3];
  uint32_t lengths[kChords + 1];
  for (int j = 0; j <= kChords; ++j) {
    const uint16_t back = static_cast<uint16_t>(4u << j);
    // (For 2·kMaxChord back, the slot this move takes: written below.)
    const uint8_t old = history_[(newest_ + kHistory - back) & kSlotMask];
    const bool reached = n > back;
    for (int axis = 0; axis < 3; ++axis) steps[j][axis] = reached ? StepOf(old, axis) : 0;
    lengths[j] = reached ? LengthOfMove(old) : 0;
  }
  int8_t in[3];
  for (int axis = 0; axis < 3; ++axis) in[axis] = StepOf(move, axis);
  for (int k = 0; k < kChords; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      ahead_[k][axis] = static_cast<int8_t>(ahead_[k][axis] + in[axis] - steps[k][axis]);
      behind_[k][axis] =
          static_cast<int8_t>(behind_[k][axis] + steps[k][axis] - steps[k + 1][axis]);
    }
    ahead_length_[k] += length - lengths[k];
    behind_length_[k] += lengths[k] - lengths[k + 1];
  }
  history_[newest_] = move;
  pending_cap_[newest_] = kNoCap;
  in_window_ = n > kHistory ? kHistory + 1 : n;

  for (int k = 0; k < kChords; ++k) {
    const uint16_t m = static_cast<uint16_t>(4u << k);
    if (n < 2 * m) continue;
    int8_t turn[3];
    for (int axis = 0; axis < 3; ++axis) {
      turn[axis] = static_cast<int8_t>(ahead_[k][axis] - behind_[k][axis]);
    }
    const uint32_t shorter =
        ahead_length_[k] < behind_length_[k] ? ahead_length_[k] : behind_length_[k];
    const uint8_t cap = CapOf(k, turn, shorter);
    if (cap == kNoCap) continue;
    for (uint16_t back = 0; back < 2 * m; ++back) {
      uint8_t& slot_cap = pending_cap_[(newest_ + kHistory - back) & kSlotMask];
      if (cap < slot_cap) slot_cap = cap;
    }
  }
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
  return FinalOf(pushed_end_ - final_end_, lowest, stop && limited_);
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
  final_end_ += final.length;
  if (final.capped && final.length > 0) AppendRegion(start, final_end_, final.braking);
  // One unit of length long, so that it is still in force on the tick after
  // the loop reaches it (HasRoom() beforehand leaves room for both).
  if (final.stop) AppendRegion(final_end_, final_end_ + 1, 0);
  // The final end moved: At()'s limit with it (AppendRegion() has made At()
  // recompute if a new region came; a longer one keeps the bounds).
  bounds_.limit = final_end_ < next_key_ ? final_end_ : next_key_;
}

TurnCaps::Final TurnCaps::FinalOf(uint64_t length, uint8_t cap, bool stop) const {
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
