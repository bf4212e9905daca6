// SPDX-License-Identifier: MIT
// The build-time settings of the Arduino Uno + CNC Shield v3 image. Each one
// is a macro that CMake sets from a cache variable (boards/uno-cnc-shield/
// CMakeLists.txt, README.md); the defaults here are the documented ones.
#pragma once

#include <stddef.h>
#include <stdint.h>

#ifndef FDSURF_UNO_BAUD
#define FDSURF_UNO_BAUD 115200
#endif
#ifndef FDSURF_UNO_TICK_HZ
#define FDSURF_UNO_TICK_HZ 2000
#endif
#ifndef FDSURF_UNO_SLICE_TICKS
#define FDSURF_UNO_SLICE_TICKS 4
#endif
#ifndef FDSURF_UNO_SERVO_UP_US
#define FDSURF_UNO_SERVO_UP_US 1000
#endif
#ifndef FDSURF_UNO_SERVO_DOWN_US
#define FDSURF_UNO_SERVO_DOWN_US 2000
#endif
#ifndef FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH
#define FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH 1
#endif

namespace fdsurf {
namespace uno {

/// The USART (through the 16U2, /dev/ttyACM0), 8N1: 115200 or 250000 bit/s.
constexpr uint32_t kBaud = FDSURF_UNO_BAUD;
static_assert(kBaud == 115200 || kBaud == 250000, "FDSURF_UNO_BAUD: 115200 or 250000");

/// Step timer interrupts per second (Timer1, CTC, clock / 8 = 2 MHz).
constexpr uint32_t kTickHz = FDSURF_UNO_TICK_HZ;
constexpr uint32_t kTimerClockHz = 16000000ul / 8;
static_assert(kTickHz >= 1000 && kTickHz <= 40000 && kTimerClockHz % kTickHz == 0,
              "FDSURF_UNO_TICK_HZ: 1000..40000, dividing 2 MHz");

/// Ticks per slice: the step interrupt runs the motion profile's choice
/// (64-bit) once a slice and only adds in between (docs/motion.md,
/// "Slices"); a power of two up to 16.
constexpr uint8_t kSliceTicks = FDSURF_UNO_SLICE_TICKS;
static_assert(kSliceTicks >= 1 && kSliceTicks <= 16 && (kSliceTicks & (kSliceTicks - 1)) == 0,
              "FDSURF_UNO_SLICE_TICKS: 1, 2, 4, 8 or 16");

/// X and Y only: the job drives two axes (a pen plotter); the shield's Z
/// driver shares the enable line but its STEP and DIR stay low.
constexpr int kAxes = 2;

/// The pen servo's pulse (microseconds) for pen up and down, until a
/// CONFIG gives others. Timer2 makes them in steps of 16 us
/// (servo_pwm.h), so a width is rounded to the nearest 16 us.
constexpr uint16_t kServoUpUs = FDSURF_UNO_SERVO_UP_US;
constexpr uint16_t kServoDownUs = FDSURF_UNO_SERVO_DOWN_US;
static_assert(kServoUpUs >= 500 && kServoUpUs <= 2500 && kServoDownUs >= 500 &&
                  kServoDownUs <= 2500,
              "servo pulses from 500 to 2500 us");

/// 1: a HIGH limit input (pull-up, switch open) is "triggered", for
/// normally-closed switches to GND (fails safe: a cut wire stops the axis);
/// 0: LOW is triggered, for normally-open switches to GND (Grbl's default
/// wiring, $5=0).
constexpr bool kEndstopTriggeredHigh = FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH != 0;
static_assert(FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH == 0 || FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH == 1,
              "FDSURF_UNO_ENDSTOP_TRIGGERED_HIGH: 0 or 1");

/// Device sizes. The static RAM (the Device, the receive ring) and the
/// stack share the 2 KB: the deepest path, a PREPARED_CURVE's check in the
/// main loop with the step interrupt on top of it, takes about 640 bytes of
/// stack (README.md has the measured budget), so every buffer is as small as
/// the job allows.
/// 1 command that can wait (the host's credit): the path generator takes a
/// command out of the queue as it starts it, so the next one arrives while
/// the current one is drawn; a second slot would cost 105 bytes.
constexpr int kQueueCapacity = 1;
/// 32 entries: without turn caps the Device runs at a top speed at which it
/// brakes within a step or two (607 steps/s with the tests' limits), so 32
/// entries (50 ms of motion) are plenty.
constexpr int kLookahead = 32;
/// Encoded replies held until the main loop sends them (the Device's
/// kReplyBytes): 64 bytes hold the largest (41 bytes) and an ACK; a reply
/// that finds no room is dropped and the host's resend brings it again.
constexpr size_t kReplyBytes = 64;
/// Entries Device::Fill() may push before the main loop services the link
/// again: a point costs about 20 000 cycles here (1.3 ms), so 2 keep a
/// round at about 2.5 ms, under the 5.6 ms the receive ring holds.
constexpr uint16_t kFillBatch = 2;
/// The UART receive ring (bytes): 64 is 5.6 ms of line at 115200 bit/s,
/// and no byte was lost in the end-to-end runs (the harness's rx_overruns);
/// with 32 (2.8 ms) the CI job lost 4 bytes to a full ring while a new curve
/// was started (their frames were resent). 128 would take 64 of the bytes
/// the stack keeps clear (README.md, "RAM").
constexpr uint8_t kRxRing = 64;

/// Step pulse high time and DIR-to-STEP set-up, in CPU cycles at 16 MHz:
/// 2 us (DRV8825 needs 1.9 us, A4988 1 us) and 1 us (DRV8825 650 ns,
/// A4988 200 ns).
constexpr uint16_t kStepHighCycles = 32;
constexpr uint16_t kDirSetupCycles = 16;

}  // namespace uno
}  // namespace fdsurf
