// SPDX-License-Identifier: MIT
// The result of every call across the hardware boundary (transport, outputs).
// Freestanding: the firmware side uses it on an MCU, so no C++ library here.
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"

namespace fdsurf {
namespace hal {

/// What went wrong, coarsely, so that callers can decide what to do next
/// (retry, reconnect, give up). The detail for people is the backend's
/// LastError() string. [[nodiscard]] (FDSURF_NODISCARD): dropping an
/// IoStatus drops a hardware failure.
enum class FDSURF_NODISCARD IoStatus : uint8_t {
  kOk = 0,
  /// Nothing (or not everything) happened within the time allowed.
  kTimeout,
  /// The device went away (unplugged, reset); Reconnect() may bring it back.
  kDisconnected,
  /// No such device, chip, line, interface or endpoint.
  kNotFound,
  /// The device or line is in use by another program or driver.
  kBusy,
  /// The operating system refused access (device node permissions).
  kPermissionDenied,
  /// The caller passed something the call does not accept (a mask with bits
  /// beyond the configured axes, a null buffer, a malformed device string).
  kInvalidArgument,
  /// Any other failure of the underlying driver or library.
  kIoError,
};

/// A short, stable, lower-case name: "ok", "timeout", "disconnected",
/// "not found", "busy", "permission denied", "invalid argument", "I/O error".
const char* IoStatusName(IoStatus status);

}  // namespace hal
}  // namespace fdsurf
