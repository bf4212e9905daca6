// SPDX-License-Identifier: MIT
// The micro:bit v1 pin map of the board port (README.md has the table with
// the edge-connector names). Numbers are nRF51822 GPIOs (P0.nn), from the
// micro:bit v1.3 schematic's edge-connector net names. Every line below is
// a pin the display, the buttons and the accelerometer/compass I2C leave
// free (P13..P16 are the SPI pins, unused by this firmware).
#pragma once

#include <stdint.h>

namespace fdsurf {
namespace board {
namespace pins {

constexpr uint32_t kXStep = 23;   // edge P13
constexpr uint32_t kXDir = 22;    // edge P14
constexpr uint32_t kYStep = 21;   // edge P15
constexpr uint32_t kYDir = 16;    // edge P16
constexpr uint32_t kEnable = 18;  // edge P8, shared by both drivers, active low
constexpr uint32_t kPen = 3;      // edge P0 (the big ring), 1 = pen down (pen line build)
constexpr uint32_t kServo = 2;    // edge P1 (big ring), the pen servo's pulses (servo build)
// The X and Y min endstops: normally-open switches to GND, internal pull-ups
// on (a closed switch reads 0), as Grbl wires its limit pins.
constexpr uint32_t kXMin = 1;   // edge P2 (the big ring)
constexpr uint32_t kYMin = 20;  // edge P12

// The UART to the interface chip (KL26Z), which the USB cable presents as
// a CDC-ACM port (/dev/ttyACM0): the target's TX and RX.
constexpr uint32_t kUartTx = 24;
constexpr uint32_t kUartRx = 25;

constexpr uint32_t Bit(uint32_t pin) { return 1u << pin; }
constexpr uint32_t kStepBits[2] = {Bit(kXStep), Bit(kYStep)};
constexpr uint32_t kDirBits[2] = {Bit(kXDir), Bit(kYDir)};
constexpr uint32_t kMinBits[2] = {Bit(kXMin), Bit(kYMin)};
constexpr uint32_t kOutputBits =
    Bit(kXStep) | Bit(kXDir) | Bit(kYStep) | Bit(kYDir) | Bit(kEnable) | Bit(kPen) | Bit(kServo);

/// The DIR level that means "towards negative" (waveform header), and the
/// ENABLE level that energises the A4988/DRV8825 (active low).
constexpr uint32_t kDirNegativeLevel = 1;
constexpr uint32_t kEnableActiveLevel = 0;

}  // namespace pins
}  // namespace board
}  // namespace fdsurf
