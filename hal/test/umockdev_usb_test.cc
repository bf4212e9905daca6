// SPDX-License-Identifier: MIT
// UsbTransport through the REAL libusb against a device emulated by umockdev:
// libusb enumerates a mock sysfs (descriptors, busnum, devnum) through
// libudev and talks usbdevfs ioctls (SUBMITURB, REAPURBNDELAY, DISCARDURB,
// CLAIMINTERFACE, ...) to /dev/bus/usb/001/004, which umockdev's preload
// library hands to the handler below. Run under umockdev-wrapper (CTest does).
//
// The handler answers as the Linux usbfs driver does (drivers/usb/core/devio.c):
// a stalled endpoint completes the URB with status -EPIPE, a discarded URB
// with -ENOENT and what it had moved so far, a device that goes away
// completes its URBs with -ESHUTDOWN and every later ioctl fails with ENODEV.
// libusb maps these (libusb/os/linux_usbfs.c) to LIBUSB_ERROR_PIPE,
// LIBUSB_ERROR_TIMEOUT, LIBUSB_ERROR_NO_DEVICE. Facts about umockdev's ioctl
// API were read from libusb's own tests/umockdev.c (no code taken).
#include <gtest/gtest.h>
#include <sys/ioctl.h>  // before linux/usbdevice_fs.h: its ioctl numbers use _IOW

#include <linux/usbdevice_fs.h>
#include <umockdev.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "fdsurf/hal/usb_transport.h"

namespace fdsurf::hal {
namespace {

using Bytes = std::vector<uint8_t>;

constexpr const char* kNode = "/dev/bus/usb/001/004";
constexpr const char* kSysPath = "/sys/devices/usb1/1-4";

// What a scripted URB does when libusb reaps it.
struct Completion {
  int status = 0;      // 0 or a negative errno, as usbfs puts in urb->status
  size_t moved = 0;    // OUT: bytes the device took; IN: ignored (data.size())
  Bytes data;          // IN: the bytes the device sends
  bool never = false;  // never completes: only a discard (timeout) ends it
};

// The emulated device's side of usbdevfs, shared with umockdev's thread.
class EmulatedDevice {
 public:
  EmulatedDevice() : handler_(umockdev_ioctl_base_new()) {
    g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(&EmulatedDevice::OnIoctl), this);
  }
  ~EmulatedDevice() {
    for (UMockdevIoctlData* urb : flying_) umockdev_ioctl_data_unref(urb);
    g_object_unref(handler_);
  }
  EmulatedDevice(const EmulatedDevice&) = delete;
  EmulatedDevice& operator=(const EmulatedDevice&) = delete;

  UMockdevIoctlBase* handler() { return handler_; }

  void Script(uint8_t endpoint, Completion completion) {
    std::lock_guard<std::mutex> lock(mutex_);
    (endpoint & 0x80 ? in_ : out_).push_back(std::move(completion));
  }
  void SetClaimErrno(int error) {
    std::lock_guard<std::mutex> lock(mutex_);
    claim_errno_ = error;
  }
  void SetPresent(bool present) {
    std::lock_guard<std::mutex> lock(mutex_);
    present_ = present;
  }
  Bytes written() {
    std::lock_guard<std::mutex> lock(mutex_);
    return written_;
  }
  // Blocks until an IN URB is in flight (the host is waiting in a read).
  void WaitForInUrb() {
    std::unique_lock<std::mutex> lock(mutex_);
    in_submitted_.wait(lock, [&] { return in_urbs_ > 0; });
  }

 private:
  static gboolean OnIoctl(UMockdevIoctlBase* /*base*/, UMockdevIoctlClient* client, gpointer self) {
    return static_cast<EmulatedDevice*>(self)->Handle(client) ? TRUE : FALSE;
  }

