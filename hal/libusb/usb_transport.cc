// SPDX-License-Identifier: MIT
#include "fdsurf/hal/usb_transport.h"

#include <libusb-1.0/libusb.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <thread>
#include <utility>

namespace fdsurf {
namespace hal {
namespace {

using SteadyClock = std::chrono::steady_clock;

// Whole packets for every speed (512 for high speed, 1024 for SuperSpeed), so
// a bulk IN transfer into it never overflows.
constexpr size_t kInBufferSize = 16384;
// Largest single OUT transfer handed to libusb.
constexpr size_t kMaxOutTransfer = 65536;

std::string Hex4(uint16_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "%04x", value);
  return text;
}

std::string PortPath(uint8_t bus, const std::vector<uint8_t>& ports) {
  std::string path = std::to_string(bus);
  for (size_t i = 0; i < ports.size(); ++i) {
    path += i == 0 ? '-' : '.';
    path += std::to_string(ports[i]);
  }
  return path;
}

std::vector<uint8_t> PortsOf(libusb_device* device) {
  uint8_t ports[8];
  const int count = libusb_get_port_numbers(device, ports, sizeof ports);
  if (count <= 0) return {};
  return std::vector<uint8_t>(ports, ports + count);
}

// Parses 1 to `max_digits` digits of base 10 or 16 into *value (≤ limit).
bool ParseNumber(std::string_view text, int base, size_t max_digits, unsigned limit,
                 unsigned* value) {
  if (text.empty() || text.size() > max_digits) return false;
  unsigned result = 0;
  for (const char c : text) {
    unsigned digit = 0;
    if (c >= '0' && c <= '9') {
      digit = static_cast<unsigned>(c - '0');
    } else if (base == 16 && c >= 'a' && c <= 'f') {
      digit = static_cast<unsigned>(c - 'a' + 10);
    } else if (base == 16 && c >= 'A' && c <= 'F') {
      digit = static_cast<unsigned>(c - 'A' + 10);
    } else {
      return false;
    }
    result = result * static_cast<unsigned>(base) + digit;
  }
  if (result > limit) return false;
  *value = result;
  return true;
}

// Milliseconds left until `deadline`, at least 1: libusb reads a timeout of 0
// as "wait forever".
unsigned RemainingMs(SteadyClock::time_point deadline) {
  const auto left =
      std::chrono::ceil<std::chrono::milliseconds>(deadline - SteadyClock::now()).count();
  return static_cast<unsigned>(std::clamp<int64_t>(left, 1, UINT_MAX));
}

// Why libusb_open failed, for the device node it names, as the status to
// report and *text; permission trouble comes with the udev rule that fixes it.
IoStatus DescribeOpenFailure(int rc, libusb_device* device, uint8_t bus,
                             const libusb_device_descriptor& descriptor, std::string* text) {
  char node[32];
  std::snprintf(node, sizeof node, "/dev/bus/usb/%03u/%03u", bus,
                libusb_get_device_address(device));
  if (rc == LIBUSB_ERROR_ACCESS) {
    char rule[128];
    std::snprintf(rule, sizeof rule,
                  R"(SUBSYSTEM=="usb", ATTR{idVendor}=="%04x", ATTR{idProduct}=="%04x", )"
                  R"(MODE="0660", TAG+="uaccess")",
                  descriptor.idVendor, descriptor.idProduct);
    *text = std::string("permission denied opening ") + node + " (add a udev rule: " + rule +
            "; see hal/README.md)";
    return IoStatus::kPermissionDenied;
  }
  if (rc == LIBUSB_ERROR_NO_DEVICE) {
    *text = std::string("vanished while opening ") + node;
    return IoStatus::kNotFound;
  }
  *text = std::string("cannot open ") + node + ": " + libusb_error_name(rc);
  return IoStatus::kIoError;
}

// The device's serial number string, empty when it has none or it cannot be
// read.
std::string ReadSerial(libusb_device_handle* handle, const libusb_device_descriptor& descriptor) {
  std::string serial;
  if (descriptor.iSerialNumber != 0) {
    unsigned char text[256];
    const int length =
        libusb_get_string_descriptor_ascii(handle, descriptor.iSerialNumber, text, sizeof text);
    if (length > 0) serial.assign(reinterpret_cast<const char*>(text), static_cast<size_t>(length));
  }
  return serial;
}

// Finds the vendor-specific interface `interface_number` (called `iface` in
// messages) in the configuration and its first bulk OUT and IN endpoints.
// Returns what is wrong, or an empty string when *out and *in are set.
std::string FindBulkEndpoints(const libusb_config_descriptor& config, uint8_t interface_number,
                              const std::string& iface, uint8_t* out, uint8_t* in) {
  const libusb_interface_descriptor* interface = nullptr;
  for (int i = 0; i < config.bNumInterfaces; ++i) {
    const libusb_interface& candidate = config.interface[i];
    if (candidate.num_altsetting > 0 &&
        candidate.altsetting[0].bInterfaceNumber == interface_number) {
      interface = &candidate.altsetting[0];
    }
  }
  if (interface == nullptr) {
    return "no " + iface + " (the device has " + std::to_string(config.bNumInterfaces) +
           " interface" + (config.bNumInterfaces == 1 ? "" : "s") + ")";
  }
  if (interface->bInterfaceClass != LIBUSB_CLASS_VENDOR_SPEC) {
    char klass[8];
    std::snprintf(klass, sizeof klass, "0x%02x", interface->bInterfaceClass);
    return iface + " is class " + klass + ", not vendor-specific (0xff)";
  }
  for (int e = 0; e < interface->bNumEndpoints; ++e) {
    const libusb_endpoint_descriptor& endpoint = interface->endpoint[e];
    if ((endpoint.bmAttributes & 0x03) != LIBUSB_ENDPOINT_TRANSFER_TYPE_BULK) continue;
    uint8_t& slot = (endpoint.bEndpointAddress & LIBUSB_ENDPOINT_IN) != 0 ? *in : *out;
    if (slot == 0) slot = endpoint.bEndpointAddress;
  }
  if (*out == 0 || *in == 0)
    return iface + " has no bulk " + (*out == 0 ? "OUT" : "IN") + " endpoint";
  return "";
}

// Why libusb_claim_interface failed, as the status to report and *text.
IoStatus DescribeClaimFailure(int rc, const std::string& iface, std::string* text) {
  switch (rc) {
    case LIBUSB_ERROR_BUSY:
      *text = iface + " busy (claimed by another program)";
      return IoStatus::kBusy;
    case LIBUSB_ERROR_ACCESS:
      *text = "permission denied claiming " + iface;
      return IoStatus::kPermissionDenied;
    case LIBUSB_ERROR_NO_DEVICE:
      *text = "vanished while claiming " + iface;
      return IoStatus::kNotFound;
    default:
      *text = "cannot claim " + iface + ": " + libusb_error_name(rc);
      return IoStatus::kIoError;
  }
}

}  // namespace

std::string UsbSelector::ToString() const {
  return by_port() ? PortPath(bus, ports) : Hex4(vendor_id) + ":" + Hex4(product_id);
}

bool ParseUsbDevice(std::string_view spec, UsbSelector* selector, std::string* error) {
  std::string quoted(1, '\'');  // built piecewise: GCC 12 warns (-Wrestrict) on "'" + string
  quoted.append(spec).push_back('\'');
  const std::string usage =
      "; expected usb, usb:VID:PID (hexadecimal, e.g. usb:1209:0001) or usb:BUS-PORT[.PORT...] "
      "(e.g. usb:1-1.4)";
  UsbSelector parsed;
  if (spec == "usb") {
    *selector = parsed;
    return true;
  }
  if (spec.substr(0, 4) != "usb:") {
    *error = "usb device " + quoted + " must start with 'usb'" + usage;
    return false;
  }
  const std::string_view rest = spec.substr(4);
  const size_t colon = rest.find(':');
  if (colon != std::string_view::npos) {
    const std::string_view vid = rest.substr(0, colon);
    const std::string_view pid = rest.substr(colon + 1);
    unsigned value = 0;
    if (!ParseNumber(vid, 16, 4, 0xffff, &value)) {
      *error = "usb device " + quoted + ": VID '" + std::string(vid) +
               "' is not a hexadecimal number of 1 to 4 digits" + usage;
      return false;
    }
    parsed.vendor_id = static_cast<uint16_t>(value);
    if (!ParseNumber(pid, 16, 4, 0xffff, &value)) {
      *error = "usb device " + quoted + ": PID '" + std::string(pid) +
               "' is not a hexadecimal number of 1 to 4 digits" + usage;
      return false;
    }
    parsed.product_id = static_cast<uint16_t>(value);
    *selector = parsed;
    return true;
  }
  const size_t dash = rest.find('-');
  if (dash == std::string_view::npos) {
    *error = "usb device " + quoted + " is neither VID:PID nor BUS-PORT" + usage;
    return false;
  }
  unsigned value = 0;
  if (!ParseNumber(rest.substr(0, dash), 10, 3, 255, &value) || value == 0) {
    *error = "usb device " + quoted + ": bus '" + std::string(rest.substr(0, dash)) +
             "' is not a number from 1 to 255" + usage;
    return false;
  }
  parsed.bus = static_cast<uint8_t>(value);
  std::string_view ports = rest.substr(dash + 1);
  while (true) {
    const size_t dot = ports.find('.');
    const std::string_view port = ports.substr(0, dot);
    if (!ParseNumber(port, 10, 3, 255, &value) || value == 0) {
      *error = "usb device " + quoted + ": port '";
      error->append(port).append("' is not a number from 1 to 255").append(usage);
      return false;
    }
    parsed.ports.push_back(static_cast<uint8_t>(value));
    if (dot == std::string_view::npos) break;
    ports.remove_prefix(dot + 1);
  }
  if (parsed.ports.size() > 7) {
    *error = "usb device " + quoted + ": " + std::to_string(parsed.ports.size()) +
             " ports deep; USB allows at most 7" + usage;
    return false;
  }
  *selector = parsed;
  return true;
}

UsbTransport::UsbTransport(const UsbSelector& selector, const UsbOptions& options,
                           libusb_context* context)
    : selector_(selector),
      options_(options),
      name_(selector.ToString()),
      context_(context),
      in_buffer_(kInBufferSize) {}

UsbTransport::~UsbTransport() {
  CloseHandle();
  libusb_exit(context_);
}

std::string UsbTransport::port_path() const { return PortPath(bus_, ports_); }

IoStatus UsbTransport::Open(const UsbSelector& selector, const UsbOptions& options,
                            std::unique_ptr<UsbTransport>* transport, std::string* error) {
  transport->reset();
  libusb_context* context = nullptr;
  const int rc = libusb_init(&context);
  if (rc != 0) {
    *error = "usb " + selector.ToString() + ": cannot initialise libusb: " + libusb_error_name(rc) +
             " (no USB access here: is /dev/bus/usb present? a container needs it passed in)";
    return IoStatus::kIoError;
  }
  std::unique_ptr<UsbTransport> self(new UsbTransport(selector, options, context));
  const IoStatus status = self->Attach(false, error);
  if (status != IoStatus::kOk) return status;
  *transport = std::move(self);
  return IoStatus::kOk;
}

IoStatus UsbTransport::Attach(bool reconnecting, std::string* error) {
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context_, &list);
  if (count < 0) {
    *error =
        "usb " + name_ + ": cannot list USB devices: " + libusb_error_name(static_cast<int>(count));
    return IoStatus::kIoError;
  }
  IoStatus status = IoStatus::kNotFound;
  std::string failure;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device* device = list[i];
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(device, &descriptor) != 0) continue;
    const Match match = TryDevice(device, descriptor, reconnecting, &status, &failure);
    if (match == Match::kTaken) {
      libusb_free_device_list(list, 1);
      return IoStatus::kOk;
    }
    if (match == Match::kFailed) break;
  }
  libusb_free_device_list(list, 1);
  if (status == IoStatus::kNotFound && failure.empty()) {
    std::string who = "usb " + name_;
    if (reconnecting) {
      who += serial_.empty() ? " at " + port_path() : " serial " + serial_;
    }
    failure = who + ": no such device (" + std::to_string(count) + " USB devices seen)";
  }
  *error = failure;
  return status;
}

