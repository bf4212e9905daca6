// SPDX-License-Identifier: MIT
#include "fdsurf/hal/gpiod_outputs.h"

#include <gpiod.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <system_error>
#include <utility>
#include <vector>

#include "fdsurf/hal/monotonic_clock.h"

namespace fdsurf {
namespace hal {
namespace {

constexpr const char* kStepNames[3] = {"STEPX", "STEPY", "STEPZ"};
constexpr const char* kDirNames[3] = {"DIRX", "DIRY", "DIRZ"};
constexpr const char* kLinesSyntax = "STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN";

// The gpiochip* entries of `dev_dir`, in numeric order, for error messages.
std::string ListChips(const std::string& dev_dir) {
  std::vector<std::pair<unsigned long, std::string>> chips;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dev_dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("gpiochip", 0) != 0) continue;
    chips.emplace_back(std::strtoul(name.c_str() + 8, nullptr, 10), name);
  }
  std::sort(chips.begin(), chips.end());
  if (chips.empty()) return "no GPIO chips in " + dev_dir;
  std::string list = "chips present: ";
  for (size_t i = 0; i < chips.size(); ++i) list += (i > 0 ? ", " : "") + chips[i].second;
  return list;
}

std::string ErrnoText(int error) { return std::strerror(error); }

// Joins message parts without a temporary per '+'.
std::string Cat(std::initializer_list<std::string_view> parts) {
  std::string text;
  for (const std::string_view part : parts) text.append(part);
  return text;
}

// Parses one LINES field: [!|+]OFFSET, or "-" where allowed.
bool ParseLine(std::string_view field, bool default_active_low, GpioLine* line) {
  line->active_low = default_active_low;
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

// A decimal of 1..6 digits.
bool ParseNumber(std::string_view text, unsigned* value) {
  if (text.empty() || text.size() > 6) return false;
  *value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
    *value = *value * 10 + static_cast<unsigned>(c - '0');
  }
  return true;
}

// PEN as "pwmN.M": chip N, channel M of the kernel's PWM class.
bool ParsePwmPen(std::string_view field, unsigned* chip, unsigned* channel) {
  if (field.substr(0, 3) != "pwm") return false;
  field.remove_prefix(3);
  const size_t dot = field.find('.');
  return dot != std::string_view::npos && ParseNumber(field.substr(0, dot), chip) &&
         ParseNumber(field.substr(dot + 1), channel);
}

}  // namespace

bool ParseGpioDevice(std::string_view spec, GpiodConfig* config, std::string* error) {
  std::string quoted(1, '\'');  // built up piecewise: GCC 12 warns (-Wrestrict) on "'" + string
  quoted.append(spec).push_back('\'');
  const std::string usage = std::string("expected gpio:CHIP:") + kLinesSyntax +
                            " (e.g. gpio:gpiochip0:17,27,22,23,24,25)";
  if (spec.substr(0, 5) != "gpio:") {
    *error = "gpio device " + quoted + " must start with 'gpio:'; " + usage;
    return false;
  }
  std::string_view rest = spec.substr(5);
  std::string endstops;
  if (const size_t last = rest.rfind(':');
      last != std::string_view::npos && rest.substr(last).find('=') != std::string_view::npos) {
    endstops = std::string(rest.substr(last + 1));  // ENDSTOPS, gpiod_inputs.h
    rest = rest.substr(0, last);
  }
  const size_t colon = rest.rfind(':');
  if (colon == std::string_view::npos || colon == 0) {
    *error = "gpio device " + quoted + " has no " + (colon == 0 ? "CHIP" : "LINES") + "; " + usage;
    return false;
  }
  const std::string_view chip = rest.substr(0, colon);
  std::string_view lines = rest.substr(colon + 1);
  std::vector<std::string_view> fields;
  while (true) {
    const size_t comma = lines.find(',');
    fields.push_back(lines.substr(0, comma));
    if (comma == std::string_view::npos) break;
    lines.remove_prefix(comma + 1);
  }
  if (fields.size() != 6 && fields.size() != 8) {
    *error = "gpio device " + quoted + ": " + std::to_string(fields.size()) +
             " lines given; expected " + kLinesSyntax + " (6 lines for 2 axes, 8 for 3)";
    return false;
  }
  GpiodConfig parsed = *config;
  parsed.chip = std::string(chip);
  parsed.endstops = endstops;
  parsed.axes = fields.size() == 8 ? 3 : 2;
  std::vector<std::pair<unsigned, const char*>> used;
  auto take = [&](std::string_view field, const char* name, bool active_low, GpioLine* line) {
    if (!ParseLine(field, active_low, line)) {
      *error = "gpio device " + quoted + ": " + name + " '" + std::string(field) +
               "' is not a line offset ([!|+]NUMBER" +
               (std::strcmp(name, "EN") == 0 ? ", or - for none)" : ")");
      return false;
    }
    for (const auto& [offset, other] : used) {
      if (offset == line->offset) {
        *error = "gpio device " + quoted + ": line " + std::to_string(offset) + " used twice (" +
                 other + " and " + name + ")";
        return false;
      }
    }
    used.emplace_back(line->offset, name);
    return true;
  };
  for (int a = 0; a < parsed.axes; ++a) {
    if (!take(fields[2 * a], kStepNames[a], false, &parsed.step[a]) ||
        !take(fields[2 * a + 1], kDirNames[a], false, &parsed.dir[a])) {
      return false;
    }
  }
  const std::string_view enable = fields[fields.size() - 2];
  parsed.has_enable = enable != "-";
  if (parsed.has_enable && !take(enable, "EN", true, &parsed.enable)) return false;
  const std::string_view pen = fields.back();
  if (pen.substr(0, 3) == "pwm") {
    parsed.has_pen_line = false;
    if (!ParsePwmPen(pen, &parsed.pen_pwm_chip, &parsed.pen_pwm_channel)) {
      *error = "gpio device " + quoted + ": PEN '" + std::string(pen) +
               "' is not a PWM channel (pwmCHIP.CHANNEL, e.g. pwm0.1)";
      return false;
    }
  } else if (!take(pen, "PEN", false, &parsed.pen)) {
    return false;
  }
  *config = std::move(parsed);
  return true;
}

