// SPDX-License-Identifier: MIT
// Output-only hardware: the step/dir/enable lines of 2 or 3 stepper drivers
// (A4988, DRV8825, TMC2208 in step/dir mode, ...) and the pen.
//
// Pigweed style (pw_digital_io): non-virtual public methods call private pure
// virtual Do...() methods; the destructor is protected and non-virtual, so
// nothing is deleted through these interfaces and freestanding builds need no
// operator delete. The types expose only what outputs can do: no reads.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"

namespace fdsurf {
namespace hal {

/// Axis a is bit (1 << a) in every mask: X = bit 0, Y = bit 1, Z = bit 2.
class StepDirOutputs {
 public:
  StepDirOutputs(const StepDirOutputs&) = delete;
  StepDirOutputs& operator=(const StepDirOutputs&) = delete;

  /// The number of axes driven: 2 (X, Y) or 3 (X, Y, Z).
  FDSURF_NODISCARD uint8_t axes() const { return axes_; }

  /// Energises (true) or releases (false) the motors. Drivers without an
  /// enable line accept this and do nothing.
  ///
  /// Errors:
  ///   kIoError  the line could not be set (LastError() has the detail).
  IoStatus SetEnabled(bool enabled) { return DoSetEnabled(enabled); }

  /// Sets every axis's direction: bit a set moves axis a towards negative
  /// on its following steps, bit a clear towards positive. Backends honour
  /// the drivers' direction set-up time before the next Step().
  ///
  /// Errors:
  ///   kInvalidArgument  a bit at or above axes() is set; nothing changed.
  ///   kIoError          a line could not be set.
  IoStatus SetDirections(uint8_t negative_mask) { return DoSetDirections(negative_mask); }

  /// Sends one step pulse on every axis in `axis_mask` (0: does nothing).
  /// Returns after the pulse has ended (the STEP lines are low again).
  ///
  /// Errors:
  ///   kInvalidArgument  a bit at or above axes() is set; nothing pulsed.
  ///   kIoError          a line could not be set; the backend has tried to
  ///                     bring every STEP line low again.
  IoStatus Step(uint8_t axis_mask) { return DoStep(axis_mask); }

  /// The detail of the last failed call ("" if none), naming the line.
  FDSURF_NODISCARD const char* LastError() const { return DoLastError(); }

 protected:
  explicit StepDirOutputs(uint8_t axes) : axes_(axes) {}
  ~StepDirOutputs() = default;

  /// The mask of the valid axis bits, (1 << axes()) - 1.
  FDSURF_NODISCARD uint8_t axis_bits() const { return static_cast<uint8_t>((1u << axes_) - 1u); }

 private:
  virtual IoStatus DoSetEnabled(bool enabled) = 0;
  virtual IoStatus DoSetDirections(uint8_t negative_mask) = 0;
  virtual IoStatus DoStep(uint8_t axis_mask) = 0;
  FDSURF_NODISCARD virtual const char* DoLastError() const = 0;

  uint8_t axes_;
};

/// The pen of a plotter (or a spindle/laser on/off line): down draws.
class PenOutput {
 public:
  PenOutput(const PenOutput&) = delete;
  PenOutput& operator=(const PenOutput&) = delete;

  /// Lowers (true) or lifts (false) the pen. Returns once the command is
  /// given; the mechanical settling time is the caller's to wait.
  ///
  /// Errors:
  ///   kIoError  the line could not be set (LastError() has the detail).
  IoStatus SetPen(bool down) { return DoSetPen(down); }

  /// The pen's configuration from the machine's CONFIG (protocol fields
  /// servo_up_us, servo_down_us): a hobby-servo pen (hal/pwm.h ServoPen)
  /// pulses `up_us` with the pen up and `down_us` with it down, µs, and
  /// moves to the new width of the state it is in; both 0 means "a plain
  /// switch" (a servo pen returns to its board's default widths). A plain
  /// switch pen (a GPIO line) has nothing to configure and accepts any
  /// widths: the optional hook's default does nothing.
  ///
  /// Errors:
  ///   kInvalidArgument  a servo pen: the widths are not both 0 and one is
  ///                     outside 500..2500; nothing changed.
  ///   kIoError          the servo's PWM could not be set.
  IoStatus ConfigureServo(uint16_t up_us, uint16_t down_us) {
    return DoConfigureServo(up_us, down_us);
  }

  /// The detail of the last failed call ("" if none).
  FDSURF_NODISCARD const char* LastError() const { return DoLastError(); }

 protected:
  PenOutput() = default;
  ~PenOutput() = default;

 private:
  virtual IoStatus DoSetPen(bool down) = 0;
  virtual IoStatus DoConfigureServo(uint16_t /*up_us*/, uint16_t /*down_us*/) {
    return IoStatus::kOk;
  }
  FDSURF_NODISCARD virtual const char* DoLastError() const = 0;
};

}  // namespace hal
}  // namespace fdsurf
