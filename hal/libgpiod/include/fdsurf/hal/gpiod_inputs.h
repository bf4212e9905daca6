// SPDX-License-Identifier: MIT
// Endstop switches read by the host itself through the Linux GPIO character
// device, with Debian 12's libgpiod 1.6 (the v1 C API): EndstopInputs
// (hal/inputs.h) on input lines of one chip.
//
// The switches are the optional fourth part of the gpio device string,
// `gpio:CHIP:LINES:ENDSTOPS` (gpiod_outputs.h has CHIP and LINES):
//
//   ENDSTOPS  comma-separated AXISEND=[!|+]OFFSET, AXISEND one of xmin, xmax,
//             ymin, ymax, zmin, zmax; each at most once, any order.
//
// As in LINES, `!` makes a line active-low (a switch that pulls the line to
// ground when triggered, the usual wiring with a pull-up), `+` active-high
// (the default). "Active" means: the switch is triggered.
//
//   gpio:gpiochip0:17,27,22,23,24,25:xmin=!5,ymin=!6      X and Y min switches to ground
//   gpio:gpiochip0:17,27,22,23,5,6,24,25:xmin=12,ymin=13,zmax=!16
#pragma once

#include <stdint.h>

#include <memory>
#include <string>
#include <string_view>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/gpiod_outputs.h"
#include "fdsurf/hal/inputs.h"
#include "fdsurf/hal/io_status.h"

struct gpiod_chip;
struct gpiod_line;

namespace fdsurf {
namespace hal {

/// The endstop lines of one chip: min[a] / max[a] for axis a (X 0, Y 1, Z 2)
/// when has_min[a] / has_max[a].
struct GpioEndstopConfig {
  std::string chip = "gpiochip0";
  std::string consumer = "fdsurf";
  bool has_min[3] = {false, false, false};
  bool has_max[3] = {false, false, false};
  GpioLine min[3];
  GpioLine max[3];
};

/// Parses ENDSTOPS (the part after LINES' colon, see above) into `config`'s
/// lines, keeping its chip and consumer. `taken` is the LINES' configuration
/// whose offsets an endstop may not reuse. Returns false with a one-line
/// reason in `*error` naming the field, e.g. "endstop 'xmin=5x' is not
/// AXISEND=[!|+]OFFSET (like xmin=!5)".
bool ParseGpioEndstops(std::string_view endstops, const GpiodConfig& taken,
                       GpioEndstopConfig* config, std::string* error);

/// The endstop switches on input lines of one GPIO chip.
///
/// Open() requests every configured line as an input for the consumer; the
/// destructor releases them. Read() reads each line (one ioctl per line)
/// with its polarity applied.
class GpiodEndstops final : public EndstopInputs {
 public:
  /// Opens the chip and requests the lines.
  ///
  /// Errors (with the detail, naming the chip and line, in `*error`;
  /// `*inputs` is left empty):
  ///   kInvalidArgument   no endstop configured.
  ///   kNotFound          no such chip, or a line offset beyond its lines.
  ///   kBusy              a line is held by another consumer (named).
  ///   kPermissionDenied  the chip cannot be opened or a line requested.
  ///   kIoError           anything else libgpiod reports (errno text).
  static IoStatus Open(const GpioEndstopConfig& config, std::unique_ptr<GpiodEndstops>* inputs,
                       std::string* error);

  ~GpiodEndstops();
  GpiodEndstops(const GpiodEndstops&) = delete;
  GpiodEndstops& operator=(const GpiodEndstops&) = delete;

 private:
  static constexpr int kMaxLines = 6;  // min and max of 3 axes

  explicit GpiodEndstops(gpiod_chip* chip) : chip_(chip) {}

  FDSURF_NODISCARD EndstopState DoFitted() const override { return fitted_; }
  IoStatus DoRead(EndstopState* state) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  gpiod_chip* chip_;
  std::string chip_name_;
  gpiod_line* lines_[kMaxLines] = {};
  GpioLine line_config_[kMaxLines] = {};
  uint8_t bits_[kMaxLines] = {};  // the axis bit of each line
  bool is_max_[kMaxLines] = {};   // whether it is a max switch
  const char* names_[kMaxLines] = {};
  int line_count_ = 0;
  EndstopState fitted_{0, 0};
  std::string last_error_;
};

}  // namespace hal
}  // namespace fdsurf
