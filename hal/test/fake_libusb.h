// SPDX-License-Identifier: MIT
// A fake libusb-1.0 for tests linked with -Wl,--wrap=<each libusb function the
// backend calls> (libusb_error_name stays real): a list of devices that can
// be unplugged and replugged elsewhere, and scripted bulk transfers.
#pragma once

#include <libusb-1.0/libusb.h>
#include <stdint.h>

#include <deque>
#include <list>
#include <string>
#include <vector>

namespace fdsurf::hal::testing {

struct FakeEndpoint {
  uint8_t address;
  uint8_t attributes;
};

struct FakeUsbDevice {
  /// 1209:0001 at 1-1.4, address 7, bulk OUT 0x01 and bulk IN 0x81 (defined
  /// out of line: GCC 12 -O2 warns wrongly on vector initializer lists here).
  FakeUsbDevice();

  uint16_t vendor_id = 0x1209;
  uint16_t product_id = 0x0001;
  uint8_t bus = 1;
  std::vector<uint8_t> ports;
  uint8_t address = 7;
  std::string serial;  // "": no serial number string
  uint8_t interface_number = 0;
  uint8_t interface_class = LIBUSB_CLASS_VENDOR_SPEC;
  /// Endpoint addresses and transfer types (bmAttributes) of the interface.
  std::vector<FakeEndpoint> endpoints;
  int open_rc = 0;   // what libusb_open returns
  int claim_rc = 0;  // what libusb_claim_interface returns
  bool present = true;
};

/// One scripted libusb_bulk_transfer: its return code, how many bytes it
/// moved, and for IN transfers the bytes.
struct FakeTransfer {
  int rc = 0;
  int transferred = 0;
  std::vector<uint8_t> in_data;
};

struct FakeUsb {
  int init_rc = 0;
  /// std::list: stable addresses, as libusb_device pointers point at them.
  std::list<FakeUsbDevice> devices;
  /// Transfers per direction, consumed in order; an empty queue times out.
  std::deque<FakeTransfer> out_script;
  std::deque<FakeTransfer> in_script;
  /// Bytes the OUT transfers moved, in order.
  std::vector<uint8_t> written;
  /// Calls that change state: "init", "list 2", "open 1-1.4", "detach 1",
  /// "claim 0 on 1-1.4", "out 64", "in 16384", "release 0", "close 1-1.4", "exit".
  std::vector<std::string> log;
  /// The timeout of each bulk transfer, in ms.
  std::vector<unsigned> timeouts_ms;
  /// Devices that become present when the device list has been fetched this
  /// many more times (for Reconnect polling), then the count is cleared.
  int lists_until_replug = -1;
  FakeUsbDevice* replug = nullptr;
  int open_handles = 0;
};

extern FakeUsb* g_fake_usb;

}  // namespace fdsurf::hal::testing
