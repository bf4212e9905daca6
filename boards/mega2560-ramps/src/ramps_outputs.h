// SPDX-License-Identifier: MIT
// The RAMPS 1.4 step/dir/enable lines and the pen servo as HAL outputs.
//
// Pin map (Arduino Mega pin = ATmega2560 port bit; README.md has the table):
//   X  STEP D54/A0 = PF0   DIR D55/A1 = PF1   EN D38    = PD7
//   Y  STEP D60/A6 = PF6   DIR D61/A7 = PF7   EN D56/A2 = PF2
//   Z  STEP D46    = PL3   DIR D48    = PL1   EN D62/A8 = PK0
//   pen servo D11 = PB5 = OC1A (the RAMPS servo header's first signal pin)
// ENABLE is active low (A4988, DRV8825); DIR high means "towards negative".
//
// Every call here runs in the step timer's interrupt (Device::Tick), the
// only writer of these ports after SetSafeOutputs(), so the read-modify-
// writes of PORTF/PORTL/PORTK need no further locking.
//
// STEP pulses go out one tick late: Step() records the axes and
// EmitStep(), first thing in the next tick's interrupt, pulses them. The
// tick's work takes from ~400 to ~4,400 cycles (the motion profile's choice
// runs once a slice, docs/motion.md), and a pulse at the end of it would
// move by that much from tick to tick (two moves 244 µs apart at 2 kHz);
// from the interrupt's start every pulse is a whole tick after the last.
// DIR is written when asked, a tick before its pulse.
#pragma once

#include <avr/io.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/board/servo_widths.h"
#include "fdsurf/hal/outputs.h"

namespace fdsurf {
namespace mega {

/// Puts every output in its safe state: motors released (ENABLE high),
/// STEP and DIR low, and the pen servo driven to "up". Called first thing
/// after every reset (power-on, watchdog, external).
void SetSafeOutputs();

class RampsSteppers final : public hal::StepDirOutputs {
 public:
  RampsSteppers() : hal::StepDirOutputs(static_cast<uint8_t>(kAxes)) {}
  ~RampsSteppers() = default;

  /// Pulses the axes the previous tick asked to step (none: nothing). Call
  /// first thing in the step interrupt. X and Y step on the same port, so
  /// their pulses start and end together.
  void EmitStep() {
    if (pending_ == 0) return;
    uint8_t f = 0;
    if ((pending_ & 1u) != 0) f |= _BV(PF0);
    if ((pending_ & 2u) != 0) f |= _BV(PF6);
    const bool z = kAxes == 3 && (pending_ & 4u) != 0;
    pending_ = 0;
    PORTF |= f;
    if (z) PORTL |= _BV(PL3);
    __builtin_avr_delay_cycles(kStepHighCycles);
    PORTF &= static_cast<uint8_t>(~f);
    if (z) PORTL &= static_cast<uint8_t>(~_BV(PL3));
  }

 private:
  hal::IoStatus DoSetEnabled(bool enabled) override {
    // A pulse still to go is sent while the driver is enabled.
    if (!enabled) EmitStep();
    if (enabled) {
      PORTD &= static_cast<uint8_t>(~_BV(PD7));
      PORTF &= static_cast<uint8_t>(~_BV(PF2));
      if (kAxes == 3) PORTK &= static_cast<uint8_t>(~_BV(PK0));
    } else {
      PORTD |= _BV(PD7);
      PORTF |= _BV(PF2);
      if (kAxes == 3) PORTK |= _BV(PK0);
    }
    return hal::IoStatus::kOk;
  }

  hal::IoStatus DoSetDirections(uint8_t negative_mask) override {
    if ((negative_mask & ~axis_bits()) != 0) return hal::IoStatus::kInvalidArgument;
    uint8_t f = static_cast<uint8_t>(PORTF & ~(_BV(PF1) | _BV(PF7)));
    if ((negative_mask & 1u) != 0) f |= _BV(PF1);
    if ((negative_mask & 2u) != 0) f |= _BV(PF7);
    PORTF = f;
    if (kAxes == 3) {
      if ((negative_mask & 4u) != 0) {
        PORTL |= _BV(PL1);
      } else {
        PORTL &= static_cast<uint8_t>(~_BV(PL1));
      }
    }
    __builtin_avr_delay_cycles(kDirSetupCycles);
    return hal::IoStatus::kOk;
  }

  // Recorded for EmitStep() in the next tick (at most one move a tick).
  hal::IoStatus DoStep(uint8_t axis_mask) override {
    if ((axis_mask & ~axis_bits()) != 0) return hal::IoStatus::kInvalidArgument;
    pending_ = static_cast<uint8_t>(pending_ | axis_mask);
    return hal::IoStatus::kOk;
  }

  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }

  /// The axes to pulse at the next tick's start.
  uint8_t pending_ = 0;
};

/// The pen as a hobby servo on OC1A: Timer1 in fast PWM (mode 14, TOP =
/// ICR1) at 2 MHz, 50 Hz; the pulse width is OCR1A / 2 microseconds.
/// A new width takes effect at the start of the next 20 ms period, from
/// Timer1's overflow interrupt (OnPeriodStart): the hardware buffers OCR1A
/// in this mode anyway, simavr does not, and a width changed mid-pulse must
/// not make one 21 ms pulse. The widths are the image's (kServoUpUs,
/// kServoDownUs) until a CONFIG gives others (servo_up_us/servo_down_us,
/// 500..2500 µs, checked by the codec); a CONFIG with both 0 returns to the
/// image's.
class ServoPen final : public hal::PenOutput {
 public:
  ServoPen() = default;
  ~ServoPen() = default;

  /// OCR1A for a pulse of `us` microseconds.
  static constexpr uint16_t CompareFor(uint16_t us) { return static_cast<uint16_t>(us * 2u); }

  /// Call from TIMER1_OVF_vect.
  void OnPeriodStart() {
    OCR1A = next_compare_;
    TIMSK1 &= static_cast<uint8_t>(~_BV(TOIE1));
  }

 private:
  // Runs in the step interrupt, so the overflow interrupt cannot cut in.
  hal::IoStatus DoSetPen(bool down) override {
    widths_.set_down(down);
    next_compare_ = CompareFor(widths_.WidthUs());
    TIFR1 = _BV(TOV1);  // an overflow flagged before now is not this period's start
    TIMSK1 |= _BV(TOIE1);
    return hal::IoStatus::kOk;
  }
  // Also from the step interrupt (Device::Tick), before any pen change; the
  // pen moves to the new width of the state it is in.
  hal::IoStatus DoConfigureServo(uint16_t up_us, uint16_t down_us) override {
    widths_.Configure(up_us, down_us);
    return DoSetPen(widths_.down());
  }
  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }

  volatile uint16_t next_compare_ = CompareFor(kServoUpUs);
  board::ServoWidths<kServoUpUs, kServoDownUs> widths_;
};

}  // namespace mega
}  // namespace fdsurf