// The libusb calls stay here, in one sequence, so that their order (each
// close before the error text is made) is plain to see: the hal tests' fakes
// check it. The helpers above only read descriptors and word failures.
UsbTransport::Match UsbTransport::TryDevice(libusb_device* device,
                                            const libusb_device_descriptor& descriptor,
                                            bool reconnecting, IoStatus* status,
                                            std::string* error) {
  const uint8_t bus = libusb_get_bus_number(device);
  const std::vector<uint8_t> ports = PortsOf(device);
  const bool same_ids = descriptor.idVendor == (reconnecting ? vendor_id_ : selector_.vendor_id) &&
                        descriptor.idProduct == (reconnecting ? product_id_ : selector_.product_id);
  if (reconnecting) {
    if (!same_ids) return Match::kSkipped;
    // Without a serial number, only the port tells two identical devices apart.
    if (serial_.empty() && (bus != bus_ || ports != ports_)) return Match::kSkipped;
  } else if (selector_.by_port() ? (bus != selector_.bus || ports != selector_.ports) : !same_ids) {
    return Match::kSkipped;
  }
  const std::string who = "usb " + name_ + ": ";
  auto fail = [&](IoStatus failed, std::string text) {
    *status = failed;
    *error = who + std::move(text);
    return Match::kFailed;
  };

  libusb_device_handle* handle = nullptr;
  int rc = libusb_open(device, &handle);
  if (rc != 0) {
    std::string text;
    const IoStatus failed = DescribeOpenFailure(rc, device, bus, descriptor, &text);
    return fail(failed, std::move(text));
  }
  auto close_and = [&](Match match) {
    libusb_close(handle);
    return match;
  };

  const std::string serial = ReadSerial(handle, descriptor);
  if (reconnecting && !serial_.empty() && serial != serial_) return close_and(Match::kSkipped);

  libusb_config_descriptor* config = nullptr;
  rc = libusb_get_active_config_descriptor(device, &config);
  if (rc != 0) {
    close_and(Match::kFailed);
    return fail(IoStatus::kIoError,
                std::string("cannot read the configuration descriptor: ") + libusb_error_name(rc));
  }
  const std::string iface = "interface " + std::to_string(options_.interface_number);
  uint8_t out = 0;
  uint8_t in = 0;
  const std::string problem =
      FindBulkEndpoints(*config, options_.interface_number, iface, &out, &in);
  libusb_free_config_descriptor(config);
  if (!problem.empty()) {
    close_and(Match::kFailed);
    return fail(IoStatus::kNotFound, problem);
  }

  // Not every platform can detach kernel drivers; claiming then says if one is bound.
  (void)libusb_set_auto_detach_kernel_driver(handle, 1);
  rc = libusb_claim_interface(handle, options_.interface_number);
  if (rc != 0) {
    close_and(Match::kFailed);
    std::string text;
    const IoStatus failed = DescribeClaimFailure(rc, iface, &text);
    return fail(failed, std::move(text));
  }
  handle_ = handle;
  endpoint_out_ = out;
  endpoint_in_ = in;
  vendor_id_ = descriptor.idVendor;
  product_id_ = descriptor.idProduct;
  serial_ = serial;
  bus_ = bus;
  ports_ = ports;
  in_begin_ = in_end_ = 0;
  *status = IoStatus::kOk;
  return Match::kTaken;
}

