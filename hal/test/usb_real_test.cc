// SPDX-License-Identifier: MIT
// UsbTransport against the real libusb (no --wrap): a VID:PID that no device
// has. Without USB access (a container without /dev/bus/usb) libusb may
// refuse to start; either way the message must say what happened.
#include <gtest/gtest.h>

#include <memory>
#include <regex>
#include <string>

#include "fdsurf/hal/usb_transport.h"

namespace fdsurf::hal {
namespace {

TEST(UsbReal, AbsentDeviceIsNotFoundOrLibusbSaysWhyItCannotLook) {
  UsbSelector selector;
  std::string error;
  // 1209:fff7 is unassigned at pid.codes (checked 2026); no real device answers to it.
  ASSERT_TRUE(ParseUsbDevice("usb:1209:fff7", &selector, &error)) << error;
  std::unique_ptr<UsbTransport> transport;
  const IoStatus status = UsbTransport::Open(selector, UsbOptions(), &transport, &error);
  EXPECT_EQ(transport, nullptr);
  if (status == IoStatus::kNotFound) {
    EXPECT_TRUE(std::regex_match(
        error, std::regex(R"(usb 1209:fff7: no such device \(\d+ USB devices seen\))")))
        << error;
  } else {
    EXPECT_EQ(status, IoStatus::kIoError) << error;
    EXPECT_TRUE(std::regex_match(
        error,
        std::regex(
            R"(usb 1209:fff7: cannot initialise libusb: LIBUSB_ERROR_\w+ \(no USB access here: is /dev/bus/usb present\? a container needs it passed in\))")))
        << error;
  }
}

}  // namespace
}  // namespace fdsurf::hal
