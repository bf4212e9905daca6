// SPDX-License-Identifier: MIT
#include "fdsurf/hal/gpiod_inputs.h"

#include <gpiod.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace fdsurf {
namespace hal {
namespace {

constexpr const char* kEndNames[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};

// "[!|+]OFFSET" into `line` (default active-high).
bool ParseOffset(std::string_view field, GpioLine* line) {
  line->active_low = false;
  if (!field.empty() && (field[0] == '!' || field[0] == '+')) {
    line->active_low = field[0] == '!';
    field.remove_prefix(1);
  }
  if (field.empty() || field.size() > 6) return false;
  unsigned value = 0;
  for (const char c : field) {
    if (c < '0' || c > '9') return false;
    value = value * 10 + static_cast<unsigned>(c - '0');
  }
  line->offset = value;
  return true;
}

// Whether `offset` is one of LINES' requested outputs.
bool IsOutputLine(const GpiodConfig& c, unsigned offset) {
  for (int a = 0; a < c.axes; ++a) {
    if (c.step[a].offset == offset || c.dir[a].offset == offset) return true;
  }
  return (c.has_enable && c.enable.offset == offset) || (c.has_pen_line && c.pen.offset == offset);
}

std::string Quoted(std::string_view text) {
  std::string quoted(1, '\'');
  quoted.append(text).push_back('\'');
  return quoted;
}

}  // namespace

bool ParseGpioEndstops(std::string_view endstops, const GpiodConfig& taken,
                       GpioEndstopConfig* config, std::string* error) {
  GpioEndstopConfig parsed = *config;
  bool seen[6] = {};
  while (true) {
    const size_t comma = endstops.find(',');
    const std::string_view field = endstops.substr(0, comma);
    const size_t equals = field.find('=');
    int end = -1;
    for (int i = 0; i < 6 && equals != std::string_view::npos; ++i) {
      if (field.substr(0, equals) == kEndNames[i]) end = i;
    }
    GpioLine line;
    if (end < 0 || !ParseOffset(field.substr(equals + 1), &line)) {
      *error = "endstop " + Quoted(field) +
               " is not AXISEND=[!|+]OFFSET with AXISEND xmin, xmax, ymin, ymax, zmin or zmax "
               "(like xmin=!5)";
      return false;
    }
    if (seen[end]) {
      *error = std::string("endstop ") + kEndNames[end] + " given twice";
      return false;
    }
    seen[end] = true;
    const int axis = end / 2;
    if (axis >= taken.axes) {
      *error = std::string("endstop ") + kEndNames[end] + ": the machine has " +
               std::to_string(taken.axes) + " axes";
      return false;
    }
    if (IsOutputLine(taken, line.offset)) {
      *error = std::string("endstop ") + kEndNames[end] + ": line " + std::to_string(line.offset) +
               " is also an output in LINES";
      return false;
    }
    for (int a = 0; a < 3; ++a) {
      if ((parsed.has_min[a] && parsed.min[a].offset == line.offset) ||
          (parsed.has_max[a] && parsed.max[a].offset == line.offset)) {
        *error = std::string("endstop ") + kEndNames[end] + ": line " +
                 std::to_string(line.offset) + " used twice";
        return false;
      }
    }
    (end % 2 == 0 ? parsed.has_min : parsed.has_max)[axis] = true;
    (end % 2 == 0 ? parsed.min : parsed.max)[axis] = line;
    if (comma == std::string_view::npos) break;
    endstops.remove_prefix(comma + 1);
  }
  *config = parsed;
  return true;
}

IoStatus GpiodEndstops::Open(const GpioEndstopConfig& config,
                             std::unique_ptr<GpiodEndstops>* inputs, std::string* error) {
  inputs->reset();
  const std::string where = "gpio " + config.chip;
  errno = 0;
  gpiod_chip* chip = gpiod_chip_open_lookup(config.chip.c_str());
  if (chip == nullptr) {
    const int e = errno;
    *error =
        "gpio: cannot open GPIO chip '" + config.chip + "' for the endstops: " + std::strerror(e);
    if (e == ENOENT || e == ENODEV) return IoStatus::kNotFound;
    if (e == EACCES || e == EPERM) return IoStatus::kPermissionDenied;
    return IoStatus::kIoError;
  }
  std::unique_ptr<GpiodEndstops> opened(new GpiodEndstops(chip));
  opened->chip_name_ = config.chip;
  const unsigned lines = gpiod_chip_num_lines(chip);
  for (int end = 0; end < 6; ++end) {
    const int axis = end / 2;
    const bool is_max = end % 2 == 1;
    if (!(is_max ? config.has_max : config.has_min)[axis]) continue;
    const GpioLine& wanted = (is_max ? config.max : config.min)[axis];
    const std::string name =
        where + ": line " + std::to_string(wanted.offset) + " (endstop " + kEndNames[end] + ")";
    if (wanted.offset >= lines) {
      *error = name + " is beyond the chip's " + std::to_string(lines) + " lines";
      return IoStatus::kNotFound;
    }
    gpiod_line* line = gpiod_chip_get_line(chip, wanted.offset);
    if (line == nullptr) {
      *error = name + ": " + std::strerror(errno);
      return IoStatus::kIoError;
    }
    if (gpiod_line_is_used(line)) {
      const char* consumer = gpiod_line_consumer(line);
      *error = name + " is busy: used by " + Quoted(consumer != nullptr ? consumer : "the kernel");
      return IoStatus::kBusy;
    }
    errno = 0;
    if (gpiod_line_request_input(line, config.consumer.c_str()) != 0) {
      const int e = errno;
      *error = name + ": cannot be requested as an input: " + std::strerror(e);
      return e == EACCES || e == EPERM ? IoStatus::kPermissionDenied
             : e == EBUSY              ? IoStatus::kBusy
                                       : IoStatus::kIoError;
    }
    const int i = opened->line_count_++;
    opened->lines_[i] = line;
    opened->line_config_[i] = wanted;
    opened->bits_[i] = static_cast<uint8_t>(1u << axis);
    opened->is_max_[i] = is_max;
    opened->names_[i] = kEndNames[end];
    uint8_t& mask = is_max ? opened->fitted_.max_mask : opened->fitted_.min_mask;
    mask = static_cast<uint8_t>(mask | opened->bits_[i]);
  }
  if (opened->line_count_ == 0) {
    *error = where + ": no endstop lines configured";
    return IoStatus::kInvalidArgument;
  }
  *inputs = std::move(opened);
  return IoStatus::kOk;
}

GpiodEndstops::~GpiodEndstops() {
  for (int i = 0; i < line_count_; ++i) gpiod_line_release(lines_[i]);
  gpiod_chip_close(chip_);
}

IoStatus GpiodEndstops::DoRead(EndstopState* state) {
  EndstopState now{0, 0};
  for (int i = 0; i < line_count_; ++i) {
    errno = 0;
    const int level = gpiod_line_get_value(lines_[i]);
    if (level < 0) {
      last_error_ = "gpio " + chip_name_ + ": line " + std::to_string(line_config_[i].offset) +
                    " (endstop " + names_[i] + ") cannot be read: " + std::strerror(errno);
      *state = EndstopState{0, 0};
      return IoStatus::kIoError;
    }
    const bool triggered = (level != 0) != line_config_[i].active_low;
    if (!triggered) continue;
    uint8_t& mask = is_max_[i] ? now.max_mask : now.min_mask;
    mask = static_cast<uint8_t>(mask | bits_[i]);
  }
  *state = now;
  return IoStatus::kOk;
}

}  // namespace hal
}  // namespace fdsurf
