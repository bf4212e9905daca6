// SPDX-License-Identifier: MIT
// UsbTransport against a fake libusb (fake_libusb.cc, linked with -Wl,--wrap):
// device selection, exact error messages, the order of libusb calls, the
// timeout handed to each transfer, and a device that disappears mid-transfer
// and comes back elsewhere with its serial number. A missing device, short
// OUT transfers, zero-length packets, stalls, timeouts and an unplug are also
// tested through the real libusb against umockdev (umockdev_usb_test.cc).
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "fake_libusb.h"
#include "fdsurf/hal/usb_transport.h"

namespace fdsurf::hal {
namespace {

using testing::FakeTransfer;
using testing::FakeUsb;
using testing::FakeUsbDevice;
using Log = std::vector<std::string>;
using Bytes = std::vector<uint8_t>;

class UsbTest : public ::testing::Test {
 protected:
  UsbTest() {
    testing::g_fake_usb = &fake_;
    FakeUsbDevice mouse;
    mouse.vendor_id = 0x046d;
    mouse.product_id = 0xc52b;
    mouse.ports = {2};
    mouse.address = 3;
    mouse.interface_class = LIBUSB_CLASS_HID;
    fake_.devices.push_back(mouse);
    FakeUsbDevice plotter;
    plotter.serial = "FD0042";
    fake_.devices.push_back(plotter);
    plotter_ = &fake_.devices.back();
  }
  ~UsbTest() override {
    EXPECT_EQ(fake_.open_handles, 0);
    testing::g_fake_usb = nullptr;
  }

  IoStatus Open(const std::string& spec, std::unique_ptr<UsbTransport>* transport,
                std::string* error, UsbOptions options = {}) {
    UsbSelector selector;
    EXPECT_TRUE(ParseUsbDevice(spec, &selector, error)) << *error;
    options.reconnect_poll_ms = 1;
    return UsbTransport::Open(selector, options, transport, error);
  }

  std::unique_ptr<UsbTransport> OpenOk(const std::string& spec = "usb") {
    std::unique_ptr<UsbTransport> transport;
    std::string error;
    EXPECT_EQ(Open(spec, &transport, &error), IoStatus::kOk) << error;
    fake_.log.clear();
    return transport;
  }

  FakeUsb fake_;
  FakeUsbDevice* plotter_;
};

TEST_F(UsbTest, OpensTheMatchingDeviceAndClaimsItsInterface) {
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  ASSERT_EQ(Open("usb:1209:0001", &transport, &error), IoStatus::kOk) << error;
  EXPECT_EQ(fake_.log, (Log{"init", "list 2", "open 1-1.4", "detach 1", "claim 0 on 1-1.4"}));
  EXPECT_EQ(transport->vendor_id(), 0x1209);
  EXPECT_EQ(transport->product_id(), 0x0001);
  EXPECT_EQ(transport->serial(), "FD0042");
  EXPECT_EQ(transport->port_path(), "1-1.4");
  EXPECT_TRUE(transport->connected());
  EXPECT_STREQ(transport->LastError(), "");
  fake_.log.clear();
  transport.reset();
  EXPECT_EQ(fake_.log, (Log{"release 0", "close 1-1.4", "exit"}));
}

TEST_F(UsbTest, OpensByPortPath) {
  FakeUsbDevice twin = *plotter_;
  twin.ports = {1, 3};
  twin.serial = "";
  fake_.devices.push_front(twin);
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  ASSERT_EQ(Open("usb:1-1.4", &transport, &error), IoStatus::kOk) << error;
  EXPECT_EQ(transport->serial(), "FD0042");
  ASSERT_EQ(Open("usb", &transport, &error), IoStatus::kOk) << error;
  EXPECT_EQ(transport->port_path(), "1-1.3");  // the first match by VID:PID
}

TEST_F(UsbTest, PermissionDeniedSuggestsAUdevRule) {
  plotter_->open_rc = LIBUSB_ERROR_ACCESS;
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kPermissionDenied);
  EXPECT_EQ(error,
            "usb 1209:0001: permission denied opening /dev/bus/usb/001/007 (add a udev rule: "
            "SUBSYSTEM==\"usb\", ATTR{idVendor}==\"1209\", ATTR{idProduct}==\"0001\", "
            "MODE=\"0660\", TAG+=\"uaccess\"; see hal/README.md)");
}

TEST_F(UsbTest, OtherOpenErrorsNameLibusbsError) {
  plotter_->open_rc = LIBUSB_ERROR_NO_MEM;
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kIoError);
  EXPECT_EQ(error, "usb 1209:0001: cannot open /dev/bus/usb/001/007: LIBUSB_ERROR_NO_MEM");
}