// libusb keeps its device list current from udev's hotplug events; without
// a udev daemon (an initramfs, most containers) the list stays as it was at
// libusb_init, and a device that comes back is never seen (found against
// the real kernel, tests/kernel/). A new context enumerates sysfs afresh.
// Only while no handle is open; if libusb_init fails the old one stays.
void UsbTransport::RenewContext() {
  if (handle_ != nullptr) return;
  libusb_context* fresh = nullptr;
  if (libusb_init(&fresh) != 0) return;
  libusb_exit(context_);
  context_ = fresh;
}

void UsbTransport::CloseHandle() {
  if (handle_ == nullptr) return;
  // Fails harmlessly (LIBUSB_ERROR_NO_DEVICE) when the device is gone.
  (void)libusb_release_interface(handle_, options_.interface_number);
  libusb_close(handle_);
  handle_ = nullptr;
}

IoStatus UsbTransport::Fail(IoStatus status, std::string detail) {
  last_error_ = "usb " + name_ + ": " + std::move(detail);
  return status;
}

IoStatus UsbTransport::TransferError(int rc, const char* what, const std::string& progress) {
  if (rc == LIBUSB_ERROR_NO_DEVICE || rc == LIBUSB_ERROR_IO) {
    CloseHandle();
    return Fail(IoStatus::kDisconnected, std::string("disconnected (") + libusb_error_name(rc) +
                                             ") during " + what + progress + "; call Reconnect()");
  }
  return Fail(IoStatus::kIoError,
              std::string(what) + " failed: " + libusb_error_name(rc) + progress);
}

