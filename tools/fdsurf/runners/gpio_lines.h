// SPDX-License-Identifier: MIT
// What the controller on this host drives, opened from one --device
// gpio:CHIP:LINES[:ENDSTOPS] (hal/libgpiod): the step/dir/enable lines, the
// pen (its line, or a hobby servo on a PWM channel of the kernel) and the
// endstop switches. `stream --device gpio:…` (gpio_runner.cc) opens them for
// one job; `fdsurf serve` (serve/) for as long as it serves.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/gpiod_inputs.h"
#include "fdsurf/hal/gpiod_outputs.h"
#include "fdsurf/hal/pwm.h"
#include "fdsurf/hal/sysfs_pwm.h"

namespace fdsurf::host {

/// A servo pen on a PWM channel of the kernel (the PEN field pwmN.M of
/// --device): started at `up_us`/`down_us` (µs, 500..2500; a CONFIG may
/// change them), lifted on every exit path (the destructor waits two 20 ms
/// periods for the up pulse to go out).
class PwmServoPen {
 public:
  /// InputError when `up_us` is 0 (the widths were not given); DeviceError
  /// when the channel cannot be opened or started (the message names it).
  PwmServoPen(const hal::GpiodConfig& config, std::uint16_t up_us, std::uint16_t down_us);
  ~PwmServoPen();
  PwmServoPen(const PwmServoPen&) = delete;
  PwmServoPen& operator=(const PwmServoPen&) = delete;

  hal::PenOutput& pen() { return *pen_; }

 private:
  std::unique_ptr<hal::SysfsPwm> pwm_;
  std::unique_ptr<hal::ServoPen> pen_;
};

/// The lines of one --device gpio:…, opened and held while this lives.
class GpioLines {
 public:
  /// Parses `device` and opens everything it names: InputError for a bad
  /// spec (naming the part; also when its axes are not `axes`, 0 takes the
  /// spec's), DeviceError when a line, the chip or the PWM channel cannot be
  /// had (naming which, and why). The servo widths are used only when the
  /// pen is pwmN.M.
  GpioLines(const std::string& device, int axes, std::uint16_t servo_up_us,
            std::uint16_t servo_down_us);
  GpioLines(const GpioLines&) = delete;
  GpioLines& operator=(const GpioLines&) = delete;

  FDSURF_NODISCARD const hal::GpiodConfig& config() const { return config_; }
  FDSURF_NODISCARD int axes() const { return config_.axes; }
  hal::GpiodOutputs& outputs() { return *outputs_; }
  /// The pen line of `outputs()`, or the servo.
  hal::PenOutput& pen() { return servo_ ? servo_->pen() : *outputs_; }
  /// nullptr without ENDSTOPS.
  hal::EndstopInputs* endstops() { return endstops_.get(); }

  /// The failed output's detail: the lines', else the pen's, else the
  /// endstops' (a switch that could not be read); "gpio: " first.
  std::string OutputError();

  /// The safe state, whatever the device did: the pen lifted and the
  /// drivers disabled directly on the lines. Whether each worked.
  struct SafeState {
    bool pen_lifted;
    bool drivers_disabled;
  };
  SafeState MakeSafe();

 private:
  hal::GpiodConfig config_;
  // Declared in this order so that the servo lifts the pen before the lines
  // are released.
  std::unique_ptr<hal::GpiodOutputs> outputs_;
  std::unique_ptr<hal::GpiodEndstops> endstops_;
  std::unique_ptr<PwmServoPen> servo_;
};

/// Puts the calling process under SCHED_FIFO (priority 40: above every
/// ordinary process, below the kernel's threaded interrupt handlers at 50),
/// as Klipper's Linux MCU process asks for real-time scheduling (its -r).
/// Another process that preempts the tick loop between a tick's wake-up and
/// its line writes makes that step late, and the next one, on time, comes
/// too soon after it: a step 2 ms after the previous one at a 4 ms minimum
/// was seen on the arm64 guest, one CPU shared with a client. The loop
/// sleeps between ticks, so it leaves the CPU to others. Needs
/// CAP_SYS_NICE (root, or an rtprio limit); without it nothing changes.
/// Returns how the process now runs, for a banner ("real-time scheduling
/// (SCHED_FIFO 40)", or "no real-time scheduling (WHY: ...)").
std::string RunInRealTime();

}  // namespace fdsurf::host
