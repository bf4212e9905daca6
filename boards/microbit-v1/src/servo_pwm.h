// SPDX-License-Identifier: MIT
// One PWM channel on an nRF51 TIMER, by compare interrupts: the pen servo's
// pulses on the micro:bit v1 (the nRF51 has no PWM peripheral).
//
// TIMER1 counts at 1 MHz (prescaler 4) in 16 bits and runs free; CC[0] is
// the next period's start, CC[1] the current pulse's end. The interrupt
// (highest priority, above the step tick) drives the pin: high at CC[0],
// low at CC[1]. Both edges go through the same few instructions after their
// compare, so the width is exact to the µs when neither edge waits for a
// masked section (the step tick cannot delay them: it runs below). A width
// or period set now takes effect at the next period's start, so a pulse is
// never cut short nor a period stretched. The usual way (TIMER + GPIOTE +
// PPI, no interrupt) is not used: QEMU's nrf51 emulates neither GPIOTE nor
// PPI, and the firmware is tested there.
#pragma once

#include <stdint.h>

#include "fdsurf/hal/pwm.h"
#include "nrf51.h"

namespace fdsurf {
namespace board {

class TimerPwm final : public hal::PwmOutput {
 public:
  /// The pin (P0.nn) must already be an output, driven low.
  explicit TimerPwm(uint32_t pin) : pin_bit_(1u << pin) {}
  ~TimerPwm() = default;

  /// Configures and starts TIMER1 and its interrupt at `priority` (0..3).
  /// The pin stays low until SetEnabled(true).
  void Start(uint32_t priority) {
    using nrf51::Reg;
    Reg(nrf51::kTimer1Mode) = 0;
    Reg(nrf51::kTimer1Bitmode) = 0;    // 16 bit
    Reg(nrf51::kTimer1Prescaler) = 4;  // 16 MHz / 2^4 = 1 MHz: counts are µs
    Reg(nrf51::kTimer1TasksClear) = 1;
    rise_ = static_cast<uint16_t>(kFirstRiseUs);
    Reg(nrf51::Timer1Cc(0)) = rise_;
    Reg(nrf51::Timer1Cc(1)) = 0;
    Reg(nrf51::Timer1EventsCompare(0)) = 0;
    Reg(nrf51::Timer1EventsCompare(1)) = 0;
    Reg(nrf51::kTimer1IntenSet) = nrf51::kTimerIntCompare0 | nrf51::kTimerIntCompare1;
    nrf51::EnableIrq(nrf51::kTimer1Irq, priority);
    Reg(nrf51::kTimer1TasksStart) = 1;
  }

  /// From TIMER1's interrupt: a period's start (the pin goes high and the
  /// pulse's end and the next start are scheduled, with the width, period
  /// and enable last set), or a pulse's end (low).
  void OnInterrupt() {
    using nrf51::Reg;
    // Both edges take the same path to their store (a few instructions
    // apart), so the width is the compares' difference.
    const uint32_t fall = Reg(nrf51::Timer1EventsCompare(1));
    const uint32_t rise = Reg(nrf51::Timer1EventsCompare(0));
    if (fall != 0) Reg(nrf51::kGpioOutClr) = pin_bit_;
    if (rise != 0) Reg(nrf51::kGpioOutSet) = rise_bits_;
    if (fall != 0) Reg(nrf51::Timer1EventsCompare(1)) = 0;
    if (rise == 0) return;
    const uint16_t pulse_us = next_pulse_us_;
    Reg(nrf51::Timer1EventsCompare(0)) = 0;
    Reg(nrf51::Timer1Cc(1)) = static_cast<uint16_t>(rise_ + pulse_us);
    Reg(nrf51::Timer1TasksCapture(2)) = 1;
    const uint16_t lateness = static_cast<uint16_t>(Reg(nrf51::Timer1Cc(2)) - rise_);
    if (lateness > max_lateness_us_) max_lateness_us_ = lateness;
    rise_ = static_cast<uint16_t>(rise_ + next_period_us_);
    Reg(nrf51::Timer1Cc(0)) = rise_;
    // QEMU's nrf51 timer can raise a stale event on a CC write (board.cc).
    Reg(nrf51::Timer1EventsCompare(0)) = 0;
    Reg(nrf51::Timer1EventsCompare(1)) = 0;
    ++periods_;
  }

  /// Periods started, and the worst delay from a period's compare to the
  /// interrupt's capture, µs (a masked section's length, plus ~2 µs).
  uint32_t periods() const { return periods_; }
  uint16_t max_lateness_us() const { return max_lateness_us_; }

 private:
  // The first period starts 1 ms after Start().
  static constexpr uint32_t kFirstRiseUs = 1000;
  // 16 bits at 1 MHz; a period must leave the interrupt time to run.
  static constexpr uint32_t kMaxPeriodUs = 60000;

  // Called from the step tick (priority below the interrupt): each word is
  // one store, read by the interrupt at the next period's start.
  hal::IoStatus DoSetPeriodMicros(uint32_t period_us) override {
    if (period_us == 0 || period_us > kMaxPeriodUs || period_us < next_pulse_us_) {
      error_ = "servo pwm (TIMER1): period 0, over 60000 us or shorter than the pulse";
      return hal::IoStatus::kInvalidArgument;
    }
    next_period_us_ = static_cast<uint16_t>(period_us);
    error_ = "";
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoSetPulseMicros(uint32_t pulse_us) override {
    if (pulse_us > next_period_us_) {
      error_ = "servo pwm (TIMER1): pulse longer than the period";
      return hal::IoStatus::kInvalidArgument;
    }
    next_pulse_us_ = static_cast<uint16_t>(pulse_us);
    UpdateRiseBits();
    error_ = "";
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoSetEnabled(bool enabled) override {
    next_enabled_ = enabled;
    UpdateRiseBits();
    error_ = "";
    return hal::IoStatus::kOk;
  }
  const char* DoLastError() const override { return error_; }

  // What a period's start writes to OUTSET: the pin, or nothing while
  // disabled or with a 0 µs pulse (one store: the interrupt sees old or new).
  void UpdateRiseBits() { rise_bits_ = next_enabled_ && next_pulse_us_ != 0 ? pin_bit_ : 0u; }

  uint32_t pin_bit_;
  // The interrupt's own state: the current period's start (TIMER1 count).
  uint16_t rise_ = 0;
  uint16_t max_lateness_us_ = 0;
  uint32_t periods_ = 0;
  // Set by the step tick, taken at the next period's start.
  volatile uint16_t next_period_us_ = 20000;
  volatile uint16_t next_pulse_us_ = 0;
  volatile bool next_enabled_ = false;
  volatile uint32_t rise_bits_ = 0;
  const char* error_ = "";
};

}  // namespace board
}  // namespace fdsurf