TEST_F(UsbTest, BusyInterface) {
  plotter_->claim_rc = LIBUSB_ERROR_BUSY;
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb:1-1.4", &transport, &error), IoStatus::kBusy);
  EXPECT_EQ(error, "usb 1-1.4: interface 0 busy (claimed by another program)");
  EXPECT_EQ(fake_.log, (Log{"init", "list 2", "open 1-1.4", "detach 1", "claim 0 on 1-1.4",
                            "close 1-1.4", "exit"}));
}

TEST_F(UsbTest, ClaimPermissionAndOtherErrors) {
  plotter_->claim_rc = LIBUSB_ERROR_ACCESS;
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kPermissionDenied);
  EXPECT_EQ(error, "usb 1209:0001: permission denied claiming interface 0");
  plotter_->claim_rc = LIBUSB_ERROR_OTHER;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kIoError);
  EXPECT_EQ(error, "usb 1209:0001: cannot claim interface 0: LIBUSB_ERROR_OTHER");
}

TEST_F(UsbTest, InterfaceMustExistBeVendorSpecificAndHaveBothBulkEndpoints) {
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  UsbOptions options;
  options.interface_number = 1;
  EXPECT_EQ(Open("usb", &transport, &error, options), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1209:0001: no interface 1 (the device has 1 interface)");

  plotter_->interface_class = LIBUSB_CLASS_COMM;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1209:0001: interface 0 is class 0x02, not vendor-specific (0xff)");

  plotter_->interface_class = LIBUSB_CLASS_VENDOR_SPEC;
  plotter_->endpoints = {{0x01, LIBUSB_TRANSFER_TYPE_BULK}, {0x82, LIBUSB_TRANSFER_TYPE_INTERRUPT}};
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1209:0001: interface 0 has no bulk IN endpoint");

  plotter_->endpoints = {{0x81, LIBUSB_TRANSFER_TYPE_BULK}};
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1209:0001: interface 0 has no bulk OUT endpoint");
  EXPECT_EQ(transport, nullptr);
}

TEST_F(UsbTest, LibusbThatCannotStartSaysSo) {
  fake_.init_rc = LIBUSB_ERROR_OTHER;
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kIoError);
  EXPECT_EQ(error,
            "usb 1209:0001: cannot initialise libusb: LIBUSB_ERROR_OTHER (no USB access here: is "
            "/dev/bus/usb present? a container needs it passed in)");
}

TEST_F(UsbTest, WriteTimeoutReportsHowMuchWentOut) {
  auto transport = OpenOk();
  fake_.out_script = {{LIBUSB_ERROR_TIMEOUT, 37, {}}};
  const Bytes data(64, 0xaa);
  EXPECT_EQ(transport->Write(data.data(), data.size(), 100), IoStatus::kTimeout);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: write timed out after 37 of 64 bytes (100 ms)");
  EXPECT_EQ(fake_.written, Bytes(37, 0xaa));
  EXPECT_EQ(fake_.log, (Log{"out 64"}));
  ASSERT_EQ(fake_.timeouts_ms.size(), 1u);
  EXPECT_LE(fake_.timeouts_ms[0], 100u);
  EXPECT_GE(fake_.timeouts_ms[0], 50u);  // the remaining time, not a fresh full timeout per call
  EXPECT_TRUE(transport->connected());   // a timeout is not a disconnect
}

TEST_F(UsbTest, ZeroTimeoutIsOneMillisecondNotForever) {
  auto transport = OpenOk();
  const Bytes data(4, 1);
  EXPECT_EQ(transport->Write(data.data(), data.size(), 0), IoStatus::kTimeout);
  EXPECT_EQ(fake_.log, (Log{"out 4"}));
  EXPECT_EQ(fake_.timeouts_ms, (std::vector<unsigned>{1}));
}