  bool Handle(UMockdevIoctlClient* client) {
    std::lock_guard<std::mutex> lock(mutex_);
    const unsigned long request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    if (!present_) {
      const bool reap = request == USBDEVFS_REAPURB || request == USBDEVFS_REAPURBNDELAY;
      if (reap && !flying_.empty()) {
        // What was in flight comes back with -ESHUTDOWN, as the host
        // controller driver flushes the endpoints of a departed device.
        UMockdevIoctlData* urb_data = flying_.front();
        flying_.erase(flying_.begin());
        reinterpret_cast<usbdevfs_urb*>(urb_data->data)->status = -ESHUTDOWN;
        GiveBack(client, arg, urb_data);
        return true;
      }
      umockdev_ioctl_client_complete(client, -1, ENODEV);
      return true;
    }
    switch (request) {
      case USBDEVFS_GET_CAPABILITIES: {
        UMockdevIoctlData* caps = umockdev_ioctl_data_resolve(arg, 0, sizeof(uint32_t), nullptr);
        const uint32_t value = USBDEVFS_CAP_BULK_SCATTER_GATHER | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                               USBDEVFS_CAP_REAP_AFTER_DISCONNECT;
        std::memcpy(caps->data, &value, sizeof value);
        umockdev_ioctl_data_unref(caps);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      }
      case USBDEVFS_GETDRIVER:  // no kernel driver bound
        umockdev_ioctl_client_complete(client, -1, ENODATA);
        return true;
      // libusb's auto-detach claims with DISCONNECT_CLAIM (detach a kernel
      // driver and claim in one ioctl); no driver is bound here.
      case USBDEVFS_DISCONNECT_CLAIM:
      case USBDEVFS_CLAIMINTERFACE:
        umockdev_ioctl_client_complete(client, claim_errno_ != 0 ? -1 : 0, claim_errno_);
        return true;
      case USBDEVFS_RELEASEINTERFACE:
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      case USBDEVFS_SUBMITURB:
        return Submit(client, arg);
      case USBDEVFS_REAPURB:
      case USBDEVFS_REAPURBNDELAY:
        return Reap(client, arg);
      case USBDEVFS_DISCARDURB:
        return Discard(client, arg);
      default:
        return false;  // umockdev answers ENOTTY
    }
  }

  bool Submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    UMockdevIoctlData* urb_data =
        umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
    auto* urb = reinterpret_cast<usbdevfs_urb*>(urb_data->data);
    if (urb->type != USBDEVFS_URB_TYPE_BULK) {
      umockdev_ioctl_data_unref(urb_data);
      return false;
    }
    // Map the buffer now so that Reap can read and fill it.
    UMockdevIoctlData* buffer =
        umockdev_ioctl_data_resolve(urb_data, G_STRUCT_OFFSET(usbdevfs_urb, buffer),
                                    static_cast<gsize>(urb->buffer_length), nullptr);
    umockdev_ioctl_data_unref(buffer);
    flying_.push_back(urb_data);
    if ((urb->endpoint & 0x80) != 0) {
      ++in_urbs_;
      in_submitted_.notify_all();
    }
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  // Hands back the URB `urb_data` (taking its reference) with `status`.
  static void GiveBack(UMockdevIoctlClient* client, UMockdevIoctlData* arg,
                       UMockdevIoctlData* urb_data) {
    UMockdevIoctlData* pointer = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
    umockdev_ioctl_data_set_ptr(pointer, 0, urb_data);
    umockdev_ioctl_data_unref(pointer);
    umockdev_ioctl_data_unref(urb_data);
    umockdev_ioctl_client_complete(client, 0, 0);
  }

  bool Reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    if (!discarded_.empty()) {
      UMockdevIoctlData* urb_data = discarded_.front();
      discarded_.pop_front();
      reinterpret_cast<usbdevfs_urb*>(urb_data->data)->status = -ENOENT;
      GiveBack(client, arg, urb_data);
      return true;
    }
    for (auto it = flying_.begin(); it != flying_.end(); ++it) {
      auto* urb = reinterpret_cast<usbdevfs_urb*>((*it)->data);
      std::deque<Completion>& script = (urb->endpoint & 0x80) != 0 ? in_ : out_;
      if (script.empty() || script.front().never) continue;
      Complete(urb, script.front());
      script.pop_front();
      UMockdevIoctlData* urb_data = *it;
      flying_.erase(it);
      GiveBack(client, arg, urb_data);
      return true;
    }
    umockdev_ioctl_client_complete(client, -1, EAGAIN);
    return true;
  }

