// SPDX-License-Identifier: MIT
#include "fdsurf/hal/sysfs_pwm.h"

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

namespace fdsurf {
namespace hal {
namespace {

IoStatus StatusOfErrno(int error_number) {
  switch (error_number) {
    case ENOENT:
    case ENODEV:
      return IoStatus::kNotFound;
    case EACCES:
    case EPERM:
      return IoStatus::kPermissionDenied;
    case EBUSY:
      return IoStatus::kBusy;
    case EINVAL:
      return IoStatus::kInvalidArgument;
    default:
      return IoStatus::kIoError;
  }
}

// "pwmchip0, pwmchip1" under `root`, or "none".
std::string ChipsPresent(const std::string& root) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(root, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("pwmchip", 0) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
  return list.empty() ? "none" : list;
}

// Whether the channel's three attributes can be opened for writing yet.
bool ChannelReady(const std::string& dir) {
  for (const char* attribute : {"period", "duty_cycle", "enable"}) {
    if (access((dir + "/" + attribute).c_str(), W_OK) != 0) return false;
  }
  return true;
}

void SleepMillis(uint32_t ms) {
  const timespec pause{0, static_cast<long>(ms) * 1000000L};
  nanosleep(&pause, nullptr);
}

}  // namespace

IoStatus WriteSysfsFile(const std::string& path, const std::string& text, std::string* error) {
  const int fd = open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  ssize_t written = -1;
  int saved = 0;
  if (fd >= 0) {
    written = write(fd, text.data(), text.size());
    saved = errno;
    if (close(fd) != 0 && written == static_cast<ssize_t>(text.size())) {
      saved = errno;  // sysfs may report the store's failure at close
      written = -1;
    }
  } else {
    saved = errno;
  }
  if (written == static_cast<ssize_t>(text.size())) return IoStatus::kOk;
  if (written >= 0) saved = EIO;  // a short write of a few bytes: not a sysfs store
  *error = "cannot write '" + text + "' to " + path + ": " + std::strerror(saved);
  return StatusOfErrno(saved);
}

IoStatus SysfsPwm::Open(const SysfsPwmConfig& config, std::unique_ptr<SysfsPwm>* pwm,
                        std::string* error) {
  pwm->reset();
  const std::string chip = config.root + "/pwmchip" + std::to_string(config.chip);
  std::error_code ec;
  if (!std::filesystem::is_directory(chip, ec)) {
    *error = "pwm: no PWM chip " + chip + " (chips present: " + ChipsPresent(config.root) + ")";
    return IoStatus::kNotFound;
  }
  const std::string dir = chip + "/pwm" + std::to_string(config.channel);
  if (!std::filesystem::is_directory(dir, ec)) {
    std::string detail;
    const IoStatus status =
        WriteSysfsFile(chip + "/export", std::to_string(config.channel), &detail);
    if (status != IoStatus::kOk) {
      *error = "pwm: " + detail;
      return status;
    }
  }
  // The kernel creates pwmM/ at once, udev then fixes its permissions.
  for (uint32_t waited = 0; !ChannelReady(dir) && waited < config.export_wait_ms; waited += 10) {
    SleepMillis(10);
  }
  if (!ChannelReady(dir)) {
    *error = "pwm: channel " + std::to_string(config.channel) + " of " + chip + ": " + dir +
             "/{period,duty_cycle,enable} are not there or not writable after the export";
    return IoStatus::kNotFound;
  }
  pwm->reset(new SysfsPwm(dir));
  return IoStatus::kOk;
}

IoStatus SysfsPwm::Write(const char* attribute, uint64_t value) {
  std::string detail;
  const IoStatus status = WriteSysfsFile(dir_ + "/" + attribute, std::to_string(value), &detail);
  if (status != IoStatus::kOk) last_error_ = "pwm: " + detail;
  return status;
}

IoStatus SysfsPwm::DoSetPeriodMicros(uint32_t period_us) {
  if (period_us == 0 || period_us < pulse_us_) {
    last_error_ = "pwm " + dir_ + ": period " + std::to_string(period_us) +
                  " us refused (not 0, not below the pulse of " + std::to_string(pulse_us_) +
                  " us)";
    return IoStatus::kInvalidArgument;
  }
  // A channel left by another program may have a duty cycle above the new
  // period, which the kernel refuses: cleared first.
  if (!period_known_) {
    if (const IoStatus status = Write("duty_cycle", 0); status != IoStatus::kOk) return status;
    pulse_us_ = 0;
  }
  if (const IoStatus status = Write("period", uint64_t{period_us} * 1000u);
      status != IoStatus::kOk) {
    return status;
  }
  period_us_ = period_us;
  period_known_ = true;
  return IoStatus::kOk;
}

IoStatus SysfsPwm::DoSetPulseMicros(uint32_t pulse_us) {
  if (!period_known_ || pulse_us > period_us_) {
    last_error_ = "pwm " + dir_ + ": pulse " + std::to_string(pulse_us) +
                  " us is longer than the period (" +
                  (period_known_ ? std::to_string(period_us_) + " us)" : "not set yet)");
    return IoStatus::kInvalidArgument;
  }
  if (const IoStatus status = Write("duty_cycle", uint64_t{pulse_us} * 1000u);
      status != IoStatus::kOk) {
    return status;
  }
  pulse_us_ = pulse_us;
  return IoStatus::kOk;
}

IoStatus SysfsPwm::DoSetEnabled(bool enabled) { return Write("enable", enabled ? 1 : 0); }

}  // namespace hal
}  // namespace fdsurf
