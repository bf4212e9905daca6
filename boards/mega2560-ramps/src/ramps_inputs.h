// SPDX-License-Identifier: MIT
// The RAMPS 1.4 endstop headers as HAL inputs.
//
// Pin map (Arduino Mega pin = ATmega2560 port bit; README.md has the table):
//   X  MIN D3  = PE5   MAX D2  = PE4
//   Y  MIN D14 = PJ1   MAX D15 = PJ0
//   Z  MIN D18 = PD3   MAX D19 = PD2   (Z only in a 3-axis image)
// The min switches are always fitted; the max ones only in an image built
// with FDSURF_MEGA_MAX_ENDSTOPS=1. Every input has its internal pull-up on,
// so an open switch (or a broken wire) reads HIGH. With the default
// FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH=1 a HIGH input is "triggered": the
// normally-closed switch to GND of Marlin's convention, which fails safe (a
// cut wire stops the axis). Build with 0 for normally-open switches to GND.
//
// Read() runs in the step interrupt on every tick: three PIN register
// reads, a few shifts, no waiting. There is no debouncing: a bounce can at
// worst end a homing search one step early or late (the back-off then
// releases the switch) or stop a move that is already at the end.
#pragma once

#include <avr/io.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/hal/inputs.h"

namespace fdsurf {
namespace mega {

/// Makes the endstop pins inputs with their pull-ups on. Called at start.
inline void SetUpEndstopPins() {
  constexpr uint8_t e = _BV(PE5) | (kMaxEndstops ? _BV(PE4) : 0);
  constexpr uint8_t j = _BV(PJ1) | (kMaxEndstops ? _BV(PJ0) : 0);
  constexpr uint8_t d = _BV(PD3) | (kMaxEndstops ? _BV(PD2) : 0);
  DDRE &= static_cast<uint8_t>(~e);
  PORTE |= e;
  DDRJ &= static_cast<uint8_t>(~j);
  PORTJ |= j;
  if (kAxes == 3) {
    DDRD &= static_cast<uint8_t>(~d);
    PORTD |= d;
  }
}

class RampsEndstops final : public hal::EndstopInputs {
 public:
  RampsEndstops() = default;
  ~RampsEndstops() = default;

 private:
  static constexpr uint8_t kAxisBits = kAxes == 3 ? 7u : 3u;

  hal::EndstopState DoFitted() const override {
    return hal::EndstopState{kAxisBits, kMaxEndstops ? kAxisBits : static_cast<uint8_t>(0)};
  }

  // Bit a of each mask from the pins' levels, HIGH = 1, then the polarity.
  hal::IoStatus DoRead(hal::EndstopState* state) override {
    const uint8_t e = PINE;
    const uint8_t j = PINJ;
    const uint8_t d = kAxes == 3 ? PIND : 0;
    uint8_t high_min =
        static_cast<uint8_t>((e >> PE5 & 1u) | (j >> PJ1 & 1u) << 1 | (d >> PD3 & 1u) << 2);
    uint8_t high_max =
        static_cast<uint8_t>((e >> PE4 & 1u) | (j >> PJ0 & 1u) << 1 | (d >> PD2 & 1u) << 2);
    if (!kEndstopTriggeredHigh) {
      high_min = static_cast<uint8_t>(~high_min);
      high_max = static_cast<uint8_t>(~high_max);
    }
    const hal::EndstopState fitted = DoFitted();
    state->min_mask = static_cast<uint8_t>(high_min & fitted.min_mask);
    state->max_mask = static_cast<uint8_t>(high_max & fitted.max_mask);
    return hal::IoStatus::kOk;
  }

  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }
};

}  // namespace mega
}  // namespace fdsurf