  // Fills `urb` as the device's answer `completion` would.
  void Complete(usbdevfs_urb* urb, const Completion& completion) {
    auto* buffer = static_cast<uint8_t*>(urb->buffer);
    if ((urb->endpoint & 0x80) != 0) {
      const size_t count = std::min(completion.data.size(), size_t(urb->buffer_length));
      std::copy_n(completion.data.begin(), count, buffer);
      urb->actual_length = static_cast<int>(count);
    } else {
      const size_t count = std::min(completion.moved, size_t(urb->buffer_length));
      written_.insert(written_.end(), buffer, buffer + count);
      urb->actual_length = static_cast<int>(count);
    }
    urb->status = completion.status;
  }

  bool Discard(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    const auto address = reinterpret_cast<gulong>(*reinterpret_cast<void**>(arg->data));
    for (auto it = flying_.begin(); it != flying_.end(); ++it) {
      if ((*it)->client_addr != address) continue;
      auto* urb = reinterpret_cast<usbdevfs_urb*>((*it)->data);
      std::deque<Completion>& script = (urb->endpoint & 0x80) != 0 ? in_ : out_;
      urb->actual_length = 0;
      if (!script.empty() && script.front().never) {
        // What a never-ending transfer moved before the host gave up.
        Completion partial = script.front();
        script.pop_front();
        Complete(urb, partial);
      }
      discarded_.push_back(*it);
      flying_.erase(it);
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    }
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return true;
  }

  UMockdevIoctlBase* handler_;
  std::mutex mutex_;
  std::condition_variable in_submitted_;
  std::deque<Completion> in_;
  std::deque<Completion> out_;
  std::vector<UMockdevIoctlData*> flying_;
  std::deque<UMockdevIoctlData*> discarded_;
  Bytes written_;
  int claim_errno_ = 0;
  int in_urbs_ = 0;
  bool present_ = true;
};

// Device, configuration, interface and endpoint descriptors (USB 2.0 spec
// §9.6) of a 1209:0001 with one vendor interface, bulk OUT 0x01 and IN 0x81.
std::string DescriptorsHex(uint8_t interface_class) {
  const Bytes bytes = {
      18,   1,    0x00, 0x02, 0,    0,
      0,    64,   0x09, 0x12, 0x01, 0x00,
      0x00, 0x01, 0,    0,    0,    1,  // device
      9,    2,    32,   0,    1,    1,
      0,    0x80, 50,  // configuration, 32 bytes in all
      9,    4,    0,    0,    2,    interface_class,
      0,    0,    0,  // interface 0
      7,    5,    0x01, 0x02, 0x00, 0x02,
      0,  // bulk OUT, 512 bytes
      7,    5,    0x81, 0x02, 0x00, 0x02,
      0,  // bulk IN, 512 bytes
  };
  std::string hex;
  for (const uint8_t byte : bytes) {
    char text[3];
    std::snprintf(text, sizeof text, "%02x", byte);
    hex += text;
  }
  return hex;
}

class UmockdevUsbTest : public ::testing::Test {
 protected:
  UmockdevUsbTest() : testbed_(umockdev_testbed_new()) {}
  ~UmockdevUsbTest() override { g_object_unref(testbed_); }

