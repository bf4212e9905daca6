// SPDX-License-Identifier: MIT
// The GPIO runner's real-time loop, apart from the GPIO lines so that it runs
// in tests on a fake clock and recorded outputs: the firmware's Device is
// serviced every 16 ticks (link out, replies in, Fill), and ticked on a
// TickScheduler, so no two ticks are closer than one period: a stall of the
// host stretches the motion and never compresses it. The ticks go on while
// the job pauses between layers (RunIdleTicks).
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

/// Runs `device` with `link` while `keep_going()` (asked before every
/// tick), one Tick per `ticks.WaitForNextTick()`, then `ticks.EndTick()`
/// (a hal::TickScheduler; tests pass other policies). `on_service(now_us)` is called after each
/// service (for progress). Returns kOk, or the status of the first Tick that
/// failed (the outputs' LastError() says why).
template <class Device, class Ticks, class OnService, class KeepGoing>
hal::IoStatus RunTickLoopWhile(hal::Clock& clock, Ticks& ticks, HostLink& link, Device& device,
                               hal::StepDirOutputs& steppers, hal::PenOutput& pen,
                               OnService on_service, KeepGoing keep_going) {
  std::vector<std::uint8_t> out;
  std::uint8_t in[256];
  for (std::uint64_t n = 0; keep_going(); ++n) {
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
    ticks.EndTick();
  }
  return hal::IoStatus::kOk;
}

/// The same until the link has finished (every command enqueued so far
/// executed, the device idle) or failed.
template <class Device, class Ticks, class OnService>
hal::IoStatus RunTickLoop(hal::Clock& clock, Ticks& ticks, HostLink& link, Device& device,
                          hal::StepDirOutputs& steppers, hal::PenOutput& pen,
                          OnService on_service) {
  return RunTickLoopWhile(clock, ticks, link, device, steppers, pen, on_service,
                          [&link] { return !link.Finished() && !link.Failed(); });
}

/// What the pause between layers runs, slice by slice: `count` more ticks of
/// the same loop. The device rests with the pen up then, so its Tick() moves
/// nothing and the outputs keep that safe state (the motors stay enabled and
/// hold the position across the pen change); the ticks keep the scheduler's
/// schedule, so that the pause is not taken for one very late tick.
template <class Device, class Ticks>
hal::IoStatus RunIdleTicks(hal::Clock& clock, Ticks& ticks, HostLink& link, Device& device,
                           hal::StepDirOutputs& steppers, hal::PenOutput& pen,
                           std::uint64_t count) {
  return RunTickLoopWhile(
      clock, ticks, link, device, steppers, pen, [](std::uint64_t) {},
      [&count] { return count-- > 0; });
}

}  // namespace fdsurf::host