IoStatus UsbTransport::DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) {
  if (data == nullptr && size > 0) return Fail(IoStatus::kInvalidArgument, "write of null data");
  if (handle_ == nullptr) return Fail(IoStatus::kDisconnected, "disconnected; call Reconnect()");
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(timeout_ms);
  size_t sent = 0;
  while (sent < size) {
    const size_t chunk = std::min(size - sent, kMaxOutTransfer);
    int transferred = 0;
    // libusb takes a non-const buffer for both directions; OUT only reads it.
    const int rc =
        libusb_bulk_transfer(handle_, endpoint_out_, const_cast<uint8_t*>(data + sent),
                             static_cast<int>(chunk), &transferred, RemainingMs(deadline));
    sent += static_cast<size_t>(std::max(transferred, 0));
    if (rc == LIBUSB_ERROR_TIMEOUT || (rc == 0 && sent < size && SteadyClock::now() >= deadline)) {
      return Fail(IoStatus::kTimeout, "write timed out after " + std::to_string(sent) + " of " +
                                          std::to_string(size) + " bytes (" +
                                          std::to_string(timeout_ms) + " ms)");
    }
    if (rc != 0) {
      return TransferError(
          rc, "write", " after " + std::to_string(sent) + " of " + std::to_string(size) + " bytes");
    }
  }
  return IoStatus::kOk;
}

