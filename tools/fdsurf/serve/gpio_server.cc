// SPDX-License-Identifier: MIT
#include "gpio_server.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "../runners/gpio_lines.h"
#include "../runners/runner.h"
#include "fdsurf/device/device.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/hal/pty_transport.h"
#include "fdsurf/hal/tick_scheduler.h"
#include "fdsurf/host/errors.h"

namespace fdsurf::host {
namespace {

// The device is serviced (bytes in and out, Fill) every 16 ticks, as in the
// GPIO runner's loop (runners/tick_loop.h): at 10 kHz every 1.6 ms.
constexpr std::uint64_t kTicksPerService = 16;
// How long a stop on SIGINT/SIGTERM may take to come to rest, and how long
// a halt's pen lift is given, µs.
constexpr std::uint64_t kStopTimeoutUs = 10'000'000;
constexpr std::uint64_t kHaltTimeUs = 200'000;

// What serving runs with, apart from the Device.
struct Server {
  Server(GpioLines& gpio_lines, hal::PtyTransport& port, std::uint32_t tick_hz)
      : ticks(clock, hal::TickScheduler::PeriodOf(tick_hz)), lines(gpio_lines), pty(port) {}

  hal::MonotonicClock clock;
  hal::TickScheduler ticks;
  GpioLines& lines;
  hal::PtyTransport& pty;
  std::uint64_t port_errors = 0;  // replies the pty could not take (the host retransmits)
};

// Ticks `device` in real time while `keep_going()`, servicing the pty:
// kOk, or the status of the Tick whose output failed.
template <class Device, class KeepGoing>
hal::IoStatus Serve(Server& server, Device& device, KeepGoing keep_going) {
  for (std::uint64_t n = 0; keep_going(); ++n) {
    if (n % kTicksPerService == 0) {
      // A timeout is a client that stopped reading mid-reply: the host's
      // retransmission recovers what it missed, so serving goes on.
      if (device.Service(server.pty) != hal::IoStatus::kOk) ++server.port_errors;
      device.Fill();
    }
    server.ticks.WaitForNextTick();
    const hal::IoStatus status = device.Tick(server.lines.outputs(), server.lines.pen());
    if (status != hal::IoStatus::kOk) return status;
    server.ticks.EndTick();
  }
  return hal::IoStatus::kOk;
}

// The end of serving, on a signal: STOP (the motion decelerates along its
// path and the pen is lifted) until at rest, or HALT after a second signal
// or the stop's time limit; then the lines made safe whatever happened.
template <class Device>
int StopServing(const ServeOptions& o, Server& server, Device& device) {
  if (!o.quiet) std::fprintf(stderr, "\nfdsurf serve: stopping the device\n");
  device.Stop();
  const std::uint64_t deadline = server.clock.NowMicros() + kStopTimeoutUs;
  hal::IoStatus status = Serve(server, device, [&] {
    return !device.Idle() && !InterruptGuard::Again() && server.clock.NowMicros() < deadline;
  });
  const bool at_rest = device.Idle();
  if (status == hal::IoStatus::kOk && !at_rest) {
    device.Halt();
    const std::uint64_t halt_deadline = server.clock.NowMicros() + kHaltTimeUs;
    status = Serve(server, device, [&] { return server.clock.NowMicros() < halt_deadline; });
  }
  const GpioLines::SafeState safe = server.lines.MakeSafe();
  const hal::TickScheduler& ticks = server.ticks;
  std::fprintf(stderr,
               "fdsurf serve: stopped %s: %u sessions, %u commands executed, %s, pen %s, drivers "
               "%s; %llu of %llu ticks late (longest %.1f ms), %llu stalled before their "
               "writes\n",
               o.device.c_str(), device.link_stats().hellos, device.executed(),
               at_rest ? "at rest" : "halted (the position may be lost)",
               safe.pen_lifted ? "lifted" : "NOT lifted",
               safe.drivers_disabled ? "disabled" : "NOT disabled",
               static_cast<unsigned long long>(ticks.late_ticks()),
               static_cast<unsigned long long>(ticks.ticks()),
               static_cast<double>(ticks.max_lateness_us()) / 1000.0,
               static_cast<unsigned long long>(ticks.stalled_ticks()));
  if (server.port_errors != 0) {
    std::fprintf(stderr,
                 "fdsurf serve: %llu times a client did not read its replies in time (the "
                 "protocol resent what it missed)\n",
                 static_cast<unsigned long long>(server.port_errors));
  }
  if (status != hal::IoStatus::kOk) {
    std::fprintf(stderr, "fdsurf: error: serve: %s\n", server.lines.OutputError().c_str());
    return 3;
  }
  return 0;
}

template <class Device>
int ServeUntilSignalled(const ServeOptions& o, Server& server, std::uint32_t tick_hz) {
  auto device = std::make_unique<Device>(tick_hz);
  device->set_endstops(server.lines.endstops());
  const hal::IoStatus status =
      Serve(server, *device, [] { return !InterruptGuard::Interrupted(); });
  if (status == hal::IoStatus::kOk) return StopServing(o, server, *device);
  const std::string error = server.lines.OutputError();
  const GpioLines::SafeState safe = server.lines.MakeSafe();
  std::fprintf(stderr, "fdsurf: error: serve: %s (pen %s, drivers %s)\n", error.c_str(),
               safe.pen_lifted ? "lifted" : "NOT lifted",
               safe.drivers_disabled ? "disabled" : "NOT disabled");
  return 3;
}

// LINK.device: which --device a server publishes at LINK, written beside
// the link (renamed into place) while it serves, removed when it stops.
class ServedDeviceNote {
 public:
  ServedDeviceNote(const std::string& link, const std::string& device) : path_(link + ".device") {
    const std::string temporary = path_ + ".new";
    std::ofstream(temporary) << device << "\n";
    std::rename(temporary.c_str(), path_.c_str());
  }
  ~ServedDeviceNote() { std::remove(path_.c_str()); }
  ServedDeviceNote(const ServedDeviceNote&) = delete;
  ServedDeviceNote& operator=(const ServedDeviceNote&) = delete;

