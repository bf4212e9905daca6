// SPDX-License-Identifier: MIT
// The micro:bit's X and Y min endstops (pins.h) as HAL inputs: two edge
// connector pins with their internal pull-ups on, a normally-open switch to
// GND closing each (Grbl's limit-pin wiring), so a LOW level is "triggered"
// and an unconnected pin reads "open". One read of GPIO IN takes both at
// once; the device reads them every tick (fdsurf/device/device.h).
#pragma once

#include <stdint.h>

#include "fdsurf/hal/inputs.h"
#include "nrf51.h"
#include "pins.h"

namespace fdsurf {
namespace board {

/// Makes the endstop pins inputs with their pull-ups on. Called at start.
inline void SetUpEndstopPins() {
  nrf51::Reg(nrf51::GpioPinCnf(pins::kXMin)) = nrf51::kPinCnfInputPullUp;
  nrf51::Reg(nrf51::GpioPinCnf(pins::kYMin)) = nrf51::kPinCnfInputPullUp;
}

class PinEndstops final : public hal::EndstopInputs {
 public:
  PinEndstops() = default;
  ~PinEndstops() = default;

 private:
  hal::EndstopState DoFitted() const override { return hal::EndstopState{0x03, 0x00}; }

  hal::IoStatus DoRead(hal::EndstopState* state) override {
    const uint32_t in = nrf51::Reg(nrf51::kGpioIn);
    uint8_t min_mask = 0;
    for (int a = 0; a < 2; ++a) {
      if ((in & pins::kMinBits[a]) == 0) min_mask = static_cast<uint8_t>(min_mask | (1u << a));
    }
    state->min_mask = min_mask;
    state->max_mask = 0;
    return hal::IoStatus::kOk;
  }
  const char* DoLastError() const override { return ""; }
};

}  // namespace board
}  // namespace fdsurf
