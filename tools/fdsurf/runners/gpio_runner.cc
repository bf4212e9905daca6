// SPDX-License-Identifier: MIT
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "../cli_options.h"
#include "fdsurf/device/device.h"
#include "fdsurf/hal/gpiod_outputs.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/hal/tick_scheduler.h"
#include "runner.h"
#include "tick_loop.h"

namespace fdsurf::host {

// This host is the controller: the firmware's Device runs here, in real time,
// on GPIO lines (tick_loop.h). A tick can only come late, and the next one is
// due a full period after it, so the path speed can only come out below the
// configured limit. A stall longer than a period stops the motion abruptly
// and resumes it at the speed it had (the device does not know about the
// stall): a stepper at speed may lose steps there, which the summary reports.
int RunGpio(const StreamOptions& o, const StreamJob& job) {
  hal::GpiodConfig config;
  std::string error;
  if (!hal::ParseGpioDevice(o.device, &config, &error)) throw InputError("--device: " + error);
  if (config.axes != o.dims) {
    throw InputError("--device: " + std::to_string(config.axes) +
                     " axes of lines given for --dims " + std::to_string(o.dims));
  }
  const std::uint32_t tick_hz = o.tick_hz != 0 ? o.tick_hz : 10000;
  CheckSpeedAgainstTicks(job, tick_hz, o);
  std::unique_ptr<hal::GpiodOutputs> outputs;
  if (hal::GpiodOutputs::Open(config, &outputs, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  HostLink link(LinkOptions());
  Enqueue(job, &link);
  ProgressLine progress(ShowProgress(o.quiet));
  hal::MonotonicClock clock;
  // The period rounded up: a tick rate above tick_hz would be a speed above the limit.
  hal::TickScheduler ticks(clock, (1'000'000 + tick_hz - 1) / tick_hz);
  const auto run = [&](auto& device) {
    std::uint64_t last_progress = 0;
    const auto show_progress = [&](std::uint64_t now) {
      if (now - last_progress <= 250'000) return;
      last_progress = now;
      progress.Show(device.executed(), job.commands.size(), link.stats().frames_sent, 0);
    };
    if (RunTickLoop(clock, ticks, link, device, *outputs, *outputs, show_progress) !=
        hal::IoStatus::kOk) {
      throw DeviceError(std::string("gpio: ") + outputs->StepDirOutputs::LastError());
    }
  };
  if (o.dims == 3) {
    auto device = std::make_unique<device::Device<3>>(tick_hz);
    run(*device);
  } else {
    auto device = std::make_unique<device::Device<2>>(tick_hz);
    run(*device);
  }
  progress.Finish();
  if (link.Failed()) throw DeviceError("gpio device: " + DecodeDeviceError(link.error()));
  if (!o.quiet) {
    std::fprintf(stderr, "%s: %zu patches drawn on %s at %u Hz ticks\n", o.file.c_str(),
                 job.patches.size(), o.device.c_str(), tick_hz);
    if (ticks.late_ticks() != 0) {
      std::fprintf(stderr,
                   "gpio: %llu of %llu ticks came a period or more late (longest %.1f ms): the "
                   "motion was stretched there\n",
                   static_cast<unsigned long long>(ticks.late_ticks()),
                   static_cast<unsigned long long>(ticks.ticks()),
                   static_cast<double>(ticks.max_lateness_us()) / 1000.0);
    }
  }
  return 0;
}

}  // namespace fdsurf::host