 private:
  std::string path_;
};

// The link (a path) when a running `serve` publishes `device` at the
// default link, else "".
std::string ServedGpioLink(const std::string& device) {
  std::string link = DefaultServeLink();
  std::ifstream note(link + ".device");
  std::string served;
  std::getline(note, served);
  // The link must lead to a live pty: a server killed outright leaves both
  // behind, and its /dev/pts/N may be gone.
  std::error_code error;
  if (served != device || !std::filesystem::exists(link, error)) return "";
  return link;
}

std::uint16_t ServoWidth(int us, const char* flag) {
  if (us != 0 && (us < 500 || us > 2500)) {
    throw InputError(std::string(flag) + ": " + std::to_string(us) +
                     " µs is not a servo pulse width (500..2500)");
  }
  return static_cast<std::uint16_t>(us);
}

}  // namespace

std::string DeviceThroughServer(const std::string& device, bool quiet) {
  if (device.rfind("gpio:", 0) != 0) return device;
  const std::string served = ServedGpioLink(device);
  if (served.empty()) return device;
  if (!quiet) std::fprintf(stderr, "fdsurf: %s is served at %s\n", device.c_str(), served.c_str());
  return "serial:" + served;
}

std::string DefaultServeLink() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  const std::string dir = runtime != nullptr && runtime[0] == '/' ? runtime : "/tmp";
  return dir + "/fdsurf-gpio";
}

int ServeGpio(const ServeOptions& o) {
  if (o.device.rfind("gpio:", 0) != 0) {
    throw InputError("--device " + (o.device.empty() ? std::string("(none)") : o.device) +
                     ": serve drives gpio:CHIP:LINES (a board on serial or usb serves itself)");
  }
  const std::uint16_t up = ServoWidth(o.servo_pulse_up_us, "--servo-pulse-up");
  const std::uint16_t down = ServoWidth(o.servo_pulse_down_us, "--servo-pulse-down");
  const std::uint32_t tick_hz = o.tick_hz != 0 ? o.tick_hz : 10000;
  GpioLines lines(o.device, 0, up, down);
  const std::string link = o.link.empty() ? DefaultServeLink() : o.link;
  // The note first: a client that finds the link finds the note beside it.
  const ServedDeviceNote note(link, o.device);
  std::unique_ptr<hal::PtyTransport> pty;
  std::string error;
  if (hal::PtyTransport::Open(link, &pty, &error) != hal::IoStatus::kOk) {
    throw InputError("--link: " + error);
  }
  const InterruptGuard interrupts;
  Server server(lines, *pty, tick_hz);
  const std::string scheduling = RunInRealTime();
  if (!o.quiet) {
    std::fprintf(stderr,
                 "fdsurf serve: %s, %d axes, %u Hz ticks, %s, served at %s (%s): use --device "
                 "serial:%s; Ctrl-C stops\n",
                 o.device.c_str(), lines.axes(), tick_hz, scheduling.c_str(), link.c_str(),
                 pty->slave_name().c_str(), link.c_str());
  }
  if (lines.axes() == 3) return ServeUntilSignalled<device::Device<3>>(o, server, tick_hz);
  return ServeUntilSignalled<device::Device<2>>(o, server, tick_hz);
}

}  // namespace fdsurf::host
