// SPDX-License-Identifier: MIT
#include "fake_libusb.h"

#include <algorithm>
#include <cstring>
#include <string>

namespace fdsurf::hal::testing {

FakeUsb* g_fake_usb = nullptr;

FakeUsbDevice::FakeUsbDevice()
    : ports{1, 4},
      endpoints{{0x01, LIBUSB_TRANSFER_TYPE_BULK}, {0x81, LIBUSB_TRANSFER_TYPE_BULK}} {}

namespace {

struct FakeHandle {
  FakeUsbDevice* device;
};

// Every libusb_config_descriptor handed out, with the storage it points into.
struct FakeConfig {
  libusb_config_descriptor config{};
  libusb_interface interface {};
  libusb_interface_descriptor altsetting{};
  std::vector<libusb_endpoint_descriptor> endpoints;
};

FakeUsbDevice* Device(libusb_device* device) { return reinterpret_cast<FakeUsbDevice*>(device); }
FakeHandle* Handle(libusb_device_handle* handle) { return reinterpret_cast<FakeHandle*>(handle); }

std::string Path(const FakeUsbDevice& device) {
  std::string path = std::to_string(device.bus);
  for (size_t i = 0; i < device.ports.size(); ++i) {
    path += i == 0 ? '-' : '.';
    path += std::to_string(device.ports[i]);
  }
  return path;
}

}  // namespace
}  // namespace fdsurf::hal::testing

using namespace fdsurf::hal::testing;  // the fake's own names

