// SPDX-License-Identifier: MIT
// The CNC Shield v3's limit switch headers as HAL inputs.
//
// Pin map (Arduino Uno pin = ATmega328P port bit), Grbl 1.1's with
// VARIABLE_SPINDLE (grbl/cpu_map.h: Z limit on D12 so that D11 is free for
// OC2A):
//   X  D9 = PB1   Y  D10 = PB2   Z  D12 = PB4 (not read: the job has 2 axes)
// The shield joins each axis's "+" and "-" headers on one pin, so a switch
// there is taken as the min switch (HOME --toward min); no max switch.
// Every input has its internal pull-up on, so an open switch (or a broken
// wire) reads HIGH. With the default FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH=1 a
// HIGH input is "triggered": normally-closed switches to GND, which fail
// safe. Build with 0 for normally-open switches to GND (Grbl's default).
//
// Read() runs in the step interrupt on every tick: one PIN register read, a
// few shifts, no waiting. No debouncing (as the Mega's: a bounce can at
// worst end a homing search one step early or late).
#pragma once

#include <avr/io.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/hal/inputs.h"

namespace fdsurf {
namespace uno {

/// Makes the limit pins (Z's too: it is then not floating) inputs with
/// their pull-ups on. Called at start.
inline void SetUpEndstopPins() {
  constexpr uint8_t b = _BV(PB1) | _BV(PB2) | _BV(PB4);
  DDRB &= static_cast<uint8_t>(~b);
  PORTB |= b;
}

class ShieldEndstops final : public hal::EndstopInputs {
 public:
  ShieldEndstops() = default;
  ~ShieldEndstops() = default;

 private:
  static constexpr uint8_t kAxisBits = 3u;  // X, Y

  hal::EndstopState DoFitted() const override {
    return hal::EndstopState{kAxisBits, static_cast<uint8_t>(0)};
  }

  // Bit a of the min mask from the pins' levels, HIGH = 1, then the polarity.
  hal::IoStatus DoRead(hal::EndstopState* state) override {
    const uint8_t b = PINB;
    uint8_t high = static_cast<uint8_t>((b >> PB1 & 1u) | (b >> PB2 & 1u) << 1);
    if (!kEndstopTriggeredHigh) high = static_cast<uint8_t>(~high);
    state->min_mask = static_cast<uint8_t>(high & kAxisBits);
    state->max_mask = 0;
    return hal::IoStatus::kOk;
  }

  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }
};

}  // namespace uno
}  // namespace fdsurf
