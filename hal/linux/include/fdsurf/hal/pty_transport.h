// SPDX-License-Identifier: MIT
// The device side of a serial port that a program on this host serves: a
// kernel pseudo-terminal (pty(7)) in raw mode, its slave published under a
// stable path by a symlink, so that the host tool opens it as
// `--device serial:PATH` as it would a board's /dev/ttyACM0. Klipper's
// Linux MCU process publishes itself the same way (/tmp/klipper_host_mcu).
//
// `fdsurf serve` (the firmware's Device on this host's GPIO lines) and the
// tests' pty device are its users. The slave is kept open here too, so that a
// client closing the port is not a hang-up for the master: the next client
// opens the same path and starts a new session.
#pragma once

#include <stdint.h>

#include <memory>
#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/transport.h"

namespace fdsurf {
namespace hal {

class PtyTransport final : public Transport {
 public:
  /// Opens a pty, makes its line discipline raw (no echo, no CR/LF
  /// translation, 8 bits) and publishes the slave at `link`: the symlink is
  /// written beside it as `link`.new and renamed over `link`, so a client
  /// never sees a half-made link, and an old link left by a process that was
  /// killed is replaced.
  ///
  /// Errors (detail in `*error`, naming the call and the path; `*pty` left
  /// empty):
  ///   kNotFound          `link`'s directory does not exist.
  ///   kPermissionDenied  `link` cannot be written there.
  ///   kIoError           openpty or the terminal settings failed.
  static IoStatus Open(const std::string& link, std::unique_ptr<PtyTransport>* pty,
                       std::string* error);

  /// Removes the link (if it still points at this pty) and closes the pty.
  ~PtyTransport();
  PtyTransport(const PtyTransport&) = delete;
  PtyTransport& operator=(const PtyTransport&) = delete;

  /// The published path, and the pty's own name (/dev/pts/N).
  FDSURF_NODISCARD const std::string& link() const { return link_; }
  FDSURF_NODISCARD const std::string& slave_name() const { return slave_name_; }

 private:
  PtyTransport(int master, int slave, std::string link, std::string slave_name)
      : master_(master),
        slave_(slave),
        link_(std::move(link)),
        slave_name_(std::move(slave_name)) {}

  // Write: waits for room up to `timeout_ms` (kTimeout after a partial
  // write: the client is not reading). Read: returns what the master has,
  // waiting up to `timeout_ms` for the first byte. Reconnect: always kOk (a
  // pty whose slave this object holds open never hangs up).
  IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) override;
  IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received, uint32_t timeout_ms) override;
  IoStatus DoReconnect(uint32_t timeout_ms) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  IoStatus Failed(IoStatus status, const std::string& what);

  int master_;
  int slave_;
  std::string link_;
  std::string slave_name_;
  std::string last_error_;
};

}  // namespace hal
}  // namespace fdsurf