extern "C" {

int __wrap_libusb_init(libusb_context** context) {
  g_fake_usb->log.emplace_back("init");
  if (g_fake_usb->init_rc != 0) return g_fake_usb->init_rc;
  *context = reinterpret_cast<libusb_context*>(g_fake_usb);
  return 0;
}

void __wrap_libusb_exit(libusb_context* /*context*/) { g_fake_usb->log.emplace_back("exit"); }

ssize_t __wrap_libusb_get_device_list(libusb_context* /*context*/, libusb_device*** list) {
  FakeUsb& fake = *g_fake_usb;
  if (fake.lists_until_replug >= 0 && fake.lists_until_replug-- == 0) {
    fake.replug->present = true;
    fake.lists_until_replug = -1;
  }
  std::vector<libusb_device*> present;
  for (FakeUsbDevice& device : fake.devices) {
    if (device.present) present.push_back(reinterpret_cast<libusb_device*>(&device));
  }
  auto* array = new libusb_device*[present.size() + 1];
  std::copy(present.begin(), present.end(), array);
  array[present.size()] = nullptr;
  *list = array;
  fake.log.push_back("list " + std::to_string(present.size()));
  return static_cast<ssize_t>(present.size());
}

void __wrap_libusb_free_device_list(libusb_device** list, int /*unref_devices*/) { delete[] list; }

int __wrap_libusb_get_device_descriptor(libusb_device* device,
                                        libusb_device_descriptor* descriptor) {
  *descriptor = {};
  descriptor->bLength = LIBUSB_DT_DEVICE_SIZE;
  descriptor->bDescriptorType = LIBUSB_DT_DEVICE;
  descriptor->idVendor = Device(device)->vendor_id;
  descriptor->idProduct = Device(device)->product_id;
  descriptor->iSerialNumber = Device(device)->serial.empty() ? 0 : 3;
  descriptor->bNumConfigurations = 1;
  return 0;
}

uint8_t __wrap_libusb_get_bus_number(libusb_device* device) { return Device(device)->bus; }

uint8_t __wrap_libusb_get_device_address(libusb_device* device) { return Device(device)->address; }

int __wrap_libusb_get_port_numbers(libusb_device* device, uint8_t* ports, int length) {
  const std::vector<uint8_t>& path = Device(device)->ports;
  if (static_cast<int>(path.size()) > length) return LIBUSB_ERROR_OVERFLOW;
  std::copy(path.begin(), path.end(), ports);
  return static_cast<int>(path.size());
}

int __wrap_libusb_open(libusb_device* device, libusb_device_handle** handle) {
  g_fake_usb->log.push_back("open " + Path(*Device(device)));
  if (Device(device)->open_rc != 0) return Device(device)->open_rc;
  *handle = reinterpret_cast<libusb_device_handle*>(new FakeHandle{Device(device)});
  ++g_fake_usb->open_handles;
  return 0;
}

void __wrap_libusb_close(libusb_device_handle* handle) {
  g_fake_usb->log.push_back("close " + Path(*Handle(handle)->device));
  delete Handle(handle);
  --g_fake_usb->open_handles;
}

int __wrap_libusb_get_string_descriptor_ascii(libusb_device_handle* handle, uint8_t index,
                                              unsigned char* data, int length) {
  const std::string& serial = Handle(handle)->device->serial;
  if (index != 3 || serial.empty()) return LIBUSB_ERROR_INVALID_PARAM;
  if (!Handle(handle)->device->present) return LIBUSB_ERROR_NO_DEVICE;
  const int count = std::min(length - 1, static_cast<int>(serial.size()));
  std::memcpy(data, serial.data(), static_cast<size_t>(count));
  data[count] = 0;
  return count;
}

int __wrap_libusb_get_active_config_descriptor(libusb_device* device,
                                               libusb_config_descriptor** config) {
  const FakeUsbDevice& fake = *Device(device);
  auto* storage = new FakeConfig;
  for (const auto& [address, attributes] : fake.endpoints) {
    libusb_endpoint_descriptor endpoint{};
    endpoint.bLength = LIBUSB_DT_ENDPOINT_SIZE;
    endpoint.bDescriptorType = LIBUSB_DT_ENDPOINT;
    endpoint.bEndpointAddress = address;
    endpoint.bmAttributes = attributes;
    endpoint.wMaxPacketSize = 64;
    storage->endpoints.push_back(endpoint);
  }
  storage->altsetting.bLength = LIBUSB_DT_INTERFACE_SIZE;
  storage->altsetting.bDescriptorType = LIBUSB_DT_INTERFACE;
  storage->altsetting.bInterfaceNumber = fake.interface_number;
  storage->altsetting.bInterfaceClass = fake.interface_class;
  storage->altsetting.bNumEndpoints = static_cast<uint8_t>(storage->endpoints.size());
  storage->altsetting.endpoint = storage->endpoints.data();
  storage->interface.altsetting = &storage->altsetting;
  storage->interface.num_altsetting = 1;
  storage->config.bLength = LIBUSB_DT_CONFIG_SIZE;
  storage->config.bDescriptorType = LIBUSB_DT_CONFIG;
  storage->config.bNumInterfaces = 1;
  storage->config.interface = &storage->interface;
  // The config is the first member, so its address is the storage's.
  *config = &storage->config;
  return 0;
}

void __wrap_libusb_free_config_descriptor(libusb_config_descriptor* config) {
  delete reinterpret_cast<FakeConfig*>(config);
}

int __wrap_libusb_set_auto_detach_kernel_driver(libusb_device_handle* /*handle*/, int enable) {
  g_fake_usb->log.push_back("detach " + std::to_string(enable));
  return 0;
}

int __wrap_libusb_claim_interface(libusb_device_handle* handle, int interface_number) {
  g_fake_usb->log.push_back("claim " + std::to_string(interface_number) + " on " +
                            Path(*Handle(handle)->device));
  return Handle(handle)->device->claim_rc;
}

int __wrap_libusb_release_interface(libusb_device_handle* handle, int interface_number) {
  g_fake_usb->log.push_back("release " + std::to_string(interface_number));
  return Handle(handle)->device->present ? 0 : LIBUSB_ERROR_NO_DEVICE;
}

int __wrap_libusb_bulk_transfer(libusb_device_handle* /*handle*/, unsigned char endpoint,
                                unsigned char* data, int length, int* transferred,
                                unsigned int timeout) {
  FakeUsb& fake = *g_fake_usb;
  const bool in = (endpoint & LIBUSB_ENDPOINT_IN) != 0;
  fake.log.push_back((in ? "in " : "out ") + std::to_string(length));
  fake.timeouts_ms.push_back(timeout);
  std::deque<FakeTransfer>& script = in ? fake.in_script : fake.out_script;
  if (script.empty()) {
    *transferred = 0;
    return LIBUSB_ERROR_TIMEOUT;
  }
  const FakeTransfer transfer = script.front();
  script.pop_front();
  if (in) {
    const int count = std::min(length, static_cast<int>(transfer.in_data.size()));
    std::copy_n(transfer.in_data.begin(), count, data);
    *transferred = count;
  } else {
    const int count = std::min(length, transfer.transferred);
    fake.written.insert(fake.written.end(), data, data + count);
    *transferred = count;
  }
  return transfer.rc;
}

}  // extern "C"