GpiodOutputs::GpiodOutputs(const GpiodConfig& config, gpiod_chip* chip)
    : StepDirOutputs(config.axes), config_(config), chip_(chip) {
  for (int a = 0; a < config.axes; ++a) {
    line_config_[line_count_] = config.step[a];
    line_names_[line_count_++] = kStepNames[a];
    line_config_[line_count_] = config.dir[a];
    line_names_[line_count_++] = kDirNames[a];
  }
  if (config.has_enable) {
    enable_index_ = line_count_;
    line_config_[line_count_] = config.enable;
    line_names_[line_count_++] = "EN";
  }
  if (config.has_pen_line) {
    pen_index_ = line_count_;
    line_config_[line_count_] = config.pen;
    line_names_[line_count_++] = "PEN";
  }
}

namespace {

// Opens the chip named in `config`, or says why not (missing, permission,
// not a GPIO chip, other).
IoStatus OpenChip(const GpiodConfig& config, gpiod_chip** chip, std::string* error) {
  errno = 0;
  *chip = gpiod_chip_open_lookup(config.chip.c_str());
  if (*chip != nullptr) return IoStatus::kOk;
  const int e = errno;
  if (e == ENOENT) {
    *error = "gpio: no GPIO chip '" + config.chip + "' (" + ListChips(config.dev_dir) + ")";
    return IoStatus::kNotFound;
  }
  if (e == EACCES || e == EPERM) {
    *error = "gpio: permission denied opening GPIO chip '" + config.chip +
             "' (add your user to the group owning /dev/gpiochip*, e.g. gpio, or add a udev "
             "rule; see hal/README.md)";
    return IoStatus::kPermissionDenied;
  }
  if (e == ENOTTY || e == EINVAL || e == ENODEV) {
    *error = "gpio: '" + config.chip + "' is not a GPIO chip (" + ErrnoText(e) + ")";
    return IoStatus::kInvalidArgument;
  }
  *error = "gpio: cannot open GPIO chip '" + config.chip + "': " + ErrnoText(e);
  return IoStatus::kIoError;
}

}  // namespace

