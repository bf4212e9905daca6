// SPDX-License-Identifier: MIT
// The host side of a serial link to a controller: a USB CDC-ACM port, a
// USB-serial chip (FTDI, CH340, the Mega's ATmega16U2), a UART, or a
// pseudo-terminal (an emulator's), through libserialport (sigrok), raw 8N1
// without flow control.
//
// The device string (ParseSerialDevice):
//
//   serial:PATH          PATH at 115200 baud, e.g. serial:/dev/ttyACM0
//   serial:PATH:BAUD     e.g. serial:/dev/ttyUSB0:250000; a PATH that itself
//                        ends in ":DIGITS" needs the BAUD given
//   serial:auto          the one listed port whose device answers HELLO
//                        (chosen by the caller: see ListSerialPorts)
#pragma once

#include <stddef.h>
#include <stdint.h>

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/transport.h"

namespace fdsurf {
namespace hal {

/// A parsed device string.
struct SerialSpec {
  /// The port's path ("" for serial:auto).
  std::string path;
  uint32_t baud = 115200;
  /// serial:auto: probe the listed ports.
  bool automatic = false;
};

/// Parses "serial:PATH[:BAUD]" or "serial:auto". BAUD is 50..4000000. Returns
/// false with a one-line reason in `*error`, e.g. "serial device
/// 'serial:/dev/ttyACM0:fast': ...".
bool ParseSerialDevice(std::string_view spec, SerialSpec* parsed, std::string* error);

/// What the system knows about one serial port.
struct SerialPortInfo {
  /// The device node, e.g. "/dev/ttyACM0" (as given, for a port named by
  /// the user).
  std::string path;
  /// "usb", "native" (a UART on the board), "bluetooth", "pty" or "unknown".
  std::string transport;
  /// USB identity, -1 / "" when not a USB port or not known.
  int usb_vendor_id = -1;
  int usb_product_id = -1;
  std::string usb_serial;
  std::string manufacturer;
  std::string product;
  /// libserialport's description ("Arduino Mega 2560", "ttyS0").
  std::string description;
  /// The /dev/serial/by-id link that points at this port, "" if none.
  std::string by_id;

  /// "2341:0042" or "" when not a USB port.
  FDSURF_NODISCARD std::string VidPid() const;
};

/// Every serial port the system lists (libserialport's sp_list_ports, which
/// reads sysfs: pseudo-terminals are not listed), sorted by path.
std::vector<SerialPortInfo> ListSerialPorts();

/// What is known about the port at `path` (a device node or a symlink to
/// one): its listing entry if it has one, else transport "pty" for a
/// pseudo-terminal, "unknown" otherwise. `path` stays as given.
SerialPortInfo DescribeSerialPort(const std::string& path);

/// Where the device `identity` (as it was when first opened) is now, for a
/// reconnect: for a USB port with a serial number, the path of the port in
/// `ports` with the same VID:PID and serial number (a board may come back as
/// another /dev/ttyACMn), "" if none is there yet; for any other port, its
/// own path again (a /dev/serial/by-id link, or a symlink re-pointed at a
/// new pty).
std::string FindSamePort(const std::vector<SerialPortInfo>& ports, const SerialPortInfo& identity);

struct SerialOptions {
  uint32_t baud = 115200;
  /// How often Reconnect() looks for the port again while it waits.
  uint32_t reconnect_poll_ms = 50;
};

/// A Transport over one serial port: raw, 8 data bits, no parity, 1 stop
/// bit, no RTS/CTS and no XON/XOFF, at the given baud. Opened exclusively:
/// TIOCEXCL (other programs' opens fail with EBUSY, unless they run as root)
/// and flock(LOCK_EX) (which pyserial's exclusive mode, picocom, and another
/// fdsurf also take, root or not).
///
/// Opening an Arduino's port resets the board through DTR (the kernel raises
/// DTR on open); its bootloader then ignores the line for 1-2 s, which the
/// caller rides out by retrying its HELLO. The port is left with HUPCL
/// clear, so closing it keeps DTR up and the next open does not reset the
/// board again (its homing survives from one fdsurf command to the next).
///
/// A hang-up (the master side of a pty closed, a USB-serial adapter
/// unplugged: POLLHUP, EIO, or end of file) closes the port and gives
/// kDisconnected. Reconnect() then waits for the same device: a USB port is
/// found again by USB VID:PID and serial number among the listed ports (it
/// may come back as another /dev/ttyACMn); any other port (one without a USB
/// serial number, a pty) by reopening the same path, e.g. a
/// /dev/serial/by-id link or a symlink that now points at a new pty.
///
/// Errors name the port, e.g.
///   "serial /dev/ttyACM9: no such port"
///   "serial /dev/ttyACM0: busy (another program has it open)"
///   "serial /dev/ttyACM0: permission denied (add yourself to the dialout group: ...)"
class SerialTransport final : public Transport {
 public:
  /// Opens and configures the port at `path`.
  ///
  /// Errors (detail in `*error`; `*transport` left empty):
  ///   kNotFound          no such file, or no device behind it.
  ///   kBusy              another program has the port open (exclusively).
  ///   kPermissionDenied  the device node cannot be opened by this user.
  ///   kInvalidArgument   the baud cannot be set.
  ///   kIoError           not a serial port, or another failure.
  static IoStatus Open(const std::string& path, const SerialOptions& options,
                       std::unique_ptr<SerialTransport>* transport, std::string* error);

  ~SerialTransport();
  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;

  /// The path given to Open().
  FDSURF_NODISCARD const std::string& path() const { return path_; }
  /// The device node last opened (the path with symlinks resolved).
  FDSURF_NODISCARD const std::string& device_node() const { return node_; }
  /// The port as first opened (its USB identity, if any).
  FDSURF_NODISCARD const SerialPortInfo& identity() const { return identity_; }
  FDSURF_NODISCARD bool connected() const { return fd_ >= 0; }
  /// Whether libserialport opened and configured the port (false: a port
  /// it does not handle, e.g. a pty, configured through termios here).
  FDSURF_NODISCARD bool opened_by_libserialport() const { return by_libserialport_; }

 private:
  SerialTransport(std::string path, const SerialOptions& options);

  IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) override;
  IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received, uint32_t timeout_ms) override;
  IoStatus DoReconnect(uint32_t timeout_ms) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  // Opens `node` (a path), configures it and takes the locks.
  IoStatus Attach(const std::string& node, std::string* error);
  // Where the same device is now: the path, or the listed USB port with the
  // identity's VID:PID and serial number ("" when it is not there).
  FDSURF_NODISCARD std::string FindAgain() const;
  void Close();
  IoStatus HangUp(const std::string& during);
  IoStatus Fail(IoStatus status, std::string detail);

  std::string path_;
  SerialOptions options_;
  std::string node_;
  SerialPortInfo identity_;
  int fd_ = -1;
  // libserialport's handle when it opened the port (struct sp_port).
  void* sp_port_ = nullptr;
  bool by_libserialport_ = false;
  std::string last_error_;
};

}  // namespace hal
}  // namespace fdsurf
