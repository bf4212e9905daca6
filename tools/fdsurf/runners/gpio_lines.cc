// SPDX-License-Identifier: MIT
#include "gpio_lines.h"

#include <sched.h>

#include <cerrno>
#include <cstring>

#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/host/errors.h"
#include "runner.h"

namespace fdsurf::host {
namespace {

// The ENDSTOPS part of --device (hal/gpiod_inputs.h) checked, before any
// line is opened; no switch when it is left out.
hal::GpioEndstopConfig EndstopsOf(const hal::GpiodConfig& config) {
  hal::GpioEndstopConfig endstops;
  endstops.chip = config.chip;
  endstops.consumer = config.consumer;
  std::string error;
  if (!config.endstops.empty() &&
      !hal::ParseGpioEndstops(config.endstops, config, &endstops, &error)) {
    throw InputError("--device: " + error);
  }
  return endstops;
}

}  // namespace

PwmServoPen::PwmServoPen(const hal::GpiodConfig& config, std::uint16_t up_us,
                         std::uint16_t down_us) {
  if (up_us == 0) {
    throw InputError("--device: the pen is a servo on pwm" + std::to_string(config.pen_pwm_chip) +
                     "." + std::to_string(config.pen_pwm_channel) +
                     ": give its pulse widths (--servo-pulse-up, --servo-pulse-down)");
  }
  hal::SysfsPwmConfig pwm_config;
  pwm_config.chip = config.pen_pwm_chip;
  pwm_config.channel = config.pen_pwm_channel;
  std::string error;
  if (hal::SysfsPwm::Open(pwm_config, &pwm_, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  pen_ = std::make_unique<hal::ServoPen>(*pwm_, up_us, down_us);
  if (pen_->Start() != hal::IoStatus::kOk) throw DeviceError(pen_->LastError());
}

PwmServoPen::~PwmServoPen() {
  if (static_cast<hal::PenOutput&>(*pen_).SetPen(false) != hal::IoStatus::kOk) return;
  hal::MonotonicClock clock;
  clock.SleepUntilMicros(clock.NowMicros() + 2 * hal::kServoPeriodUs);
}

GpioLines::GpioLines(const std::string& device, int axes, std::uint16_t servo_up_us,
                     std::uint16_t servo_down_us) {
  std::string error;
  if (!hal::ParseGpioDevice(device, &config_, &error)) throw InputError("--device: " + error);
  if (axes != 0 && config_.axes != axes) {
    throw InputError("--device: " + std::to_string(config_.axes) +
                     " axes of lines given for --dims " + std::to_string(axes));
  }
  const hal::GpioEndstopConfig endstop_config = EndstopsOf(config_);
  if (hal::GpiodOutputs::Open(config_, &outputs_, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  if (!config_.endstops.empty() &&
      hal::GpiodEndstops::Open(endstop_config, &endstops_, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  if (!config_.has_pen_line) {
    servo_ = std::make_unique<PwmServoPen>(config_, servo_up_us, servo_down_us);
  }
}

std::string GpioLines::OutputError() {
  const std::string lines_error = outputs_->StepDirOutputs::LastError();
  if (!lines_error.empty()) return "gpio: " + lines_error;
  const std::string pen_error = pen().LastError();
  if (pen_error.empty() && endstops_ != nullptr) return endstops_->LastError();
  return "gpio: " + pen_error;
}

GpioLines::SafeState GpioLines::MakeSafe() {
  SafeState state{};
  state.pen_lifted = pen().SetPen(false) == hal::IoStatus::kOk;
  state.drivers_disabled = outputs_->SetEnabled(false) == hal::IoStatus::kOk;
  return state;
}

std::string RunInRealTime() {
  // Above every ordinary process, below the kernel's threaded interrupt
  // handlers (SCHED_FIFO 50), which the pty and the GPIO ioctls may need.
  constexpr int kPriority = 40;
  sched_param param{};
  param.sched_priority = kPriority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) == 0) {
    return "real-time scheduling (SCHED_FIFO " + std::to_string(kPriority) + ")";
  }
  return std::string("no real-time scheduling (") + std::strerror(errno) +
         ": run it as root or give the user an rtprio limit; ticks may come late under load)";
}

}  // namespace fdsurf::host
