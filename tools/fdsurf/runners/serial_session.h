// SPDX-License-Identifier: MIT
// A serial port with the host link on it: what `fdsurf stream --device
// serial:...` runs on and what `fdsurf ports --probe` asks (serial_runner.cc).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "../stream_command.h"
#include "fdsurf/hal/serial_transport.h"
#include "fdsurf/host/stream.h"
#include "transport_loop.h"

namespace fdsurf::host {

/// An open port whose device answered HELLO (`loop->link().hello()`).
struct SerialSession {
  std::unique_ptr<hal::SerialTransport> port;
  std::unique_ptr<TransportLoop> loop;
};

/// Opens `path` at `baud` and sends HELLO for up to `connect_timeout_ms`.
/// Returns the session, or nothing with the reason in `*error` (naming the
/// port: missing, busy, no answer). `*interrupted` is set after Ctrl-C.
std::optional<SerialSession> ProbeSerialPort(const std::string& path, std::uint32_t baud,
                                             std::uint32_t connect_timeout_ms, bool quiet,
                                             std::string* error, bool* interrupted);

/// `fdsurf stream --device serial:PATH[:BAUD]|serial:auto`: 0 done, 130
/// after Ctrl-C; DeviceError (exit 3) naming the port for a missing, busy or
/// silent port, one lost and not back in time, or a job the device refuses.
int RunSerial(const StreamOptions& o, const StreamJob& job);

}  // namespace fdsurf::host
