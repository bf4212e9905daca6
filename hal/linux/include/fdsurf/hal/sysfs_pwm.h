// SPDX-License-Identifier: MIT
// One channel of Linux's PWM class (Documentation/driver-api/pwm.rst, "Using
// PWMs with the sysfs interface"): the hardware PWM a Raspberry Pi drives a
// servo with, without the jitter of a software-timed GPIO line.
//
//   ROOT/pwmchipN/export          write M: the kernel creates pwmchipN/pwmM/
//   ROOT/pwmchipN/pwmM/period     the period, nanoseconds
//   ROOT/pwmchipN/pwmM/duty_cycle the active time, nanoseconds (≤ period)
//   ROOT/pwmchipN/pwmM/enable     1 on, 0 off
//
// ROOT is /sys/class/pwm; a test points it at a directory tree that mimics
// it. Every value is written in one write() to a freshly opened file, as
// sysfs attributes want.
#pragma once

#include <stdint.h>

#include <memory>
#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/pwm.h"

namespace fdsurf {
namespace hal {

/// Which channel, and where the PWM class is.
struct SysfsPwmConfig {
  std::string root = "/sys/class/pwm";
  unsigned chip = 0;
  unsigned channel = 0;
  /// How long Open() waits for pwmM/ (and its files' permissions, set by
  /// udev) to appear after the export, milliseconds.
  uint32_t export_wait_ms = 1000;
};

/// A PWM channel through sysfs. Open() exports the channel if pwmM/ is not
/// there yet. The destructor leaves the channel as it is, pulsing and
/// exported: a servo without pulses goes limp and could let a lifted pen
/// drop, so the caller lifts the pen before and SetEnabled(false) is its
/// choice; unexporting resets the pin's mux on some SoCs.
///
/// Errors name the file and what the kernel said, e.g.
///   "pwm: no PWM chip /sys/class/pwm/pwmchip3 (chips present: pwmchip0)"
///   "pwm: cannot write '20000000' to /sys/class/pwm/pwmchip0/pwm0/period:
///    Permission denied"
/// errno maps to IoStatus: ENOENT/ENODEV kNotFound, EACCES/EPERM
/// kPermissionDenied, EBUSY kBusy, EINVAL kInvalidArgument, else kIoError.
class SysfsPwm final : public PwmOutput {
 public:
  /// Errors (detail in `*error`, `*pwm` left empty):
  ///   kNotFound  no ROOT/pwmchipN, or pwmM/ did not appear after the export.
  ///   others     the export could not be written (errno as above).
  static IoStatus Open(const SysfsPwmConfig& config, std::unique_ptr<SysfsPwm>* pwm,
                       std::string* error);

  ~SysfsPwm() = default;
  SysfsPwm(const SysfsPwm&) = delete;
  SysfsPwm& operator=(const SysfsPwm&) = delete;

  /// ROOT/pwmchipN/pwmM.
  FDSURF_NODISCARD const std::string& channel_dir() const { return dir_; }

 private:
  explicit SysfsPwm(std::string dir) : dir_(std::move(dir)) {}

  IoStatus DoSetPeriodMicros(uint32_t period_us) override;
  IoStatus DoSetPulseMicros(uint32_t pulse_us) override;
  IoStatus DoSetEnabled(bool enabled) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  IoStatus Write(const char* attribute, uint64_t value);

  std::string dir_;
  uint32_t period_us_ = 0;
  uint32_t pulse_us_ = 0;
  bool period_known_ = false;
  std::string last_error_;
};

/// Writes `text` to `path` in one write(). kOk, or the errno's IoStatus with
/// "cannot write 'TEXT' to PATH: REASON" in `*error`.
IoStatus WriteSysfsFile(const std::string& path, const std::string& text, std::string* error);

}  // namespace hal
}  // namespace fdsurf
