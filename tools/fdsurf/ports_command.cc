// SPDX-License-Identifier: MIT
// `fdsurf ports`: the serial ports, with what users otherwise dig out of
// /dev/serial/by-id (USB VID:PID, serial number, product), and with --probe
// what answers the fdsurf protocol's HELLO on each.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "fdsurf/hal/serial_transport.h"
#include "runners/serial_session.h"

namespace fdsurf::host {
namespace {

std::string OrDash(const std::string& text) { return text.empty() ? "-" : text; }

// What answered on `path`, in words, or why nothing did.
std::string Probe(const std::string& path, const PortsOptions& o, bool* answered) {
  std::string error;
  bool interrupted = false;
  const auto session =
      ProbeSerialPort(path, o.baud, Milliseconds(o.timeout_s), true, &error, &interrupted);
  *answered = session.has_value();
  if (!session) return error;
  const protocol::HelloReply& hello = *session->loop->link().hello();
  return "fdsurf protocol " + std::to_string(hello.version) + ", " +
         std::to_string(hello.max_axes) + " axes, " + std::to_string(hello.tick_hz) +
         " Hz ticks, queue " + std::to_string(hello.queue_capacity) + ", lines up to " +
         std::to_string(hello.max_lines);
}

void PrintTable(const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> width;
  for (const auto& row : rows) {
    width.resize(std::max(width.size(), row.size()));
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  }
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c) {
      line += row[c];
      if (c + 1 < row.size()) line += std::string(width[c] - row[c].size() + 2, ' ');
    }
    std::printf("%s\n", line.c_str());
  }
}

}  // namespace

void AddPortsOptions(CLI::App* command, PortsOptions* o) {
  command->add_option("PATH", o->paths,
                      "ports to show besides the listed ones (a pty, which is never listed)");
  command->add_flag("--probe", o->probe,
                    "send HELLO on each port (only the PATHs, when some are given) and show "
                    "what answered (opening an Arduino's port resets it)");
  command->add_option("--baud", o->baud, "--probe: the baud")
      ->check(CLI::Range(50, 4000000))
      ->capture_default_str();
  command->add_option("--timeout", o->timeout_s, "--probe: seconds to wait for each answer")
      ->check(CLI::Range(0.1, 60.0))
      ->capture_default_str();
}

int RunPorts(const PortsOptions& o) {
  std::vector<hal::SerialPortInfo> ports;
  for (const std::string& path : o.paths) {
    std::error_code error;
    if (!std::filesystem::exists(path, error)) {
      std::fprintf(stderr, "fdsurf: error: serial %s: no such port\n", path.c_str());
      return 3;
    }
    ports.push_back(hal::DescribeSerialPort(path));
  }
  for (hal::SerialPortInfo& listed : hal::ListSerialPorts()) {
    const bool named = std::any_of(ports.begin(), ports.end(), [&](const auto& port) {
      std::error_code error;
      return std::filesystem::equivalent(port.path, listed.path, error);
    });
    if (!named) ports.push_back(std::move(listed));
  }
  std::vector<std::vector<std::string>> rows{
      {"PORT", "TRANSPORT", "VID:PID", "SERIAL", "MANUFACTURER", "PRODUCT", "BY-ID"}};
  if (o.probe) rows[0].push_back("ANSWER");
  // With ports named, only those are probed: opening the others would reset
  // any Arduino among them and cost the timeout on each.
  const std::size_t probed = o.paths.empty() ? ports.size() : o.paths.size();
  int answering = 0;
  for (std::size_t i = 0; i < ports.size(); ++i) {
    const hal::SerialPortInfo& port = ports[i];
    rows.push_back({port.path, port.transport, OrDash(port.VidPid()), OrDash(port.usb_serial),
                    OrDash(port.manufacturer), OrDash(port.product), OrDash(port.by_id)});
    if (o.probe && i >= probed) rows.back().push_back("(not probed)");
    if (o.probe && i < probed) {
      bool answered = false;
      rows.back().push_back(Probe(port.path, o, &answered));
      answering += answered ? 1 : 0;
    }
  }
  if (ports.empty()) {
    std::fprintf(stderr, "fdsurf: no serial ports listed (name a pty on the command line)\n");
    return 0;
  }
  PrintTable(rows);
  return o.probe && answering == 0 ? 3 : 0;
}

}  // namespace fdsurf::host
