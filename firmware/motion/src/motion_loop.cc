// SPDX-License-Identifier: MIT
#include "fdsurf/motion/motion_loop.h"

namespace fdsurf {
namespace motion {
namespace {

// log2 of a slice's ticks, or -1 when `slice_ticks` is not a power of two up
// to kMaxSliceTicks (0 counts as 1).
int SliceShiftOf(uint8_t slice_ticks) {
  if (slice_ticks == 0) return 0;
  for (int shift = 0; (1 << shift) <= kMaxSliceTicks; ++shift) {
    if (slice_ticks == (1 << shift)) return shift;
  }
  return -1;
}

}  // namespace

bool ToTickLimits(const MotionLimits& limits, TickLimits* out) {
  const int slice_shift = SliceShiftOf(limits.slice_ticks);
  if (limits.tick_hz == 0 || limits.max_rate == 0 || limits.max_rate > limits.tick_hz ||
      limits.travel_rate == 0 || limits.travel_rate > limits.tick_hz || slice_shift < 0) {
    return false;
  }
  out->slice_shift = static_cast<uint8_t>(slice_shift);
  const uint64_t hz = limits.tick_hz;
  // Rounded down, so the loop never exceeds the configured figures.
  const uint64_t max_speed = (static_cast<uint64_t>(limits.max_rate) << kLengthFracBits) / hz;
  const uint64_t travel_speed = (static_cast<uint64_t>(limits.travel_rate) << kLengthFracBits) / hz;
  const uint64_t accel = (static_cast<uint64_t>(limits.accel) << kLengthFracBits) / (hz * hz);
  if (accel == 0 || accel > max_speed || accel > travel_speed) return false;
  out->max_speed = static_cast<uint32_t>(max_speed);
  out->travel_speed = static_cast<uint32_t>(travel_speed);
  out->accel = static_cast<uint32_t>(accel);
  out->pen_delay_ticks =
      static_cast<uint32_t>(static_cast<uint64_t>(limits.pen_delay_ms) * hz / 1000);
  // The smallest axis limit per tick, capped at one step per tick² (a lower
  // limit is conservative), so that the products in TurnCaps fit in 64 bits.
  uint64_t smallest = 0;
  for (const uint32_t axis_accel : limits.axis_accel) {
    if (axis_accel == 0) continue;
    if (!AxisLimitServable(axis_accel, limits.accel, limits.tick_hz)) return false;
    uint64_t per_tick = (static_cast<uint64_t>(axis_accel) << kLengthFracBits) / (hz * hz);
    if (per_tick > (uint64_t{1} << kLengthFracBits)) per_tick = uint64_t{1} << kLengthFracBits;
    if (smallest == 0 || per_tick < smallest) smallest = per_tick;
  }
  out->turn_budget =
      smallest == 0 ? 0 : static_cast<uint32_t>(FloorSqrt(smallest * smallest - accel * accel));
#if !FDSURF_DEVICE_TURN_CAPS
  // No caps to slow the turns: every speed stays where no chord could bind,
  // which keeps each axis within its limit on any path (docs/motion.md, "A
  // device without turn caps"); refused where that leaves no room to
  // accelerate.
  const uint32_t no_chord_binds = TurnCaps::TopSpeedNoChordBinds(out->turn_budget);
  if (out->max_speed > no_chord_binds) out->max_speed = no_chord_binds;
  if (out->travel_speed > no_chord_binds) out->travel_speed = no_chord_binds;
  if (out->accel > no_chord_binds) return false;
#endif
  const uint32_t top = out->max_speed > out->travel_speed ? out->max_speed : out->travel_speed;
  TurnCaps::SkipThresholds(out->turn_budget, top, out->turn_skip);
  return true;
}

bool AxisLimitServable(uint32_t axis_accel, uint32_t accel, uint32_t tick_hz) {
  if (tick_hz == 0) return false;
  const uint64_t hz = tick_hz;
  const uint64_t axis_per_tick = (static_cast<uint64_t>(axis_accel) << kLengthFracBits) / (hz * hz);
  const uint64_t path_per_tick = (static_cast<uint64_t>(accel) << kLengthFracBits) / (hz * hz);
  return axis_per_tick > path_per_tick;
}

MotionLoop::MotionLoop(uint8_t* storage, uint16_t capacity)
    : storage_(storage), capacity_(capacity), mask_(static_cast<uint16_t>(capacity - 1)) {}

void MotionLoop::Configure(const TickLimits& limits) {
  limits_ = limits;
  const uint32_t top =
      limits.max_speed > limits.travel_speed ? limits.max_speed : limits.travel_speed;
  caps_.Configure(limits.turn_budget, limits.accel, top, limits.turn_skip);
  head_start_ = 0;
  const uint64_t ticks = uint64_t{1} << limits.slice_shift;
  ramp_distance_ = static_cast<uint32_t>(limits.accel * (ticks * (ticks - 1) / 2));
}

MotionLoop::PreparedEntry MotionLoop::Prepare(uint8_t entry) {
  const EntryKind kind = KindOf(entry);
  if (kind == EntryKind::kMove)
    return PreparedEntry{entry, caps_.Measure(entry, LengthOfMove(entry))};
  // The loop rests at a pen event: no chord spans it.
  if (kind == EntryKind::kPenUp || kind == EntryKind::kPenDown) {
    return PreparedEntry{entry, caps_.MeasureAll(false)};
  }
  return PreparedEntry{entry, TurnCaps::Final{0, 0, false, false}};
}

bool MotionLoop::Push(const PreparedEntry& prepared) {
  if (Full()) return false;
  const uint8_t entry = prepared.entry;
  storage_[(head_ + count_) & mask_] = entry;
  ++count_;
  const EntryKind kind = KindOf(entry);
  if (kind == EntryKind::kPenUp || kind == EntryKind::kPenDown) {
    runs_[(first_run_ + stops_) % kMaxPenEvents] = 0;
    ++stops_;
  } else if (kind == EntryKind::kMove) {
    uint64_t& run = stops_ == 0 ? distance_ : runs_[(first_run_ + stops_ - 1) % kMaxPenEvents];
    AddLength(&run, LengthOfMove(entry));
  }
  caps_.Commit(prepared.final);
  return true;
}

void MotionLoop::Pop() {
  if (KindOf(At(0)) == EntryKind::kMove) AddLength(&head_start_, LengthOfMove(At(0)));
  head_ = static_cast<uint16_t>((head_ + 1) & mask_);
  --count_;
}

void MotionLoop::Clear() {
  head_ = 0;
  count_ = 0;
  stops_ = 0;
  first_run_ = 0;
  distance_ = 0;
  phase_ = 0;
  speed_ = 0;
  braking_ = 0;
  pen_wait_ = 0;
  slice_left_ = 0;
  ramp_ = 0;
  creep_ = 0;
  stopping_ = false;
  pausing_ = false;
  head_start_ = 0;
  caps_.Clear();
}

void MotionLoop::set_position(const int32_t (&position)[3]) {
  for (int a = 0; a < 3; ++a) position_[a] = position[a];
}

// The slice's start and choice are called from Tick() alone, once each: in
// one frame with it, an AVR's step interrupt takes 35 bytes less stack (the
// Uno keeps 160 B clear of its static RAM).
#if defined(__GNUC__)
#define FDSURF_IN_TICK inline __attribute__((always_inline))
#else
#define FDSURF_IN_TICK inline
#endif

// Whether a slice of 2^shift ticks may accelerate: v + S·a ≤ v_max,
// B + 2·S·v + a·S² ≤ D and B(v + S·a) = B + S·v + a·S(S − 1)/2 ≤ B_c.
FDSURF_IN_TICK bool MotionLoop::Accelerates(uint8_t shift, uint64_t available,
                                            uint64_t caps_braking) const {
  const uint32_t a = limits_.accel;
  const uint32_t limit = pen_down_ ? limits_.max_speed : limits_.travel_speed;
  if (speed_ + (a << shift) > limit) return false;
  // S·v + a·S(S − 1)/2 and S·v + S·a + a·S(S − 1)/2 in 32 bits (below
  // 2^29 + 2^28 + 2^31): B(v + S·a) = B + the first, and
  // B + 2·S·v + a·S² = B(v + S·a) + the second.
  const uint32_t ramp = shift == 0 ? 0 : ramp_distance_;
  const uint32_t to_braking = (speed_ << shift) + ramp;
  const uint64_t then_braking = braking_ + to_braking;
  return then_braking <= caps_braking && then_braking + (to_braking + (a << shift)) <= available;
}

// Whether a slice of 2^shift ticks has room to cruise: B + S·v ≤ D and
// B ≤ B_c (the speed aside).
FDSURF_IN_TICK bool MotionLoop::HasRoom(uint8_t shift, uint64_t available,
                                        uint64_t caps_braking) const {
  return braking_ <= caps_braking && braking_ + (speed_ << shift) <= available;
}

// Takes a slice of 2^shift ticks of acceleration: B(v + S·a) =
// B + S·v + a·S(S − 1)/2 from the slice's end on.
FDSURF_IN_TICK uint8_t MotionLoop::Accelerate(uint8_t shift) {
  ramp_ = 1;
  braking_ += (speed_ << shift) + (shift == 0 ? 0 : ramp_distance_);
  return shift;
}

FDSURF_IN_TICK uint8_t MotionLoop::ChooseSlice(bool braking) {
  // Where the loop must be able to stop: the next pen event or the end of
  // the buffer, or the end of the moves whose turn caps are final; and what
  // the caps allow (docs/motion.md, "Each axis on curves").
  const uint64_t position = head_start_ + phase_;
  const TurnCaps::Bounds caps = caps_.At(position);
  const uint64_t caps_left = caps.limit > position ? caps.limit - position : 0;
  const uint64_t stop_left = distance_ - phase_;
  const uint64_t available = caps_left < stop_left ? caps_left : stop_left;
  const uint32_t a = limits_.accel;
  const uint32_t v = speed_;
  // Pen down: drawing speed; pen up: travel speed. pen_down_ changes only
  // where a pen event is passed, at rest, so the profile starts from v = 0
  // under the new limit and every bound in docs/motion.md holds per run.
  const uint32_t limit = pen_down_ ? limits_.max_speed : limits_.travel_speed;
  creep_ = 0;
  // A slice of S ticks takes the speeds v + a, …, v + S·a (accelerating) or
  // v each (cruising); either is taken only if its last tick keeps the rule
  // v' + B(v') ≤ D, D the distance left before that tick: then every tick
  // of the slice keeps it (docs/motion.md, "Slices"). Accelerating, that is
  // B + 2·S·v + a·S² ≤ D (what the first S − 1 ticks cover plus the last
  // speed and its braking distance B + S·v + a·S(S − 1)/2); cruising,
  // B + S·v ≤ D. S·v and S·a fit in 32 bits (v ≤ 2^24, S ≤ 16), which
  // keeps an AVR's stack small.
  //
  // The tries, in order: a slice of acceleration; one tick of acceleration,
  // only when the slice failed because it would pass the speed limit; a
  // slice of cruising; then one tick of acceleration or of cruising (the
  // per-tick rule's order). A slice of cruising comes before a tick of
  // acceleration where the slice of acceleration fails on the distance or
  // the caps (else a profile that follows a stop point moving ahead, the end
  // of the final caps, chose on every tick); a tick of acceleration comes
  // first where it fails only on the limit (else the speed stayed up to S·a
  // below it: an Uno at 2 kHz cruised at 4·a of its 7.6·a).
  //
  // Each try needs room for the slice's cruise, B + S·v ≤ D and B ≤ B_c
  // (its acceleration needs more), so that is tested first: a choice that
  // brakes costs two tests, not five (a micro:bit's tick is 800 cycles).
  const uint8_t slice = limits_.slice_shift;
  const bool cruise_speed = v >= a && v <= limit;
  if (!braking && HasRoom(slice, available, caps.braking)) {
    if (Accelerates(slice, available, caps.braking)) return Accelerate(slice);
    if (v + (a << slice) > limit && Accelerates(0, available, caps.braking)) return Accelerate(0);
    if (cruise_speed) {
      ramp_ = 0;
      return slice;
    }
  }
  if (!braking && slice != 0 && HasRoom(0, available, caps.braking)) {
    if (Accelerates(0, available, caps.braking)) return Accelerate(0);
    if (cruise_speed) {
      ramp_ = 0;
      return 0;
    }
  }
  if (v > a) {
    // Braking by a a tick, for a whole slice while the speed allows it:
    // B(v − S·a) = B(v) − (S·v − S·a − a·S(S − 1)/2).
    ramp_ = -1;
    const uint8_t shift = v >= (a << limits_.slice_shift) ? limits_.slice_shift : 0;
    const uint32_t ramp = shift == 0 ? 0 : ramp_distance_;
    braking_ -= ((v - a) << shift) - ramp;
    return shift;
  }
  // At rest or at a (never braking here: Tick() ends a stop or pause at a),
  // with less than a to go (else a single tick would accelerate or cruise):
  // cover it exactly in one tick, a speed below a.
  ramp_ = 0;
  braking_ = 0;
  speed_ = 0;
  creep_ = static_cast<uint32_t>(available);
  return 0;
}

FDSURF_IN_TICK bool MotionLoop::StartSlice(TickOutput* out) {
  // Held at a pause: nothing is passed, not even a pen event at the head.
  if (pausing_ && speed_ == 0) return false;
  // Entries that are not moves are passed at rest (pen events) or on the
  // fly (command boundaries).
  while (count_ > 0 && KindOf(At(0)) != EntryKind::kMove) {
    const EntryKind kind = KindOf(At(0));
    Pop();
    if (kind == EntryKind::kCommandDone) {
      ++out->commands_done;
      continue;
    }
    PassPenEvent(kind == EntryKind::kPenDown, out);
    return false;
  }
  const bool braking = stopping_ || pausing_;
  if (braking && speed_ <= limits_.accel) {
    // At rest (or one deceleration from it): the stop or pause is complete.
    // A pause forgets the progress into the head move: the motor has not
    // moved for it, and a restart from rest must cover the whole unit move
    // (else its first step comes sooner than the acceleration allows).
    speed_ = 0;
    braking_ = 0;
    if (pausing_) phase_ = 0;
    return false;
  }
  if (count_ == 0) {
    speed_ = 0;
    braking_ = 0;
    return false;
  }
  slice_left_ = static_cast<uint8_t>(1u << ChooseSlice(braking));
  ++slices_;
  return true;
}

TickOutput MotionLoop::Tick() {
  TickOutput out = {0, 0, 0, 0};
  if (pen_wait_ > 0) {
    --pen_wait_;
    return out;
  }
  if (slice_left_ == 0) {
    if (!StartSlice(&out)) return out;
  } else {
    while (count_ > 0 && KindOf(At(0)) == EntryKind::kCommandDone) {
      Pop();
      ++out.commands_done;
    }
    // A slice that accelerates or cruises ends short of the next pen event
    // and of the end of the buffer (ChooseSlice()); one that brakes may
    // reach them at rest before its last tick, and ends there.
    if (count_ == 0 || KindOf(At(0)) != EntryKind::kMove) {
      slice_left_ = 0;
      return out;
    }
  }
  // The tick itself: the speed changes by at most a, then the position
  // advances by it (or by a creep).
  --slice_left_;
  const uint32_t a = limits_.accel;
  if (ramp_ > 0) {
    speed_ += a;
  } else if (ramp_ < 0 && speed_ >= a) {
    speed_ -= a;
  }
  phase_ += speed_ + creep_;
  const uint8_t head = At(0);
  const uint32_t length = LengthOfMove(head);
  if (phase_ >= length) {
    phase_ -= length;
    distance_ -= length;
    Pop();
    ++moves_;
    for (int axis = 0; axis < 3; ++axis) {
      if (((head >> (2 * axis)) & 1) == 0) continue;
      out.step_mask = static_cast<uint8_t>(out.step_mask | (1u << axis));
      if (((head >> (2 * axis)) & 2) != 0) {
        out.negative_mask = static_cast<uint8_t>(out.negative_mask | (1u << axis));
        --position_[axis];
      } else {
        ++position_[axis];
      }
    }
  }
  return out;
}

void MotionLoop::PassPenEvent(bool down, TickOutput* out) {
  // A pen event is only reached with no distance left before it, where the
  // profile guarantees speed ≤ a; stopping from there is one deceleration.
  // The run after this pen event becomes the head run.
  --stops_;
  speed_ = 0;
  braking_ = 0;
  phase_ = 0;
  distance_ = runs_[first_run_];
  first_run_ = static_cast<uint8_t>((first_run_ + 1) % kMaxPenEvents);
  if (down != pen_down_) {
    pen_down_ = down;
    out->pen = down ? 1 : -1;
    pen_wait_ = limits_.pen_delay_ticks;
  }
}

}  // namespace motion
}  // namespace fdsurf