TEST_F(UsbTest, ReadReturnsWhatArrivedAndKeepsTheRest) {
  auto transport = OpenOk();
  Bytes buffer(3);
  size_t received = 99;
  EXPECT_EQ(transport->Read(buffer.data(), buffer.size(), &received, 50), IoStatus::kTimeout);
  EXPECT_EQ(received, 0u);
  EXPECT_STREQ(transport->LastError(), "usb 1209:0001: nothing received within 50 ms");

  // Bytes that arrived before a timeout are data; a 3-byte read takes them in turn.
  fake_.in_script = {{LIBUSB_ERROR_TIMEOUT, 0, {1, 2, 3, 4, 5}}};
  fake_.log.clear();
  ASSERT_EQ(transport->Read(buffer.data(), buffer.size(), &received, 50), IoStatus::kOk);
  EXPECT_EQ(received, 3u);
  EXPECT_EQ(buffer, (Bytes{1, 2, 3}));
  ASSERT_EQ(transport->Read(buffer.data(), buffer.size(), &received, 50), IoStatus::kOk);
  EXPECT_EQ(received, 2u);
  EXPECT_EQ(buffer[0], 4);
  EXPECT_EQ(buffer[1], 5);
  EXPECT_EQ(fake_.log, (Log{"in 16384"}));  // one transfer of whole packets served both reads
}

TEST_F(UsbTest, TransferErrorsThatAreNotUnplugs) {
  auto transport = OpenOk();
  fake_.in_script = {{LIBUSB_ERROR_PIPE, 0, {}}};
  uint8_t byte = 0;
  size_t received = 0;
  EXPECT_EQ(transport->Read(&byte, 1, &received, 10), IoStatus::kIoError);
  EXPECT_STREQ(transport->LastError(), "usb 1209:0001: read failed: LIBUSB_ERROR_PIPE");
  fake_.out_script = {{LIBUSB_ERROR_OVERFLOW, 2, {}}};
  EXPECT_EQ(transport->Write(&byte, 1, 10), IoStatus::kIoError);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: write failed: LIBUSB_ERROR_OVERFLOW after 1 of 1 bytes");
  EXPECT_TRUE(transport->connected());
}

TEST_F(UsbTest, UnplugMidTransferThenReconnectFindsTheSameSerialElsewhere) {
  auto transport = OpenOk();
  // The device vanishes during a write after 10 of 32 bytes.
  fake_.out_script = {{LIBUSB_ERROR_NO_DEVICE, 10, {}}};
  plotter_->present = false;
  const Bytes data(32, 7);
  EXPECT_EQ(transport->Write(data.data(), data.size(), 100), IoStatus::kDisconnected);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: disconnected (LIBUSB_ERROR_NO_DEVICE) during write after 10 of 32 "
               "bytes; call Reconnect()");
  EXPECT_EQ(fake_.log, (Log{"out 32", "release 0", "close 1-1.4"}));
  EXPECT_FALSE(transport->connected());
  uint8_t byte = 0;
  size_t received = 0;
  EXPECT_EQ(transport->Read(&byte, 1, &received, 10), IoStatus::kDisconnected);
  EXPECT_STREQ(transport->LastError(), "usb 1209:0001: disconnected; call Reconnect()");

  // Not back yet.
  EXPECT_EQ(transport->Reconnect(0), IoStatus::kTimeout);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001 serial FD0042: no such device (1 USB devices seen); not back "
               "within 0 ms");

  // Back on another port and address, behind an impostor with the same VID:PID.
  FakeUsbDevice impostor = *plotter_;
  impostor.serial = "OTHER";
  impostor.ports = {1, 2};
  impostor.present = true;
  fake_.devices.push_front(impostor);
  plotter_->ports = {1, 3};
  plotter_->address = 12;
  fake_.replug = plotter_;
  fake_.lists_until_replug = 2;  // appears at the third enumeration
  fake_.log.clear();
  ASSERT_EQ(transport->Reconnect(5000), IoStatus::kOk) << transport->LastError();
  // Each attempt enumerates in a new libusb context (a fresh look at sysfs:
  // without udevd libusb's list never changes; tests/kernel/).
  EXPECT_EQ(fake_.log,
            (Log{"init", "exit", "list 2", "open 1-1.2", "close 1-1.2", "init", "exit", "list 2",
                 "open 1-1.2", "close 1-1.2", "init", "exit", "list 3", "open 1-1.2", "close 1-1.2",
                 "open 1-1.3", "detach 1", "claim 0 on 1-1.3"}));
  EXPECT_EQ(transport->port_path(), "1-1.3");
  EXPECT_EQ(transport->Reconnect(0), IoStatus::kOk);  // already up

  fake_.out_script = {{0, 32, {}}};
  fake_.written.clear();
  ASSERT_EQ(transport->Write(data.data(), data.size(), 100), IoStatus::kOk);
  EXPECT_EQ(fake_.written, data);
}

