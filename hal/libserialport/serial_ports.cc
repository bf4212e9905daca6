// SPDX-License-Identifier: MIT
// The device string and the port listing (libserialport's enumeration, which
// reads sysfs, plus the /dev/serial/by-id links udev makes).
#include <libserialport.h>
#include <stdlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <system_error>

#include "fdsurf/hal/serial_transport.h"

namespace fdsurf {
namespace hal {
namespace {

constexpr uint32_t kMinBaud = 50;
constexpr uint32_t kMaxBaud = 4'000'000;

std::string OrEmpty(const char* text) { return text == nullptr ? std::string() : text; }

// The path with every symlink resolved, or `path` itself when it cannot be.
std::string Resolved(const std::string& path) {
  char buffer[PATH_MAX];
  return realpath(path.c_str(), buffer) != nullptr ? std::string(buffer) : path;
}

// Device node -> the /dev/serial/by-id link that points at it.
std::map<std::string, std::string> ByIdLinks() {
  std::map<std::string, std::string> links;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/dev/serial/by-id", error)) {
    links.emplace(Resolved(entry.path().string()), entry.path().string());
  }
  return links;
}

const char* TransportName(enum sp_transport transport) {
  switch (transport) {
    case SP_TRANSPORT_NATIVE:
      return "native";
    case SP_TRANSPORT_USB:
      return "usb";
    case SP_TRANSPORT_BLUETOOTH:
      return "bluetooth";
  }
  return "unknown";
}

SerialPortInfo InfoOf(const struct sp_port* port) {
  SerialPortInfo info;
  info.path = OrEmpty(sp_get_port_name(port));
  info.transport = TransportName(sp_get_port_transport(port));
  info.description = OrEmpty(sp_get_port_description(port));
  if (sp_get_port_transport(port) == SP_TRANSPORT_USB) {
    int vid = -1;
    int pid = -1;
    if (sp_get_port_usb_vid_pid(port, &vid, &pid) == SP_OK) {
      info.usb_vendor_id = vid;
      info.usb_product_id = pid;
    }
    info.usb_serial = OrEmpty(sp_get_port_usb_serial(port));
    info.manufacturer = OrEmpty(sp_get_port_usb_manufacturer(port));
    info.product = OrEmpty(sp_get_port_usb_product(port));
  }
  return info;
}

bool AllDigits(std::string_view text) {
  return !text.empty() && text.size() <= 9 &&
         std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

std::string SerialPortInfo::VidPid() const {
  if (usb_vendor_id < 0 || usb_product_id < 0) return "";
  char text[24];
  std::snprintf(text, sizeof text, "%04x:%04x", static_cast<unsigned>(usb_vendor_id),
                static_cast<unsigned>(usb_product_id));
  return text;
}

bool ParseSerialDevice(std::string_view spec, SerialSpec* parsed, std::string* error) {
  std::string quoted(1, '\'');
  quoted.append(spec).push_back('\'');
  const std::string usage =
      "; expected serial:PATH[:BAUD] (e.g. serial:/dev/ttyACM0:115200) "
      "or serial:auto";
  if (spec.substr(0, 7) != "serial:" || spec.size() == 7) {
    *error = "serial device " + quoted + " names no port" + usage;
    return false;
  }
  SerialSpec result;
  std::string_view rest = spec.substr(7);
  if (rest == "auto") {
    result.automatic = true;
    *parsed = result;
    return true;
  }
  const size_t colon = rest.rfind(':');
  if (colon != std::string_view::npos) {
    const std::string_view baud = rest.substr(colon + 1);
    if (!AllDigits(baud)) {
      *error =
          "serial device " + quoted + ": baud '" + std::string(baud) + "' is not a number" + usage;
      return false;
    }
    const unsigned long value = std::strtoul(std::string(baud).c_str(), nullptr, 10);
    if (value < kMinBaud || value > kMaxBaud) {
      *error = "serial device " + quoted + ": baud " + std::string(baud) + " is not within " +
               std::to_string(kMinBaud) + ".." + std::to_string(kMaxBaud) + usage;
      return false;
    }
    result.baud = static_cast<uint32_t>(value);
    rest = rest.substr(0, colon);
  }
  if (rest.empty()) {
    *error = "serial device " + quoted + " names no port" + usage;
    return false;
  }
  result.path = std::string(rest);
  *parsed = result;
  return true;
}

std::vector<SerialPortInfo> ListSerialPorts() {
  std::vector<SerialPortInfo> ports;
  struct sp_port** list = nullptr;
  if (sp_list_ports(&list) != SP_OK) return ports;
  const std::map<std::string, std::string> by_id = ByIdLinks();
  for (size_t i = 0; list[i] != nullptr; ++i) {
    SerialPortInfo info = InfoOf(list[i]);
    const auto link = by_id.find(Resolved(info.path));
    if (link != by_id.end()) info.by_id = link->second;
    ports.push_back(std::move(info));
  }
  sp_free_port_list(list);
  std::sort(ports.begin(), ports.end(),
            [](const SerialPortInfo& a, const SerialPortInfo& b) { return a.path < b.path; });
  return ports;
}

SerialPortInfo DescribeSerialPort(const std::string& path) {
  const std::string node = Resolved(path);
  for (SerialPortInfo& info : ListSerialPorts()) {
    if (Resolved(info.path) == node) {
      info.path = path;
      return info;
    }
  }
  SerialPortInfo info;
  info.path = path;
  info.transport = node.rfind("/dev/pts/", 0) == 0 ? "pty" : "unknown";
  info.description = node;
  const std::map<std::string, std::string> by_id = ByIdLinks();
  const auto link = by_id.find(node);
  if (link != by_id.end()) info.by_id = link->second;
  return info;
}

}  // namespace hal
}  // namespace fdsurf
