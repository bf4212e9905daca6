// SPDX-License-Identifier: MIT
// A byte link to the other end: USB bulk endpoints, an in-memory pair, later
// perhaps a UART. The wire protocol frames its messages itself (COBS), so a
// transport only moves bytes and reports failures.
//
// Pigweed style (pw_digital_io): the public methods are non-virtual and call
// private pure virtual Do...() methods that backends implement. The destructor
// is protected and non-virtual: nobody deletes a backend through this
// interface, so freestanding builds need no operator delete. Backends are
// final classes with public destructors.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"

namespace fdsurf {
namespace hal {

class Transport {
 public:
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  /// Sends all `size` bytes of `data`, waiting at most `timeout_ms` (0: only
  /// as long as the backend must to hand the bytes over).
  ///
  /// Errors:
  ///   kTimeout          not everything was sent in time; some bytes may have
  ///                     gone out (LastError() says how many), so a framed
  ///                     protocol must resynchronise at the next frame.
  ///   kDisconnected     the link is down; call Reconnect().
  ///   kInvalidArgument  `data` is null while `size` > 0.
  ///   kIoError          any other failure (LastError() has the detail).
  IoStatus Write(const uint8_t* data, size_t size, uint32_t timeout_ms) {
    return DoWrite(data, size, timeout_ms);
  }

  /// Receives at least 1 and at most `capacity` bytes into `data`, waiting at
  /// most `timeout_ms` for the first byte, and stores the count in
  /// `*received`. Never waits for `capacity` bytes: it returns what arrived.
  ///
  /// Errors (`*received` is 0 on every error):
  ///   kTimeout          nothing arrived in time.
  ///   kDisconnected     the link is down; call Reconnect().
  ///   kInvalidArgument  `data` or `received` is null, or `capacity` is 0.
  ///   kIoError          any other failure.
  IoStatus Read(uint8_t* data, size_t capacity, size_t* received, uint32_t timeout_ms) {
    return DoRead(data, capacity, received, timeout_ms);
  }

  /// After kDisconnected: waits up to `timeout_ms` for the same device (not
  /// just any device of the same kind) to come back, and reopens it. Bytes
  /// queued in either direction before the disconnect are lost. Returns kOk
  /// at once if the link is up.
  ///
  /// Errors:
  ///   kTimeout           the device did not come back in time.
  ///   kPermissionDenied  it came back but cannot be opened.
  ///   kBusy              it came back but another program holds it.
  ///   kIoError           any other failure.
  IoStatus Reconnect(uint32_t timeout_ms) { return DoReconnect(timeout_ms); }

  /// The human-readable detail of the last failed call, naming the device
  /// (e.g. "usb 1209:0001: disconnected (LIBUSB_ERROR_NO_DEVICE)"), or ""
  /// if no call has failed yet. Valid until the next call on this object.
  FDSURF_NODISCARD const char* LastError() const { return DoLastError(); }

 protected:
  Transport() = default;
  ~Transport() = default;

 private:
  virtual IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) = 0;
  virtual IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received,
                          uint32_t timeout_ms) = 0;
  virtual IoStatus DoReconnect(uint32_t timeout_ms) = 0;
  FDSURF_NODISCARD virtual const char* DoLastError() const = 0;
};

}  // namespace hal
}  // namespace fdsurf
