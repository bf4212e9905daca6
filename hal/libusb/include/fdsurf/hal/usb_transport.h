// SPDX-License-Identifier: MIT
// The host side of a USB link to a controller: one vendor-specific interface
// with a bulk OUT and a bulk IN endpoint, through libusb-1.0.
//
// The device string (ParseUsbDevice):
//
//   usb                  VID:PID 1209:0001 (the pid.codes test PID; see
//                        hal/README.md before shipping hardware with it)
//   usb:VID:PID          hexadecimal, e.g. usb:1209:0001, usb:cafe:4011
//   usb:BUS-PORT[.PORT]  the physical port, as in /sys/bus/usb/devices:
//                        usb:1-1.4 is bus 1, root port 1, hub port 4
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

struct libusb_context;
struct libusb_device;
struct libusb_device_handle;
struct libusb_device_descriptor;

namespace fdsurf {
namespace hal {

/// Which device to open: by VID:PID (the first match), or, when `ports` is
/// non-empty, by bus number and port path.
struct UsbSelector {
  uint16_t vendor_id = 0x1209;
  uint16_t product_id = 0x0001;
  uint8_t bus = 0;
  std::vector<uint8_t> ports;

  FDSURF_NODISCARD bool by_port() const { return !ports.empty(); }
  /// "1209:0001" or "1-1.4": how every error message names the device.
  FDSURF_NODISCARD std::string ToString() const;
};

/// Parses "usb", "usb:VID:PID" or "usb:BUS-PORT[.PORT...]". Returns false with
/// a one-line reason in `*error`, e.g. "usb device 'usb:12x9:1': VID '12x9' is
/// not a hexadecimal number of 1 to 4 digits".
bool ParseUsbDevice(std::string_view spec, UsbSelector* selector, std::string* error);

struct UsbOptions {
  /// The bInterfaceNumber of the vendor-specific (class 0xff) interface.
  uint8_t interface_number = 0;
  /// How often Reconnect() re-enumerates while it waits.
  uint32_t reconnect_poll_ms = 100;
};

/// A Transport over the bulk endpoints of one USB interface.
///
/// Write() sends all bytes (libusb splits them into packets); Read() returns
/// what one bulk IN transfer brought (kept in an internal buffer of whole
/// packets, so reads never overflow). LIBUSB_ERROR_NO_DEVICE or
/// LIBUSB_ERROR_IO (unplug, reset) makes the transport kDisconnected;
/// Reconnect() then re-enumerates until the same device is back: same VID:PID
/// and serial number if it has one, else same VID:PID on the same port path.
///
/// Errors name the device and libusb's error name, e.g.
///   "usb 1209:0001: no such device (12 USB devices seen)"
///   "usb 1-1.4: interface 0 busy (claimed by another program)"
///   "usb 1209:0001: permission denied opening /dev/bus/usb/001/007 (add a udev rule: ...)"
class UsbTransport final : public Transport {
 public:
  /// Initialises libusb, finds the device, checks that the interface is
  /// vendor-specific with a bulk OUT and a bulk IN endpoint, detaches any
  /// kernel driver and claims the interface.
  ///
  /// Errors (detail in `*error`; `*transport` left empty):
  ///   kNotFound          no such device, interface or endpoint.
  ///   kPermissionDenied  the device node cannot be opened (udev rule).
  ///   kBusy              another program has claimed the interface.
  ///   kIoError           libusb cannot start (e.g. no /dev/bus/usb in a
  ///                      container) or another libusb error.
  static IoStatus Open(const UsbSelector& selector, const UsbOptions& options,
                       std::unique_ptr<UsbTransport>* transport, std::string* error);

  ~UsbTransport();
  UsbTransport(const UsbTransport&) = delete;
  UsbTransport& operator=(const UsbTransport&) = delete;

  /// The device opened (valid after Open, kept across reconnects).
  FDSURF_NODISCARD uint16_t vendor_id() const { return vendor_id_; }
  FDSURF_NODISCARD uint16_t product_id() const { return product_id_; }
  /// The serial number string, "" if the device has none.
  FDSURF_NODISCARD const std::string& serial() const { return serial_; }
  /// "BUS-PORT.PORT..." of the device as last opened.
  FDSURF_NODISCARD std::string port_path() const;
  FDSURF_NODISCARD bool connected() const { return handle_ != nullptr; }

 private:
  enum class Match { kTaken, kSkipped, kFailed };

  UsbTransport(const UsbSelector& selector, const UsbOptions& options, libusb_context* context);

  IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) override;
  IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received, uint32_t timeout_ms) override;
  IoStatus DoReconnect(uint32_t timeout_ms) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  // Enumerates and opens the selected device (or, when `reconnecting`, the
  // same device as before).
  IoStatus Attach(bool reconnecting, std::string* error);
  Match TryDevice(libusb_device* device, const libusb_device_descriptor& descriptor,
                  bool reconnecting, IoStatus* status, std::string* error);
  void CloseHandle();
  // A fresh libusb context (a new enumeration) while disconnected.
  void RenewContext();
  IoStatus Fail(IoStatus status, std::string detail);
  IoStatus TransferError(int rc, const char* what, const std::string& progress);

  UsbSelector selector_;
  UsbOptions options_;
  std::string name_;
  libusb_context* context_;
  libusb_device_handle* handle_ = nullptr;
  uint8_t endpoint_out_ = 0;
  uint8_t endpoint_in_ = 0;
  uint16_t vendor_id_ = 0;
  uint16_t product_id_ = 0;
  std::string serial_;
  uint8_t bus_ = 0;
  std::vector<uint8_t> ports_;
  std::vector<uint8_t> in_buffer_;
  size_t in_begin_ = 0;
  size_t in_end_ = 0;
  std::string last_error_;
};

}  // namespace hal
}  // namespace fdsurf