TEST_F(UsbTest, WithoutSerialReconnectWantsTheSamePort) {
  plotter_->serial = "";
  auto transport = OpenOk();
  fake_.in_script = {{LIBUSB_ERROR_IO, 0, {}}};
  uint8_t byte = 0;
  size_t received = 0;
  EXPECT_EQ(transport->Read(&byte, 1, &received, 10), IoStatus::kDisconnected);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: disconnected (LIBUSB_ERROR_IO) during read; call Reconnect()");

  plotter_->ports = {1, 3};  // the same model on another port is another device
  EXPECT_EQ(transport->Reconnect(20), IoStatus::kTimeout);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001 at 1-1.4: no such device (2 USB devices seen); not back within 20 "
               "ms");
  plotter_->ports = {1, 4};
  EXPECT_EQ(transport->Reconnect(20), IoStatus::kOk);
}

TEST_F(UsbTest, ReconnectReportsADeviceThatCameBackButCannotBeOpened) {
  auto transport = OpenOk();
  fake_.in_script = {{LIBUSB_ERROR_NO_DEVICE, 0, {}}};
  uint8_t byte = 0;
  size_t received = 0;
  ASSERT_EQ(transport->Read(&byte, 1, &received, 10), IoStatus::kDisconnected);
  plotter_->claim_rc = LIBUSB_ERROR_BUSY;
  EXPECT_EQ(transport->Reconnect(5), IoStatus::kBusy);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: interface 0 busy (claimed by another program)");
}

TEST(ParseUsbDevice, AcceptsTheDocumentedForms) {
  UsbSelector selector;
  std::string error;
  ASSERT_TRUE(ParseUsbDevice("usb", &selector, &error));
  EXPECT_EQ(selector.ToString(), "1209:0001");
  EXPECT_FALSE(selector.by_port());
  ASSERT_TRUE(ParseUsbDevice("usb:CAFE:4011", &selector, &error));
  EXPECT_EQ(selector.vendor_id, 0xcafe);
  EXPECT_EQ(selector.product_id, 0x4011);
  EXPECT_EQ(selector.ToString(), "cafe:4011");
  ASSERT_TRUE(ParseUsbDevice("usb:3-1.4.2", &selector, &error));
  EXPECT_EQ(selector.bus, 3);
  EXPECT_EQ(selector.ports, (std::vector<uint8_t>{1, 4, 2}));
  EXPECT_EQ(selector.ToString(), "3-1.4.2");
  ASSERT_TRUE(ParseUsbDevice("usb:1-2", &selector, &error));
  EXPECT_EQ(selector.ToString(), "1-2");
}

TEST(ParseUsbDevice, ExplainsEveryMistake) {
  const std::string usage =
      "; expected usb, usb:VID:PID (hexadecimal, e.g. usb:1209:0001) or usb:BUS-PORT[.PORT...] "
      "(e.g. usb:1-1.4)";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"serial:/dev/ttyACM0", "usb device 'serial:/dev/ttyACM0' must start with 'usb'"},
      {"usbx", "usb device 'usbx' must start with 'usb'"},
      {"usb:12x9:0001",
       "usb device 'usb:12x9:0001': VID '12x9' is not a hexadecimal number of 1 to 4 digits"},
      {"usb:1209:10000",
       "usb device 'usb:1209:10000': PID '10000' is not a hexadecimal number of 1 to 4 digits"},
      {"usb:1209:", "usb device 'usb:1209:': PID '' is not a hexadecimal number of 1 to 4 digits"},
      {"usb:1209", "usb device 'usb:1209' is neither VID:PID nor BUS-PORT"},
      {"usb:0-1", "usb device 'usb:0-1': bus '0' is not a number from 1 to 255"},
      {"usb:1-", "usb device 'usb:1-': port '' is not a number from 1 to 255"},
      {"usb:1-1..2", "usb device 'usb:1-1..2': port '' is not a number from 1 to 255"},
      {"usb:1-256", "usb device 'usb:1-256': port '256' is not a number from 1 to 255"},
      {"usb:1-1.2.3.4.5.6.7.8",
       "usb device 'usb:1-1.2.3.4.5.6.7.8': 8 ports deep; USB allows at most 7"},
  };
  for (const auto& [spec, message] : cases) {
    UsbSelector selector;
    selector.vendor_id = 0xbeef;
    std::string error;
    EXPECT_FALSE(ParseUsbDevice(spec, &selector, &error)) << spec;
    EXPECT_EQ(error, message + usage) << spec;
    EXPECT_EQ(selector.vendor_id, 0xbeef) << spec;  // untouched on failure
  }
}

}  // namespace
}  // namespace fdsurf::hal
