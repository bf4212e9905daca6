// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "../cli_options.h"
#include "fdsurf/device/device.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/hal/tick_scheduler.h"
#include "gpio_lines.h"
#include "runner.h"
#include "tick_loop.h"

namespace fdsurf::host {
namespace {

// Everything a job on the GPIO lines runs with, apart from the Device.
struct GpioRig {
  GpioRig(GpioLines& gpio_lines, std::uint32_t tick_hz, bool quiet)
      : ticks(clock, hal::TickScheduler::PeriodOf(tick_hz)),
        link(LinkOptions()),
        lines(gpio_lines),
        progress(ShowProgress(quiet)) {}

  hal::MonotonicClock clock;
  hal::TickScheduler ticks;
  HostLink link;
  GpioLines& lines;
  ProgressLine progress;
};

// Ticks `device` while `keep_going()`; DeviceError when an output fails.
template <class Device, class KeepGoing>
void Tick(GpioRig& rig, Device& device, std::uint64_t total_commands, KeepGoing keep_going) {
  std::uint64_t last_progress = 0;
  const auto show_progress = [&](std::uint64_t now) {
    if (now - last_progress <= 250'000) return;
    last_progress = now;
    rig.progress.Show(device.executed(), total_commands, rig.link.stats().frames_sent, 0);
  };
  if (RunTickLoopWhile(rig.clock, rig.ticks, rig.link, device, rig.lines.outputs(), rig.lines.pen(),
                       show_progress, keep_going) != hal::IoStatus::kOk) {
    throw DeviceError(rig.lines.OutputError());
  }
}

// After a second Ctrl-C: HALT through the link (the device drops everything
// at once), a few ticks for it to take effect, and then the pen lifted and
// the drivers disabled directly on the lines, whatever the device did; 130.
template <class Device>
int HaltNow(const StreamOptions& o, GpioRig& rig, Device& device) {
  if (!o.quiet) std::fprintf(stderr, "\nfdsurf: interrupted again: halting\n");
  rig.link.RequestHalt();
  const std::uint64_t deadline = rig.clock.NowMicros() + 200'000;
  Tick(rig, device, 0,
       [&] { return !rig.link.HaltAcknowledged() && rig.clock.NowMicros() < deadline; });
  const GpioLines::SafeState safe = rig.lines.MakeSafe();
  std::fprintf(stderr,
               "fdsurf: halted: gpio %s stopped at once, pen %s, drivers %s (the position may be "
               "lost: home before the next job)\n",
               o.device.c_str(), safe.pen_lifted ? "lifted" : "NOT lifted",
               safe.drivers_disabled ? "disabled" : "NOT disabled");
  return 130;
}

// After Ctrl-C: STOP through the link (the device decelerates along its path
// and lifts the pen), ticks until it rests (10 s at most), what was done; 130.
template <class Device>
int StopAtRest(const StreamOptions& o, const StreamJob& job, GpioRig& rig, Device& device) {
  rig.progress.Finish();
  if (!o.quiet) std::fprintf(stderr, "fdsurf: interrupted: stopping the device\n");
  rig.link.RequestStop();
  const std::uint64_t deadline = rig.clock.NowMicros() + 10'000'000;
  Tick(rig, device, job.commands.size(), [&] {
    return !(rig.link.StopAcknowledged() && device.Idle()) && rig.clock.NowMicros() < deadline &&
           !InterruptGuard::Again();
  });
  if (InterruptGuard::Again()) return HaltNow(o, rig, device);
  const bool pen_down = device.motion().pen_down();
  std::fprintf(stderr,
               "fdsurf: stopped: gpio %s is %s (pen %s) after %u of %zu commands executed\n",
               o.device.c_str(), device.Idle() ? "at rest" : "NOT at rest",
               pen_down ? "down" : "up", device.executed(), job.commands.size());
  return 130;
}

// The job layer by layer (as the other runners): a layer runs until the link
// reports it executed and the device idle, then the pause for the pen change
// keeps the ticks going (RunIdleTicks, 20 ms a slice) until Enter. 0, or
// 130 after Ctrl-C.
template <class Device>
int RunLayers(const StreamOptions& o, const StreamJob& job, GpioRig& rig, Device& device,
              std::uint32_t tick_hz) {
  HostLink& link = rig.link;
  for (std::size_t from = 0;;) {
    const std::size_t to = NextLayerBoundary(job, from);
    rig.progress.SetLayer(LayerLabel(job, from));
    Enqueue(job, &link, from, to);
    {
      PauseToggle pause(true, o.quiet, &rig.progress);
      Tick(rig, device, job.commands.size(), [&] {
        pause.Poll(&link);
        return !link.Finished() && !link.Failed() && !InterruptGuard::Interrupted();
      });
    }
    if (InterruptGuard::Interrupted()) return StopAtRest(o, job, rig, device);
    if (link.Failed() || to == job.commands.size()) break;
    if (device.motion().pen_down()) {
      throw DeviceError("gpio: the pen is down at the end of " + LayerLabel(job, from) +
                        ": not pausing for a pen change");
    }
    rig.progress.Finish();
    const auto idle_slice = [&] {
      if (RunIdleTicks(rig.clock, rig.ticks, link, device, rig.lines.outputs(), rig.lines.pen(),
                       std::max<std::uint64_t>(1, tick_hz / 50)) != hal::IoStatus::kOk) {
        throw DeviceError(rig.lines.OutputError());
      }
    };
    if (!PauseForLayer(o.no_pause, job, to, device.executed(), idle_slice)) {
      return StopAtRest(o, job, rig, device);
    }
    from = to;
  }
  rig.progress.Finish();
  if (link.Failed()) throw DeviceError("gpio device: " + DecodeDeviceError(link.error()));
  return 0;
}

}  // namespace

// This host is the controller: the firmware's Device runs here, in real time,
// on GPIO lines (tick_loop.h). A tick can only come late, and the next one is
// due a full period after it, so the path speed can only come out below the
// configured limit. A stall longer than a period stops the motion abruptly
// and resumes it at the speed it had (the device does not know about the
// stall): a stepper at speed may lose steps there, which the summary reports.
int RunGpio(const StreamOptions& o, const StreamJob& job) {
  const std::uint32_t tick_hz = o.tick_hz != 0 ? o.tick_hz : 10000;
  {
    // The spec is checked before the speed, as the lines are opened after.
    hal::GpiodConfig config;
    std::string error;
    if (!hal::ParseGpioDevice(o.device, &config, &error)) throw InputError("--device: " + error);
  }
  CheckSpeedAgainstTicks(job, tick_hz, o);
  GpioLines lines(o.device, o.dims, job.config.servo_up_us, job.config.servo_down_us);
  const std::string scheduling = RunInRealTime();
  const InterruptGuard interrupts;
  GpioRig rig(lines, tick_hz, o.quiet);
  rig.progress.SetSchedule(o.schedule.get());
  int code = 0;
  if (o.dims == 3) {
    auto device = std::make_unique<device::Device<3>>(tick_hz);
    device->set_endstops(lines.endstops());
    code = RunLayers(o, job, rig, *device, tick_hz);
  } else {
    auto device = std::make_unique<device::Device<2>>(tick_hz);
    device->set_endstops(lines.endstops());
    code = RunLayers(o, job, rig, *device, tick_hz);
  }
  if (code != 0 || o.quiet) return code;
  std::fprintf(stderr, "%s: %s drawn on %s at %u Hz ticks, %s\n", o.file.c_str(),
               JobContents(job).c_str(), o.device.c_str(), tick_hz, scheduling.c_str());
  const hal::TickScheduler& ticks = rig.ticks;
  if (ticks.late_ticks() != 0) {
    std::fprintf(stderr,
                 "gpio: %llu of %llu ticks came a period or more late (longest %.1f ms): the "
                 "motion was stretched there\n",
                 static_cast<unsigned long long>(ticks.late_ticks()),
                 static_cast<unsigned long long>(ticks.ticks()),
                 static_cast<double>(ticks.max_lateness_us()) / 1000.0);
  }
  return 0;
}

}  // namespace fdsurf::host
