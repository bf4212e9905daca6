// SPDX-License-Identifier: MIT
#include "fdsurf/motion/motion_loop.h"

namespace fdsurf {
namespace motion {
bool ToTickLimits(const MotionLimits& limits, TickLimits* out) {
  if (limits.tick_hz == 0 || limits.max_rate == 0 || limits.max_rate > limits.tick_hz ||
      limits.travel_rate == 0 || limits.travel_rate > limits.tick_hz) {
    return false;
  }
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
    run += LengthOfMove(entry);
  }
  caps_.Commit(prepared.final);
  return true;
}

void MotionLoop::Pop() {
  if (KindOf(At(0)) == EntryKind::kMove) head_start_ += LengthOfMove(At(0));
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
  stopping_ = false;
  pausing_ = false;
  head_start_ = 0;
  caps_.Clear();
}

void MotionLoop::set_position(const int32_t (&position)[3]) {
  for (int a = 0; a < 3; ++a) position_[a] = position[a];
}

// Longer than the project's 80 lines on purpose: this runs once per step
// tick (40 kHz on the simulator), and the profile's phases (pen wait, next
// entry, accelerate / cruise / brake, the step itself) read as one sequence
// whose order the proof in docs/motion.md follows; split into calls, an MCU
// pays for each on every tick.
TickOutput MotionLoop::Tick() {  // NOLINT(readability-function-size)
  TickOutput out = {0, 0, 0, 0};
  if (pen_wait_ > 0) {
    --pen_wait_;
    return out;
  }
  // Held at a pause: nothing is passed, not even a pen event at the head.
  if (pausing_ && speed_ == 0) return out;
  // Entries that are not moves are passed at rest (pen events) or on the fly
  // (command boundaries).
  while (count_ > 0 && KindOf(At(0)) != EntryKind::kMove) {
    const EntryKind kind = KindOf(At(0));
    Pop();
    if (kind == EntryKind::kCommandDone) {
      ++out.commands_done;
      continue;
    }
    // A pen event is only reached with no distance left before it, where the
    // profile guarantees speed ≤ a; stopping from there is one deceleration.
    // The run after this pen event becomes the head run.
    --stops_;
    speed_ = 0;
    braking_ = 0;
    phase_ = 0;
    distance_ = runs_[first_run_];
    first_run_ = static_cast<uint8_t>((first_run_ + 1) % kMaxPenEvents);
    const bool down = kind == EntryKind::kPenDown;
    if (down != pen_down_) {
      pen_down_ = down;
      out.pen = down ? 1 : -1;
      pen_wait_ = limits_.pen_delay_ticks;
    }
    return out;
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
    return out;
  }
  if (count_ == 0) {
    speed_ = 0;
    braking_ = 0;
    return out;
  }

  // Where the loop must be able to stop: the next pen event or the end of
  // the buffer, or the end of the moves whose turn caps are final; and what
  // the caps allow (docs/motion.md, "Each axis on curves").
  const uint64_t position = head_start_ + phase_;
  const TurnCaps::Bounds caps = caps_.At(position);
  const uint64_t caps_left = caps.limit > position ? caps.limit - position : 0;
  const uint64_t stop_left = distance_ - phase_;
  const uint64_t available = caps_left < stop_left ? caps_left : stop_left;
  const uint32_t a = limits_.accel;
  const uint64_t v = speed_;
  // Pen down: drawing speed; pen up: travel speed. pen_down_ changes only
  // where a pen event is passed, at rest, so the profile starts from v = 0
  // under the new limit and every bound in docs/motion.md holds per run.
  const uint32_t limit = pen_down_ ? limits_.max_speed : limits_.travel_speed;
  uint64_t advance = 0;
  if (!braking && v + a <= limit && (v + a) + braking_ + v <= available &&
      braking_ + v <= caps.braking) {
    braking_ += v;  // B(n+1) = B(n) + n·a
    speed_ += a;
    advance = speed_;
  } else if (!braking && v + braking_ <= available && v <= limit && braking_ <= caps.braking) {
    advance = v;
  } else if (v >= a) {
    speed_ -= a;
    braking_ -= speed_;  // B(n−1) = B(n) − (n−1)·a
    advance = speed_;
  }
  if (speed_ == 0 && !braking) {
    // At rest with less than one acceleration step to go: cover it exactly.
    advance = available < a ? available : 0;
  }
  phase_ += static_cast<uint32_t>(advance);
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

}  // namespace motion
}  // namespace fdsurf