IoStatus UsbTransport::DoRead(uint8_t* data, size_t capacity, size_t* received,
                              uint32_t timeout_ms) {
  if (received != nullptr) *received = 0;
  if (data == nullptr || received == nullptr || capacity == 0) {
    return Fail(IoStatus::kInvalidArgument, "read into a null or empty buffer");
  }
  if (handle_ == nullptr) return Fail(IoStatus::kDisconnected, "disconnected; call Reconnect()");
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(timeout_ms);
  while (in_begin_ == in_end_) {
    int transferred = 0;
    const int rc = libusb_bulk_transfer(handle_, endpoint_in_, in_buffer_.data(),
                                        static_cast<int>(in_buffer_.size()), &transferred,
                                        RemainingMs(deadline));
    if (transferred > 0) {
      // Data that came before a timeout is still data.
      in_begin_ = 0;
      in_end_ = static_cast<size_t>(transferred);
      break;
    }
    if (rc == LIBUSB_ERROR_TIMEOUT || (rc == 0 && SteadyClock::now() >= deadline)) {
      return Fail(IoStatus::kTimeout,
                  "nothing received within " + std::to_string(timeout_ms) + " ms");
    }
    if (rc != 0) return TransferError(rc, "read", "");
    // rc == 0 with no bytes: a zero-length packet; wait for more.
  }
  const size_t count = std::min(capacity, in_end_ - in_begin_);
  std::copy_n(in_buffer_.begin() + static_cast<ptrdiff_t>(in_begin_), count, data);
  in_begin_ += count;
  *received = count;
  return IoStatus::kOk;
}

IoStatus UsbTransport::DoReconnect(uint32_t timeout_ms) {
  if (handle_ != nullptr) return IoStatus::kOk;
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(timeout_ms);
  while (true) {
    RenewContext();
    std::string error;
    const IoStatus status = Attach(true, &error);
    if (status == IoStatus::kOk) return IoStatus::kOk;
    if (SteadyClock::now() >= deadline) {
      // A device that is back but cannot be opened says why; one that is not
      // back is a timeout.
      if (status != IoStatus::kNotFound) {
        last_error_ = error;
        return status;
      }
      last_error_ = error + "; not back within " + std::to_string(timeout_ms) + " ms";
      return IoStatus::kTimeout;
    }
    // Just after re-enumeration udev may not have applied permissions yet, or
    // a kernel driver may still hold the interface: retry those too.
    std::this_thread::sleep_for(std::chrono::milliseconds(
        std::min<int64_t>(options_.reconnect_poll_ms, RemainingMs(deadline))));
  }
}

}  // namespace hal
}  // namespace fdsurf