  // Adds the plotter at bus 1 port 4 (address 4), as the kernel would list it.
  void Plug(uint8_t interface_class = 0xff) {
    GError* error = nullptr;
    if (!attached_) {  // before the device appears, so that opening it works at once
      ASSERT_TRUE(umockdev_testbed_attach_ioctl(testbed_, kNode, device_.handler(), &error))
          << (error != nullptr ? error->message : "");
      attached_ = true;
    }
    const std::string record = std::string("P: /devices/usb1/1-4\nN: bus/usb/001/004\n") +
                               "E: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\n"
                               "E: BUSNUM=001\nE: DEVNUM=004\nE: DEVNAME=" +
                               kNode + "\n" + "A: busnum=1\\n\nA: devnum=4\\n\nA: speed=480\\n\n" +
                               "A: bConfigurationValue=1\\n\n" +
                               "H: descriptors=" + DescriptorsHex(interface_class) + "\n";
    ASSERT_TRUE(umockdev_testbed_add_from_string(testbed_, record.c_str(), &error))
        << (error != nullptr ? error->message : "");
    device_.SetPresent(true);
  }

  void Unplug() {
    device_.SetPresent(false);
    umockdev_testbed_uevent(testbed_, kSysPath, "remove");
    umockdev_testbed_remove_device(testbed_, kSysPath);
  }

  IoStatus Open(const std::string& spec, std::unique_ptr<UsbTransport>* transport,
                std::string* error) {
    UsbSelector selector;
    EXPECT_TRUE(ParseUsbDevice(spec, &selector, error)) << *error;
    UsbOptions options;
    options.reconnect_poll_ms = 5;
    return UsbTransport::Open(selector, options, transport, error);
  }

  std::unique_ptr<UsbTransport> OpenOk() {
    std::unique_ptr<UsbTransport> transport;
    std::string error;
    EXPECT_EQ(Open("usb:1209:0001", &transport, &error), IoStatus::kOk) << error;
    return transport;
  }

  UMockdevTestbed* testbed_;
  EmulatedDevice device_;
  bool attached_ = false;
};

TEST_F(UmockdevUsbTest, EnumeratesOpensAndClaimsThroughRealLibusb) {
  Plug();
  auto transport = OpenOk();
  ASSERT_NE(transport, nullptr);
  EXPECT_EQ(transport->vendor_id(), 0x1209);
  EXPECT_EQ(transport->port_path(), "1-4");
  EXPECT_EQ(transport->serial(), "");
}

