// SPDX-License-Identifier: MIT
#include "fdsurf/hal/sim_endstops.h"

namespace fdsurf {
namespace hal {

EndstopState SimEndstops::DoFitted() const {
  const uint8_t axis_bits = static_cast<uint8_t>((1u << steps_.axes()) - 1u);
  EndstopState fitted{static_cast<uint8_t>(options_.min_switches & axis_bits), 0};
  for (int axis = 0; axis < steps_.axes(); ++axis) {
    if (options_.travel[axis] > 0)
      fitted.max_mask = static_cast<uint8_t>(fitted.max_mask | 1u << axis);
  }
  return fitted;
}

IoStatus SimEndstops::DoRead(EndstopState* state) {
  ++reads_;
  *state = EndstopState{0, 0};
  if (injected_ != IoStatus::kOk) {
    const IoStatus status = injected_;
    injected_ = IoStatus::kOk;
    last_error_ = std::string("sim endstops: injected ") + IoStatusName(status);
    return status;
  }
  for (int axis = 0; axis < steps_.axes(); ++axis) {
    const uint8_t bit = static_cast<uint8_t>(1u << axis);
    const int64_t real = real_position(axis);
    if ((options_.min_switches & bit) != 0 && (options_.broken_min & bit) == 0 && real <= 0) {
      state->min_mask = static_cast<uint8_t>(state->min_mask | bit);
    }
    if (options_.travel[axis] > 0 && (options_.broken_max & bit) == 0 &&
        real >= options_.travel[axis]) {
      state->max_mask = static_cast<uint8_t>(state->max_mask | bit);
    }
  }
  return IoStatus::kOk;
}

}  // namespace hal
}  // namespace fdsurf
