// SPDX-License-Identifier: MIT
// Simulated endstop switches: they watch a SimStepDir's counted steps and
// trigger where a real carriage would touch them. The firmware's position 0
// at power-on is where the carriage happens to stand, not the switch, so
// each axis has a start offset: the carriage's real distance from the min
// switch at power-on, in steps. Homing therefore really has to search.
#pragma once

#include <stdint.h>

#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/inputs.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/sim.h"

namespace fdsurf {
namespace hal {

/// Where the switches are, per axis (X, Y, Z). Real position = counted steps
/// + start_offset; the min switch is triggered at real position ≤ 0, the max
/// switch at real position ≥ travel (when travel > 0).
struct SimEndstopOptions {
  /// The carriage's real position at power-on, steps from the min switch.
  int64_t start_offset[3] = {0, 0, 0};
  /// The real position of the max switch; 0: no max switch on that axis.
  int64_t travel[3] = {0, 0, 0};
  /// Axes that have a min switch (bit a: axis a).
  uint8_t min_switches = 0x07;
  /// Switches that never trigger, as a broken wire would (min, max masks).
  uint8_t broken_min = 0;
  uint8_t broken_max = 0;
};

class SimEndstops final : public EndstopInputs {
 public:
  /// `steps` must outlive this object; its axes() axes are watched.
  SimEndstops(const SimStepDir& steps, const SimEndstopOptions& options)
      : steps_(steps), options_(options) {}

  /// The carriage's real position on `axis` now (steps from the min switch).
  FDSURF_NODISCARD int64_t real_position(int axis) const {
    return steps_.position(axis) + options_.start_offset[axis];
  }
  /// Makes the next Read() fail with `status`.
  void InjectError(IoStatus status) { injected_ = status; }
  /// Reads so far (the firmware polls once per tick).
  FDSURF_NODISCARD uint64_t reads() const { return reads_; }

 private:
  FDSURF_NODISCARD EndstopState DoFitted() const override;
  IoStatus DoRead(EndstopState* state) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  const SimStepDir& steps_;
  SimEndstopOptions options_;
  IoStatus injected_ = IoStatus::kOk;
  uint64_t reads_ = 0;
  std::string last_error_;
};

}  // namespace hal
}  // namespace fdsurf