TEST_F(UmockdevUsbTest, MissingDeviceIsNotFound) {
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb:1209:0001", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1209:0001: no such device (0 USB devices seen)");
  Plug();
  EXPECT_EQ(Open("usb:cafe:4011", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb cafe:4011: no such device (1 USB devices seen)");
  EXPECT_EQ(Open("usb:1-3", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1-3: no such device (1 USB devices seen)");
  EXPECT_EQ(transport, nullptr);
}

TEST_F(UmockdevUsbTest, InterfaceMustBeVendorSpecific) {
  Plug(0x02);
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb:1-4", &transport, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "usb 1-4: interface 0 is class 0x02, not vendor-specific (0xff)");
}

TEST_F(UmockdevUsbTest, ClaimRefusedWithEbusyIsBusy) {
  Plug();
  device_.SetClaimErrno(EBUSY);
  std::unique_ptr<UsbTransport> transport;
  std::string error;
  EXPECT_EQ(Open("usb", &transport, &error), IoStatus::kBusy);
  EXPECT_EQ(error, "usb 1209:0001: interface 0 busy (claimed by another program)");
}

TEST_F(UmockdevUsbTest, ShortOutTransfersAreContinued) {
  Plug();
  auto transport = OpenOk();
  device_.Script(0x01, {0, 20, {}, false});
  device_.Script(0x01, {0, 44, {}, false});
  Bytes data(64);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i);
  ASSERT_EQ(transport->Write(data.data(), data.size(), 1000), IoStatus::kOk)
      << transport->LastError();
  EXPECT_EQ(device_.written(), data);
}

TEST_F(UmockdevUsbTest, StallIsAnIoErrorNotADisconnect) {
  Plug();
  auto transport = OpenOk();
  device_.Script(0x81, {-EPIPE, 0, {}, false});
  uint8_t byte = 0;
  size_t received = 0;
  EXPECT_EQ(transport->Read(&byte, 1, &received, 1000), IoStatus::kIoError);
  EXPECT_STREQ(transport->LastError(), "usb 1209:0001: read failed: LIBUSB_ERROR_PIPE");
  device_.Script(0x01, {-EPIPE, 0, {}, false});
  EXPECT_EQ(transport->Write(&byte, 1, 1000), IoStatus::kIoError);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: write failed: LIBUSB_ERROR_PIPE after 0 of 1 bytes");
  EXPECT_TRUE(transport->connected());
  // The endpoint works again afterwards.
  device_.Script(0x81, {0, 0, {42}, false});
  ASSERT_EQ(transport->Read(&byte, 1, &received, 1000), IoStatus::kOk);
  EXPECT_EQ(byte, 42);
}

TEST_F(UmockdevUsbTest, TimeoutsKeepWhatMovedAndSkipZeroLengthPackets) {
  Plug();
  auto transport = OpenOk();
  // The device takes 37 bytes, then nothing: libusb discards the URB at the
  // deadline and usbfs reports what it had moved.
  device_.Script(0x01, {0, 37, {}, true});
  const Bytes data(64, 0xaa);
  EXPECT_EQ(transport->Write(data.data(), data.size(), 30), IoStatus::kTimeout);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: write timed out after 37 of 64 bytes (30 ms)");
  EXPECT_EQ(device_.written(), Bytes(37, 0xaa));
  EXPECT_TRUE(transport->connected());

  uint8_t buffer[3] = {};
  size_t received = 99;
  EXPECT_EQ(transport->Read(buffer, sizeof buffer, &received, 0), IoStatus::kTimeout);
  EXPECT_EQ(received, 0u);
  EXPECT_STREQ(transport->LastError(), "usb 1209:0001: nothing received within 0 ms");

  device_.Script(0x81, {0, 0, {}, false});  // a zero-length packet
  device_.Script(0x81, {0, 0, {1, 2, 3, 4, 5}, false});
  ASSERT_EQ(transport->Read(buffer, sizeof buffer, &received, 1000), IoStatus::kOk);
  EXPECT_EQ(Bytes(buffer, buffer + received), (Bytes{1, 2, 3}));
  ASSERT_EQ(transport->Read(buffer, sizeof buffer, &received, 1000), IoStatus::kOk);
  EXPECT_EQ(Bytes(buffer, buffer + received), (Bytes{4, 5}));
}

TEST_F(UmockdevUsbTest, DeviceRemovedMidReadDisconnectsThenReconnectFindsItBack) {
  Plug();
  auto transport = OpenOk();
  std::thread unplug([&] {
    device_.WaitForInUrb();
    Unplug();
  });
  uint8_t byte = 0;
  size_t received = 0;
  const IoStatus status = transport->Read(&byte, 1, &received, 5000);
  unplug.join();
  EXPECT_EQ(status, IoStatus::kDisconnected);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001: disconnected (LIBUSB_ERROR_NO_DEVICE) during read; call "
               "Reconnect()");
  EXPECT_FALSE(transport->connected());

  EXPECT_EQ(transport->Reconnect(20), IoStatus::kTimeout);
  EXPECT_STREQ(transport->LastError(),
               "usb 1209:0001 at 1-4: no such device (0 USB devices seen); not back within 20 ms");

  Plug();
  ASSERT_EQ(transport->Reconnect(2000), IoStatus::kOk) << transport->LastError();
  device_.Script(0x81, {0, 0, {7}, false});
  ASSERT_EQ(transport->Read(&byte, 1, &received, 1000), IoStatus::kOk);
  EXPECT_EQ(byte, 7);
}

}  // namespace
}  // namespace fdsurf::hal

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  // umockdev_in_mock_environment() says no under umockdev-wrapper 0.17.16
  // here, so look for the preload library itself.
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload == nullptr || std::strstr(preload, "libumockdev-preload") == nullptr) {
    std::fprintf(stderr, "%s: not under umockdev; run it as: umockdev-wrapper %s (ctest does)\n",
                 argv[0], argv[0]);
    return 2;
  }
  return RUN_ALL_TESTS();
}
