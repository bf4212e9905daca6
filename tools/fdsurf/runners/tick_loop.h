// SPDX-License-Identifier: MIT
// The GPIO runner's real-time loop, apart from the GPIO lines so that it runs
// in tests on a fake clock and recorded outputs: the firmware's Device is
// serviced every 16 ticks (link out, replies in, Fill), and ticked on a
// TickScheduler, so no two ticks are closer than one period: a stall of the
// host stretches the motion and never compresses it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fdsurf/hal/clock.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/outputs.h"
#include "fdsurf/hal/tick_scheduler.h"
#include "fdsurf/host/link.h"

namespace fdsurf::host {

/// Runs `device` with `link` until the link has finished or failed, one
/// Tick per `ticks.WaitForNextTick()` (a hal::TickScheduler; tests pass
/// other policies).
/// `on_service(now_us)` is called after each service (for progress). Returns
/// kOk, or the status of the first Tick that failed (the outputs' LastError()
/// says why).
template <class Device, class Ticks, class OnService>
hal::IoStatus RunTickLoop(hal::Clock& clock, Ticks& ticks, HostLink& link, Device& device,
                          hal::StepDirOutputs& steppers, hal::PenOutput& pen,
                          OnService on_service) {
  std::vector<std::uint8_t> out;
  std::uint8_t in[256];
  for (std::uint64_t n = 0; !link.Finished() && !link.Failed(); ++n) {
    if (n % 16 == 0) {
      const std::uint64_t now = clock.NowMicros();
      out.clear();
      link.Poll(now, &out);
      for (const std::uint8_t byte : out) device.OnByte(byte);
      for (std::size_t got; (got = device.ReadOutput(in, sizeof in)) > 0;) {
        link.OnBytes(in, got, now);
      }
      device.Fill();
      on_service(now);
    }
    ticks.WaitForNextTick();
    const hal::IoStatus status = device.Tick(steppers, pen);
    if (status != hal::IoStatus::kOk) return status;
  }
  return hal::IoStatus::kOk;
}

}  // namespace fdsurf::host