IoStatus GpiodOutputs::Open(const GpiodConfig& config, std::unique_ptr<GpiodOutputs>* outputs,
                            std::string* error) {
  outputs->reset();
  const std::string where = "gpio " + config.chip + ": ";
  if (config.axes != 2 && config.axes != 3) {
    *error = where + std::to_string(config.axes) + " axes (2 or 3 supported)";
    return IoStatus::kInvalidArgument;
  }
  gpiod_chip* chip = nullptr;
  if (const IoStatus opened = OpenChip(config, &chip, error); opened != IoStatus::kOk) {
    return opened;
  }
  std::unique_ptr<GpiodOutputs> self(new GpiodOutputs(config, chip));
  gpiod_line* step_lines[kMaxAxes] = {};
  int step_initial[kMaxAxes] = {};
  int step_count = 0;
  const unsigned chip_lines = gpiod_chip_num_lines(chip);
  for (int i = 0; i < self->line_count_; ++i) {
    const unsigned offset = self->line_config_[i].offset;
    const std::string line = "line " + std::to_string(offset) + " (" + self->line_names_[i] + ")";
    for (int j = 0; j < i; ++j) {
      if (self->line_config_[j].offset == offset) {
        *error = where + line + " is also " + self->line_names_[j];
        return IoStatus::kInvalidArgument;
      }
    }
    if (offset >= chip_lines) {
      *error = where + line + " does not exist: the chip has " + std::to_string(chip_lines) +
               " lines (0-" + std::to_string(chip_lines - 1) + ")";
      return IoStatus::kNotFound;
    }
    errno = 0;
    gpiod_line* handle = gpiod_chip_get_line(chip, offset);
    if (handle == nullptr) {
      *error = Cat({where, "cannot get ", line, ": ", ErrnoText(errno)});
      return IoStatus::kIoError;
    }
    auto busy = [&]() {
      const char* consumer = gpiod_line_consumer(handle);
      *error = where + line + " is busy: " +
               (consumer != nullptr && consumer[0] != '\0'
                    ? std::string("used by '") + consumer + "'"
                    : std::string("used by another program or driver"));
      return IoStatus::kBusy;
    };
    if (gpiod_line_is_used(handle)) return busy();
    // Inactive at first: no pulse, positive, motors off, pen up.
    const int initial = self->line_config_[i].active_low ? 1 : 0;
    if (self->IsStepLine(i)) {
      // Requested below, all together: one request can set them in one call.
      step_lines[step_count] = handle;
      step_initial[step_count++] = initial;
      continue;
    }
    errno = 0;
    if (gpiod_line_request_output(handle, config.consumer.c_str(), initial) != 0) {
      const int e = errno;
      if (e == EBUSY) return busy();
      if (e == EACCES || e == EPERM) {
        *error = Cat({where, "permission denied requesting ", line});
        return IoStatus::kPermissionDenied;
      }
      *error = Cat({where, "cannot request ", line, " as an output: ", ErrnoText(e)});
      return IoStatus::kIoError;
    }
    self->lines_[i] = handle;
  }
  if (const IoStatus status = self->RequestStepLines(step_lines, step_initial, step_count, error);
      status != IoStatus::kOk) {
    return status;
  }
  self->dir_changed_us_ = MonotonicClock::Now();
  *outputs = std::move(self);
  return IoStatus::kOk;
}

// The STEP lines of every axis as one request (one file descriptor), which
// gpiod_line_set_value_bulk needs: the edges of a diagonal step then leave in
// one ioctl instead of one per axis (under load those were up to 0.6 ms
// apart, tests/kernel/arm64).
IoStatus GpiodOutputs::RequestStepLines(gpiod_line* const* handles, const int* initial, int count,
                                        std::string* error) {
  gpiod_line_bulk bulk;
  gpiod_line_bulk_init(&bulk);
  for (int a = 0; a < count; ++a) gpiod_line_bulk_add(&bulk, handles[a]);
  errno = 0;
  if (gpiod_line_request_bulk_output(&bulk, config_.consumer.c_str(), initial) != 0) {
    const int e = errno;
    const std::string where = "gpio " + config_.chip + ": ";
    const std::string lines = "step lines " + StepLineList();
    if (e == EBUSY) {
      *error = Cat({where, lines, " are busy: used by another program or driver"});
      return IoStatus::kBusy;
    }
    if (e == EACCES || e == EPERM) {
      *error = Cat({where, "permission denied requesting ", lines});
      return IoStatus::kPermissionDenied;
    }
    *error = Cat({where, "cannot request ", lines, " as outputs: ", ErrnoText(e)});
    return IoStatus::kIoError;
  }
  for (int a = 0; a < count; ++a) lines_[2 * a] = handles[a];
  return IoStatus::kOk;
}

// "17 (STEPX), 22 (STEPY)": the STEP lines, for messages.
std::string GpiodOutputs::StepLineList() const {
  std::string list;
  for (int a = 0; a < axes(); ++a) {
    if (a > 0) list += ", ";
    list += std::to_string(line_config_[2 * a].offset) + " (" + kStepNames[a] + ")";
  }
  return list;
}

