// SPDX-License-Identifier: MIT
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "../cli_options.h"
#include "fdsurf/device/device.h"
#include "fdsurf/hal/gpiod_outputs.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "runner.h"

namespace fdsurf::host {

// This host is the controller: the firmware's Device runs here, in real time,
// on GPIO lines. Ticks can only come late (never early), so speeds and
// accelerations can only come out below the configured limits.
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
  const auto run = [&](auto& device) {
    std::vector<std::uint8_t> out;
    std::uint8_t in[256];
    const std::uint64_t tick_us = 1'000'000 / tick_hz;
    std::uint64_t next_tick = clock.NowMicros();
    std::uint64_t last_progress = 0;
    std::uint64_t ticks = 0;
    while (!link.Finished() && !link.Failed()) {
      if (ticks++ % 16 == 0) {
        const std::uint64_t now = clock.NowMicros();
        out.clear();
        link.Poll(now, &out);
        for (const std::uint8_t byte : out) device.OnByte(byte);
        for (std::size_t n; (n = device.ReadOutput(in, sizeof in)) > 0;) link.OnBytes(in, n, now);
        device.Fill();
        if (now - last_progress > 250'000) {
          last_progress = now;
          progress.Show(device.executed(), job.commands.size(), link.stats().frames_sent, 0);
        }
      }
      next_tick += tick_us;
      clock.SleepUntilMicros(next_tick);
      if (device.Tick(*outputs, *outputs) != hal::IoStatus::kOk) {
        throw DeviceError(std::string("gpio: ") + outputs->StepDirOutputs::LastError());
      }
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
  }
  return 0;
}

}  // namespace fdsurf::host
