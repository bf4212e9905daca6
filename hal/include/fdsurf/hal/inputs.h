// SPDX-License-Identifier: MIT
// Input-only hardware: the endstop switches at the ends of each axis's
// travel. The firmware polls them in its step tick (Device::Tick): it homes
// against them, stops motion that runs into one (a hard limit, kEndstopHit),
// and reports them in STATUS; nothing here interrupts or blocks.
//
// Pigweed style, as outputs.h: non-virtual public methods call private pure
// virtual Do...() methods; the destructor is protected and non-virtual.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"

namespace fdsurf {
namespace hal {

/// Which endstops are triggered now. Axis a is bit (1 << a) in each mask
/// (X = bit 0, Y = bit 1, Z = bit 2): `min_mask` the switch at the axis's
/// position-0 end, `max_mask` the one at its travel end. An axis without a
/// switch at an end never has that bit set.
struct EndstopState {
  uint8_t min_mask;
  uint8_t max_mask;
};

/// The endstop switches of 2 or 3 axes, already debounced and with their
/// polarity applied by the backend (a set bit always means "triggered").
class EndstopInputs {
 public:
  EndstopInputs(const EndstopInputs&) = delete;
  EndstopInputs& operator=(const EndstopInputs&) = delete;

  /// The switches fitted: bit a of min_mask (max_mask) set when axis a has
  /// a switch at its min (max) end. Constant for the object's lifetime.
  FDSURF_NODISCARD EndstopState fitted() const { return DoFitted(); }

  /// Reads every switch now into *state. Cheap enough to call once per step
  /// tick (a register read on an MCU, one ioctl for all lines on Linux).
  ///
  /// Errors:
  ///   kIoError  a line could not be read (LastError() names it); *state is
  ///             then all clear.
  IoStatus Read(EndstopState* state) { return DoRead(state); }

  /// The detail of the last failed call ("" if none), naming the line.
  FDSURF_NODISCARD const char* LastError() const { return DoLastError(); }

 protected:
  EndstopInputs() = default;
  ~EndstopInputs() = default;

 private:
  FDSURF_NODISCARD virtual EndstopState DoFitted() const = 0;
  virtual IoStatus DoRead(EndstopState* state) = 0;
  FDSURF_NODISCARD virtual const char* DoLastError() const = 0;
};

}  // namespace hal
}  // namespace fdsurf
