// SPDX-License-Identifier: MIT
// The CNC Shield v3's step/dir/enable lines as HAL outputs.
//
// Pin map (Arduino Uno pin = ATmega328P port bit), Grbl 1.1's
// (grbl/cpu_map.h, CPU_MAP_ATMEGA328P), which the shield is wired for:
//   X  STEP D2 = PD2   DIR D5 = PD5
//   Y  STEP D3 = PD3   DIR D6 = PD6
//   Z  STEP D4 = PD4   DIR D7 = PD7   (not driven: the job has 2 axes)
//   EN D8 = PB0, shared by the three driver sockets
// ENABLE is active low (A4988, DRV8825); DIR high means "towards negative".
//
// Every call here runs in the step timer's interrupt (Device::Tick), the
// only writer of PORTD and of PB0 after SetSafeOutputs(); the servo's
// interrupt writes no port (its pin is Timer2's OC2A), so the read-modify-
// writes need no further locking.
//
// STEP pulses go out one tick late: Step() records the axes and
// EmitStep(), first thing in the next tick's interrupt, pulses them, so
// every pulse is a whole tick after the last however long the tick's work
// (the motion profile's choice runs once a slice; boards/mega2560-ramps's
// ramps_outputs.h measured the difference). DIR is written when asked, a
// tick before its pulse.
#pragma once

#include <avr/io.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/hal/outputs.h"

namespace fdsurf {
namespace uno {

/// Puts every output in its safe state: motors released (EN high), STEP
/// and DIR low, the pen servo at "up". Called first thing after every
/// reset (power-on, watchdog, the DTR reset when the port is opened).
void SetSafeOutputs();

class ShieldSteppers final : public hal::StepDirOutputs {
 public:
  ShieldSteppers() : hal::StepDirOutputs(static_cast<uint8_t>(kAxes)) {}
  ~ShieldSteppers() = default;

  /// Pulses the axes the previous tick asked to step (none: nothing). Call
  /// first thing in the step interrupt. X and Y step on the same port, so
  /// their pulses start and end together.
  void EmitStep() {
    if (pending_ == 0) return;
    uint8_t d = 0;
    if ((pending_ & 1u) != 0) d |= _BV(PD2);
    if ((pending_ & 2u) != 0) d |= _BV(PD3);
    pending_ = 0;
    PORTD |= d;
    __builtin_avr_delay_cycles(kStepHighCycles);
    PORTD &= static_cast<uint8_t>(~d);
  }

 private:
  hal::IoStatus DoSetEnabled(bool enabled) override {
    // A pulse still to go is sent while the drivers are enabled.
    if (!enabled) EmitStep();
    if (enabled) {
      PORTB &= static_cast<uint8_t>(~_BV(PB0));
    } else {
      PORTB |= _BV(PB0);
    }
    return hal::IoStatus::kOk;
  }

  hal::IoStatus DoSetDirections(uint8_t negative_mask) override {
    if ((negative_mask & ~axis_bits()) != 0) return hal::IoStatus::kInvalidArgument;
    uint8_t d = static_cast<uint8_t>(PORTD & ~(_BV(PD5) | _BV(PD6)));
    if ((negative_mask & 1u) != 0) d |= _BV(PD5);
    if ((negative_mask & 2u) != 0) d |= _BV(PD6);
    PORTD = d;
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

}  // namespace uno
}  // namespace fdsurf