// Drives every STEP line at once: active where `active_mask` has the axis.
IoStatus GpiodOutputs::SetSteps(uint8_t active_mask) {
  gpiod_line_bulk bulk;
  gpiod_line_bulk_init(&bulk);
  int values[kMaxAxes] = {};
  for (int a = 0; a < axes(); ++a) {
    gpiod_line_bulk_add(&bulk, lines_[2 * a]);
    values[a] = ((active_mask >> a & 1) != 0) != line_config_[2 * a].active_low ? 1 : 0;
  }
  errno = 0;
  if (gpiod_line_set_value_bulk(&bulk, values) != 0) {
    std::string wanted;
    for (int a = 0; a < axes(); ++a) {
      wanted += (a > 0 ? ", " : "") + std::string(kStepNames[a]) + "=" + std::to_string(values[a]);
    }
    last_error_ = Cat({"gpio ", config_.chip, ": cannot set step lines ", StepLineList(), " to ",
                       wanted, ": ", ErrnoText(errno)});
    return IoStatus::kIoError;
  }
  return IoStatus::kOk;
}

GpiodOutputs::~GpiodOutputs() {
  const bool all_requested = lines_[line_count_ - 1] != nullptr;
  if (all_requested) {
    // Leave the machine safe: pen up, motors off (errors cannot be reported).
    if (pen_index_ >= 0) (void)Set(pen_index_, false);
    if (enable_index_ >= 0) (void)Set(enable_index_, false);
  }
  for (gpiod_line* line : lines_) {
    if (line != nullptr) gpiod_line_release(line);
  }
  gpiod_chip_close(chip_);
}

IoStatus GpiodOutputs::Set(int index, bool active) {
  const int value = active != line_config_[index].active_low ? 1 : 0;
  errno = 0;
  if (gpiod_line_set_value(lines_[index], value) != 0) {
    last_error_ = "gpio " + config_.chip + ": cannot set line " +
                  std::to_string(line_config_[index].offset) + " (" + line_names_[index] + ") to " +
                  std::to_string(value) + ": " + ErrnoText(errno);
    return IoStatus::kIoError;
  }
  return IoStatus::kOk;
}

IoStatus GpiodOutputs::CheckMask(uint8_t mask, const char* what) {
  if ((mask & ~axis_bits()) == 0) return IoStatus::kOk;
  last_error_ = "gpio " + config_.chip + ": " + what + " mask " + std::to_string(mask) +
                " has bits beyond " + std::to_string(axes()) + " axes";
  return IoStatus::kInvalidArgument;
}

IoStatus GpiodOutputs::DoSetEnabled(bool enabled) {
  if (enable_index_ < 0) return IoStatus::kOk;
  return Set(enable_index_, enabled);
}

IoStatus GpiodOutputs::DoSetDirections(uint8_t negative_mask) {
  if (const IoStatus status = CheckMask(negative_mask, "direction"); status != IoStatus::kOk) {
    return status;
  }
  for (int a = 0; a < axes(); ++a) {
    const bool negative = (negative_mask >> a & 1) != 0;
    if (negative == ((negative_mask_ >> a & 1) != 0)) continue;
    if (const IoStatus status = Set(2 * a + 1, negative); status != IoStatus::kOk) return status;
    negative_mask_ = static_cast<uint8_t>(negative_mask_ ^ (1u << a));
    dir_changed_us_ = MonotonicClock::Now();
  }
  return IoStatus::kOk;
}

IoStatus GpiodOutputs::DoStep(uint8_t axis_mask) {
  if (const IoStatus status = CheckMask(axis_mask, "step"); status != IoStatus::kOk) return status;
  if (axis_mask == 0) return IoStatus::kOk;
  // DIR set-up time, and a low time as long as the high time since the last pulse.
  MonotonicClock::BusyWaitUntil(
      std::max(dir_changed_us_ + config_.dir_setup_us, step_low_us_ + config_.min_pulse_us));
  IoStatus result = SetSteps(axis_mask);
  const uint64_t high_us = MonotonicClock::Now();
  MonotonicClock::BusyWaitUntil(high_us + config_.min_pulse_us);
  // Bring every STEP line low, even after a failure, keeping the first error.
  const bool failed_high = result != IoStatus::kOk;
  const std::string first_error = failed_high ? last_error_ : std::string();
  const IoStatus low = SetSteps(0);
  if (result == IoStatus::kOk) result = low;
  step_low_us_ = MonotonicClock::Now();
  if (failed_high) last_error_ = first_error;
  return result;
}

IoStatus GpiodOutputs::DoSetPen(bool down) {
  if (pen_index_ < 0) return IoStatus::kOk;  // a PWM servo pen, driven by the caller
  return Set(pen_index_, down);
}

}  // namespace hal
}  // namespace fdsurf
