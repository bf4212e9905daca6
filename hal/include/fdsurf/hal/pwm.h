// SPDX-License-Identifier: MIT
// A PWM output (one channel of a timer or of Linux's PWM class) and the
// hobby-servo pen lift built on it.
//
// Same shape as outputs.h (Pigweed's pw_digital_io): non-virtual public
// methods call private pure virtual Do...() methods; the destructor is
// protected and non-virtual. Freestanding: the MCU boards use it.
//
// A hobby servo reads the width of a pulse repeated every 20 ms (50 Hz):
// about 1000 µs is one end of its travel, 2000 µs the other, 1500 µs the
// middle (the usual range; many servos take 500..2500 µs).
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/outputs.h"

namespace fdsurf {
namespace hal {

/// One PWM channel: a pulse of `pulse_us` at the start of every period of
/// `period_us`, while enabled; the line stays inactive (low) while disabled.
/// Times are microseconds; a backend whose timer counts in other units
/// rounds to its nearest tick and says so in its header.
class PwmOutput {
 public:
  PwmOutput(const PwmOutput&) = delete;
  PwmOutput& operator=(const PwmOutput&) = delete;

  /// Sets the period, µs (50 Hz: 20000). Keeps the pulse width, which must
  /// not exceed the new period.
  ///
  /// Errors:
  ///   kInvalidArgument  0, beyond what the backend's timer can count, or
  ///                     shorter than the pulse width; nothing changed.
  ///   kIoError (or what the OS said)  the backend could not set it.
  IoStatus SetPeriodMicros(uint32_t period_us) { return DoSetPeriodMicros(period_us); }

  /// Sets the pulse width, µs, from the next period on (a backend never cuts
  /// a pulse short or makes one period longer).
  ///
  /// Errors:
  ///   kInvalidArgument  longer than the period; nothing changed.
  ///   kIoError (or what the OS said)  the backend could not set it.
  IoStatus SetPulseMicros(uint32_t pulse_us) { return DoSetPulseMicros(pulse_us); }

  /// Starts (true) or stops (false) the pulses.
  ///
  /// Errors: kIoError (or what the OS said) if the backend could not.
  IoStatus SetEnabled(bool enabled) { return DoSetEnabled(enabled); }

  /// The detail of the last failed call ("" if none), naming the channel
  /// (and the file, for Linux's sysfs).
  FDSURF_NODISCARD const char* LastError() const { return DoLastError(); }

 protected:
  PwmOutput() = default;
  ~PwmOutput() = default;

 private:
  virtual IoStatus DoSetPeriodMicros(uint32_t period_us) = 0;
  virtual IoStatus DoSetPulseMicros(uint32_t pulse_us) = 0;
  virtual IoStatus DoSetEnabled(bool enabled) = 0;
  FDSURF_NODISCARD virtual const char* DoLastError() const = 0;
};

/// The servo period, µs (50 Hz).
constexpr uint32_t kServoPeriodUs = 20000;
/// The pulse widths a servo pen accepts, µs (the protocol's range too).
constexpr uint16_t kServoMinPulseUs = 500;
constexpr uint16_t kServoMaxPulseUs = 2500;

/// A pen lifted by a hobby servo on a PWM channel: the pulse is `up_us`
/// with the pen up, `down_us` with it down, every 20 ms. The widths come
/// from the constructor (the board's defaults) until a CONFIG gives others
/// (PenOutput::ConfigureServo; both 0 returns to the defaults).
///
/// The PWM object must outlive this one. Start() must be called once
/// before SetPen(): it sets the period, the pen-up width, and enables.
class ServoPen final : public PenOutput {
 public:
  ServoPen(PwmOutput& pwm, uint16_t default_up_us, uint16_t default_down_us)
      : pwm_(pwm),
        default_up_us_(default_up_us),
        default_down_us_(default_down_us),
        up_us_(default_up_us),
        down_us_(default_down_us) {}
  ~ServoPen() = default;

  /// 50 Hz, pen up, pulses on. Errors: the PWM's (LastError() has them).
  IoStatus Start() {
    IoStatus status = pwm_.SetPeriodMicros(kServoPeriodUs);
    if (status == IoStatus::kOk) status = pwm_.SetPulseMicros(up_us_);
    if (status == IoStatus::kOk) status = pwm_.SetEnabled(true);
    down_ = false;
    return Note(status);
  }

  /// The widths in force, µs.
  FDSURF_NODISCARD uint16_t up_us() const { return up_us_; }
  FDSURF_NODISCARD uint16_t down_us() const { return down_us_; }
  FDSURF_NODISCARD bool down() const { return down_; }

 private:
  IoStatus DoSetPen(bool down) override {
    down_ = down;
    return Note(pwm_.SetPulseMicros(down ? down_us_ : up_us_));
  }

  // Both 0: the defaults. Else each in 500..2500; the pen moves to the new
  // width of the state it is in.
  IoStatus DoConfigureServo(uint16_t up_us, uint16_t down_us) override {
    if (up_us == 0 && down_us == 0) {
      up_us = default_up_us_;
      down_us = default_down_us_;
    } else if (!InRange(up_us) || !InRange(down_us)) {
      pwm_failed_ = false;
      error_ = "servo pen: pulse widths outside 500..2500 us";
      return IoStatus::kInvalidArgument;
    }
    up_us_ = up_us;
    down_us_ = down_us;
    return DoSetPen(down_);
  }

  FDSURF_NODISCARD const char* DoLastError() const override {
    if (pwm_failed_) return pwm_.LastError();
    return error_ != nullptr ? error_ : "";
  }

  static bool InRange(uint16_t us) { return us >= kServoMinPulseUs && us <= kServoMaxPulseUs; }

  IoStatus Note(IoStatus status) {
    pwm_failed_ = status != IoStatus::kOk;
    error_ = nullptr;
    return status;
  }

  PwmOutput& pwm_;
  uint16_t default_up_us_;
  uint16_t default_down_us_;
  uint16_t up_us_;
  uint16_t down_us_;
  bool down_ = false;
  bool pwm_failed_ = false;
  const char* error_ = nullptr;
};

}  // namespace hal
}  // namespace fdsurf
