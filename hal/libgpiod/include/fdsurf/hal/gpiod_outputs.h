// SPDX-License-Identifier: MIT
// Step/dir/enable and pen lines driven by the host itself through the Linux
// GPIO character device, with Debian 12's libgpiod 1.6 (the v1 C API).
//
// The device string `gpio:CHIP:LINES` (ParseGpioDevice):
//
//   CHIP   gpiochip0 (name), /dev/gpiochip0 (path), 0 (number) or a label
//          such as pinctrl-bcm2711: whatever gpiod_chip_open_lookup accepts.
//   LINES  STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN: 6 line offsets for two
//          axes, 8 for three. EN may be `-` (no enable line).
//
// PEN may instead be `pwmN.M`: the pen is a hobby servo on channel M of the
// kernel's PWM chip N (/sys/class/pwm/pwmchipN/pwmM, hal/linux sysfs_pwm.h),
// driven by the caller (no pen line is requested here).
//
// Each offset may carry a polarity prefix: `!` active-low, `+` active-high.
// Defaults: STEP, DIR and PEN active-high, EN active-low (the ~ENABLE input
// of A4988 and DRV8825 boards). "Active" means: STEP pulsing, DIR moving
// towards negative, EN motors energised, PEN pen down.
//
//   gpio:gpiochip0:17,27,22,23,24,25          X 17/27, Y 22/23, ~EN 24, pen 25
//   gpio:gpiochip0:17,!27,22,23,5,6,+24,25    X dir inverted, Z 5/6, EN active-high
//   gpio:/dev/gpiochip0:17,27,22,23,-,!25     no enable line, pen line active-low
//   gpio:gpiochip0:17,27,22,23,24,pwm0.1      pen servo on pwmchip0's channel 1
#pragma once

#include <stdint.h>

#include <memory>
#include <string>
#include <string_view>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/outputs.h"

struct gpiod_chip;
struct gpiod_line;

namespace fdsurf {
namespace hal {

/// One line of the chip: its offset and whether its active level is low.
struct GpioLine {
  unsigned offset = 0;
  bool active_low = false;
};

/// Everything GpiodOutputs::Open needs. ParseGpioDevice fills chip, axes and
/// the lines; the timing fields keep their defaults unless set by the caller.
struct GpiodConfig {
  /// The chip, as gpiod_chip_open_lookup accepts it (name, path, number, label).
  std::string chip = "gpiochip0";
  /// 2 or 3.
  uint8_t axes = 2;
  GpioLine step[3];
  GpioLine dir[3];
  bool has_enable = false;
  GpioLine enable{0, true};
  GpioLine pen;
  /// false when PEN was `pwmN.M`: the pen is a servo on that PWM channel,
  /// which the caller drives; no pen line is requested and SetPen() here
  /// does nothing.
  bool has_pen_line = true;
  unsigned pen_pwm_chip = 0;
  unsigned pen_pwm_channel = 0;
  /// The ENDSTOPS part of `gpio:CHIP:LINES:ENDSTOPS` as written ("" when
  /// left out), for ParseGpioEndstops (gpiod_inputs.h); no line of it is
  /// requested here.
  std::string endstops;
  /// The shortest STEP pulse, in microseconds, busy-waited on CLOCK_MONOTONIC:
  /// both the high time and the low time before the next pulse. A4988 needs
  /// 1 µs, DRV8825 1.9 µs.
  uint32_t min_pulse_us = 2;
  /// The time from a DIR change to the next STEP edge, in microseconds
  /// (DRV8825: 650 ns; A4988: 200 ns).
  uint32_t dir_setup_us = 1;
  /// The consumer name shown by gpioinfo for the requested lines.
  std::string consumer = "fdsurf";
  /// Where the chips are listed for the "chips present" part of the error
  /// when the chip is missing (tests point it elsewhere).
  std::string dev_dir = "/dev";
};

/// Parses "gpio:CHIP:LINES[:ENDSTOPS]" (see the top of this file; ENDSTOPS,
/// a part holding '=', is kept as text in config->endstops) into `config`, keeping
/// its other fields. Returns false with a one-line reason in `*error`
/// (e.g. "gpio:gpiochip0:17,27,22: 3 lines given; expected ...").
bool ParseGpioDevice(std::string_view spec, GpiodConfig* config, std::string* error);

/// The step/dir/enable lines and the pen line on one GPIO chip.
///
/// Open() requests every line as an output for the consumer, with the motors
/// disabled, every direction positive, STEP inactive and the pen up. The
/// destructor lifts the pen, disables the motors and releases the lines.
/// Errors name the chip and line, e.g.
///   "gpio: no GPIO chip 'gpiochip9' (chips present: gpiochip0, gpiochip1)"
///   "gpio gpiochip0: line 17 (STEPX) is busy: used by 'spi0'"
class GpiodOutputs final : public StepDirOutputs, public PenOutput {
 public:
  /// Opens the chip and requests the lines.
  ///
  /// Errors (with the detail in `*error`; `*outputs` is left empty):
  ///   kInvalidArgument   axes not 2 or 3, a line used twice, or CHIP is not
  ///                      a GPIO chip (e.g. /dev/null).
  ///   kNotFound          no such chip, or a line offset beyond its lines.
  ///   kBusy              a line is held by another consumer (named).
  ///   kPermissionDenied  the chip cannot be opened or a line requested.
  ///   kIoError           anything else libgpiod reports (errno text).
  static IoStatus Open(const GpiodConfig& config, std::unique_ptr<GpiodOutputs>* outputs,
                       std::string* error);

  ~GpiodOutputs();
  GpiodOutputs(const GpiodOutputs&) = delete;
  GpiodOutputs& operator=(const GpiodOutputs&) = delete;

  using StepDirOutputs::LastError;

 private:
  // Index of each line in lines_: step[a] = 2a, dir[a] = 2a + 1, then EN, PEN.
  static constexpr int kMaxLines = 8;

  GpiodOutputs(const GpiodConfig& config, gpiod_chip* chip);

  IoStatus DoSetEnabled(bool enabled) override;
  IoStatus DoSetDirections(uint8_t negative_mask) override;
  IoStatus DoStep(uint8_t axis_mask) override;
  IoStatus DoSetPen(bool down) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  static constexpr int kMaxAxes = 3;

  FDSURF_NODISCARD bool IsStepLine(int index) const { return index < 2 * axes() && index % 2 == 0; }
  IoStatus RequestStepLines(gpiod_line* const* handles, const int* initial, int count,
                            std::string* error);
  FDSURF_NODISCARD std::string StepLineList() const;
  IoStatus SetSteps(uint8_t active_mask);
  IoStatus Set(int index, bool active);
  IoStatus CheckMask(uint8_t mask, const char* what);

  GpiodConfig config_;
  gpiod_chip* chip_;
  gpiod_line* lines_[kMaxLines] = {};
  GpioLine line_config_[kMaxLines] = {};
  const char* line_names_[kMaxLines] = {};
  int line_count_ = 0;
  int enable_index_ = -1;
  int pen_index_ = -1;
  uint8_t negative_mask_ = 0;
  uint64_t dir_changed_us_ = 0;
  uint64_t step_low_us_ = 0;
  std::string last_error_;
};

}  // namespace hal
}  // namespace fdsurf
