// SPDX-License-Identifier: MIT
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "../cli_options.h"
#include "serial_session.h"

namespace fdsurf::host {
namespace {

TransportLoopOptions LoopOptions(const std::string& path, std::uint32_t connect_timeout_ms,
                                 std::uint32_t reconnect_timeout_ms, bool quiet) {
  TransportLoopOptions options;
  options.device = "serial " + path;
  options.connect_timeout_ms = connect_timeout_ms;
  options.reconnect_timeout_ms = reconnect_timeout_ms;
  options.quiet = quiet;
  return options;
}

// Opens the port and puts the link's loop on it; nothing is sent yet.
std::optional<SerialSession> OpenSession(const std::string& path, std::uint32_t baud,
                                         const TransportLoopOptions& loop_options,
                                         std::string* error) {
  SerialSession session;
  hal::SerialOptions options;
  options.baud = baud;
  if (hal::SerialTransport::Open(path, options, &session.port, error) != hal::IoStatus::kOk) {
    return std::nullopt;
  }
  session.loop = std::make_unique<TransportLoop>(*session.port, loop_options);
  return session;
}

// serial:auto: every listed port is probed; exactly one must answer.
SerialSession FindTheOneBoard(const StreamOptions& o, std::uint32_t baud) {
  std::vector<SerialSession> answered;
  std::vector<std::string> answered_paths;
  std::string tried;
  const std::vector<hal::SerialPortInfo> ports = hal::ListSerialPorts();
  for (const hal::SerialPortInfo& info : ports) {
    std::string error;
    bool interrupted = false;
    auto session = ProbeSerialPort(info.path, baud, Milliseconds(o.connect_timeout_s), true, &error,
                                   &interrupted);
    if (interrupted) throw DeviceError("serial:auto: interrupted while probing " + info.path);
    if (session) {
      answered_paths.push_back(info.path);
      answered.push_back(std::move(*session));
      tried += "\n  " + info.path + ": answered HELLO";
    } else {
      tried += "\n  " + error;
    }
  }
  if (answered.size() == 1) return std::move(answered.front());
  if (ports.empty()) {
    throw DeviceError(
        "serial:auto: no serial ports listed (a pty is never listed: name it, "
        "serial:PATH)");
  }
  throw DeviceError(std::string("serial:auto: ") +
                    (answered.empty() ? "no port answered HELLO"
                                      : std::to_string(answered.size()) +
                                            " ports answered HELLO; name one with serial:PATH") +
                    " (tried " + std::to_string(ports.size()) + " at " + std::to_string(baud) +
                    " baud):" + tried);
}

}  // namespace

std::optional<SerialSession> ProbeSerialPort(const std::string& path, std::uint32_t baud,
                                             std::uint32_t connect_timeout_ms, bool quiet,
                                             std::string* error, bool* interrupted) {
  *interrupted = false;
  std::optional<SerialSession> session =
      OpenSession(path, baud, LoopOptions(path, connect_timeout_ms, 0, quiet), error);
  if (!session) return std::nullopt;
  try {
    if (!session->loop->Connect()) {
      *interrupted = true;
      *error = "serial " + path + ": interrupted";
      return std::nullopt;
    }
  } catch (const DeviceError& e) {
    *error = e.what();
    return std::nullopt;
  }
  return session;
}

int RunSerial(const StreamOptions& o, const StreamJob& job) {
  hal::SerialSpec spec;
  std::string error;
  if (!hal::ParseSerialDevice(o.device, &spec, &error)) throw InputError("--device: " + error);
  if (spec.automatic && !o.resume.empty()) {
    // Probing the ports starts new sessions, which would end the one to resume.
    throw InputError("--resume needs the port named (serial:PATH), not serial:auto");
  }
  const InterruptGuard interrupts;
  SerialSession session;
  if (spec.automatic) {
    session = FindTheOneBoard(o, spec.baud);
  } else {
    std::optional<SerialSession> opened =
        OpenSession(spec.path, spec.baud,
                    LoopOptions(spec.path, Milliseconds(o.connect_timeout_s), 0, o.quiet), &error);
    if (!opened) throw DeviceError(error);
    session = std::move(*opened);
  }
  // Probing connects without reconnecting; the job reconnects after an unplug.
  TransportLoop& loop = *session.loop;
  loop.set_reconnect_timeout_ms(Milliseconds(o.reconnect_timeout_s));
  loop.set_no_pause(o.no_pause);
  std::optional<std::uint32_t> old_executed;
  if (o.resume_state) old_executed = loop.FinishOldSession(o.resume_state->session);
  if (!loop.Connect()) {
    std::fprintf(stderr, "fdsurf: interrupted before the device answered; nothing was sent\n");
    return 130;
  }
  const std::string name = "serial " + session.port->path();
  const protocol::HelloReply hello = *loop.link().hello();
  const StreamJob fitted = FitJobToDevice(job, hello, name, o);
  std::optional<JobJournal> journal;
  const StreamJob to_run = JobWithJournal(o, job, fitted, old_executed, &loop, &journal);
  ProgressLine progress(ShowProgress(o.quiet));
  progress.SetSchedule(o.resume_state ? nullptr : o.schedule.get());
  const int code = RunKeepingJournal(&loop, to_run, &progress, &journal);
  if (code != 0 || o.quiet) return code;
  const HostLinkStats& stats = loop.link().stats();
  std::fprintf(stderr,
               "%s: %s drawn by %s (%u baud, %u Hz ticks); %llu frames sent (%llu "
               "resent), %llu reconnects\n",
               o.file.c_str(), JobContents(job).c_str(), name.c_str(), spec.baud, hello.tick_hz,
               static_cast<unsigned long long>(stats.frames_sent),
               static_cast<unsigned long long>(stats.retransmitted),
               static_cast<unsigned long long>(loop.reconnects()));
  return 0;
}

}  // namespace fdsurf::host
