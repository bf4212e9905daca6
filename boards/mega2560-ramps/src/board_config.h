// SPDX-License-Identifier: MIT
// The build-time settings of the Mega 2560 + RAMPS 1.4 image. Each one is a
// macro that CMake sets from a cache variable (boards/mega2560-ramps/
// CMakeLists.txt, README.md); the defaults here are the documented ones.
#pragma once

#include <stdint.h>

#ifndef FDSURF_MEGA_BAUD
#define FDSURF_MEGA_BAUD 115200
#endif
#ifndef FDSURF_MEGA_TICK_HZ
#define FDSURF_MEGA_TICK_HZ 2000
#endif
#ifndef FDSURF_MEGA_SLICE_TICKS
#define FDSURF_MEGA_SLICE_TICKS 4
#endif
#ifndef FDSURF_MEGA_AXES
#define FDSURF_MEGA_AXES 2
#endif
#ifndef FDSURF_MEGA_SERVO_UP_US
#define FDSURF_MEGA_SERVO_UP_US 1000
#endif
#ifndef FDSURF_MEGA_SERVO_DOWN_US
#define FDSURF_MEGA_SERVO_DOWN_US 2000
#endif
#ifndef FDSURF_MEGA_MAX_ENDSTOPS
#define FDSURF_MEGA_MAX_ENDSTOPS 0
#endif
#ifndef FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH
#define FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH 1
#endif

namespace fdsurf {
namespace mega {

/// UART0 (the 16U2 USB-serial chip), 8N1: 115200 or 250000 bit/s.
constexpr uint32_t kBaud = FDSURF_MEGA_BAUD;
static_assert(kBaud == 115200 || kBaud == 250000, "FDSURF_MEGA_BAUD: 115200 or 250000");

/// Step timer interrupts per second (Timer3, CTC, clock / 8 = 2 MHz).
constexpr uint32_t kTickHz = FDSURF_MEGA_TICK_HZ;
constexpr uint32_t kTimerClockHz = 16000000ul / 8;
static_assert(kTickHz >= 1000 && kTickHz <= 40000 && kTimerClockHz % kTickHz == 0,
              "FDSURF_MEGA_TICK_HZ: 1000..40000, dividing 2 MHz");

/// Ticks per slice: the step interrupt runs the motion profile's choice
/// (64-bit) once a slice and only adds in between (docs/motion.md,
/// "Slices"); a power of two up to 16.
constexpr uint8_t kSliceTicks = FDSURF_MEGA_SLICE_TICKS;
static_assert(kSliceTicks >= 1 && kSliceTicks <= 16 && (kSliceTicks & (kSliceTicks - 1)) == 0,
              "FDSURF_MEGA_SLICE_TICKS: 1, 2, 4, 8 or 16");

/// 2 (X, Y: a pen plotter) or 3 (X, Y, Z driven by the job, --dims 3).
constexpr int kAxes = FDSURF_MEGA_AXES;
static_assert(kAxes == 2 || kAxes == 3, "FDSURF_MEGA_AXES: 2 or 3");

/// The pen servo's pulse (microseconds, every 20 ms) for pen up and down.
constexpr uint16_t kServoUpUs = FDSURF_MEGA_SERVO_UP_US;
constexpr uint16_t kServoDownUs = FDSURF_MEGA_SERVO_DOWN_US;
static_assert(kServoUpUs >= 500 && kServoUpUs <= 2500 && kServoDownUs >= 500 &&
                  kServoDownUs <= 2500,
              "servo pulses from 500 to 2500 us");

/// The endstops (ramps_inputs.h): the min switches are always read; the
/// max ones (X_MAX D2, Y_MAX D15, Z_MAX D19) only when this is 1.
constexpr bool kMaxEndstops = FDSURF_MEGA_MAX_ENDSTOPS != 0;
static_assert(FDSURF_MEGA_MAX_ENDSTOPS == 0 || FDSURF_MEGA_MAX_ENDSTOPS == 1,
              "FDSURF_MEGA_MAX_ENDSTOPS: 0 or 1");
/// 1: a HIGH input (pull-up, switch open) is "triggered", for normally-
/// closed switches to GND (the default: a broken wire stops the axis);
/// 0: LOW is triggered, for normally-open switches to GND.
constexpr bool kEndstopTriggeredHigh = FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH != 0;
static_assert(FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH == 0 || FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH == 1,
              "FDSURF_MEGA_ENDSTOP_TRIGGERED_HIGH: 0 or 1");

/// Device sizes: commands that can wait (the host's credit) and unit moves
/// buffered ahead of the motion. They and the validation's stack share the
/// 8 KB of RAM (README.md has the measured budget).
/// 128 entries: the turn caps (fdsurf/motion/turn_caps.h) took about 600 B
/// of RAM, and at this board's speeds (2000 ticks/s, 1600 steps/s and
/// 2000 mm/s² in the tests: 8 steps of braking) the 63 moves the caps keep
/// pending and 65 final ones are plenty.
constexpr int kQueueCapacity = 4;
constexpr int kLookahead = 128;
/// Entries Device::Fill() may push before the main loop services the link
/// again: expanding a point costs about 13 000 cycles here, so 16 is about
/// 15 ms (README.md).
constexpr uint16_t kFillBatch = 16;
/// The UART receive ring (bytes): 11 ms of line at 115200 bit/s.
constexpr uint8_t kRxRing = 128;
/// Bytes of replies waiting for the UART's data-register-empty interrupt:
/// the main loop hands a reply over and goes on (a polled send waited for
/// the line, 5 % of the main loop's cycles on issue 36's job), and waits
/// only when a burst of replies outgrows the ring.
constexpr uint8_t kTxRing = 128;

/// Step pulse high time and DIR-to-STEP set-up, in CPU cycles at 16 MHz:
/// 2 us (DRV8825 needs 1.9 us, A4988 1 us) and 1 us (DRV8825 650 ns,
/// A4988 200 ns).
constexpr uint16_t kStepHighCycles = 32;
constexpr uint16_t kDirSetupCycles = 16;

}  // namespace mega
}  // namespace fdsurf
