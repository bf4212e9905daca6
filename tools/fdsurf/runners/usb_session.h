// SPDX-License-Identifier: MIT
// A USB device with the host link on it: what `fdsurf stream --device usb...`
// runs on (usb_runner.cc) and what `fdsurf machine ... --device usb...` sends
// its commands through (machine/manual_command.cc).
#pragma once

#include <memory>
#include <string>

#include "../stream_command.h"
#include "fdsurf/hal/usb_transport.h"
#include "transport_loop.h"

namespace fdsurf::host {

/// An open device and a transport loop on it, not yet connected
/// (`loop->Connect()` sends HELLO).
struct UsbSession {
  std::unique_ptr<hal::UsbTransport> usb;
  std::unique_ptr<TransportLoop> loop;
  std::string name;  ///< "usb VID:PID" or "usb BUS-PORT", for messages
};

/// Opens the device `o.device` names (usb, usb:VID:PID, usb:BUS-PORT) with
/// o's connect and reconnect timeouts, quiet and no-pause settings.
/// InputError for a --device that does not parse; DeviceError naming the
/// device when it is missing, busy or not accessible.
UsbSession OpenUsbSession(const StreamOptions& o);

}  // namespace fdsurf::host
