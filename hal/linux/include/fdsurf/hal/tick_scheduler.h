// SPDX-License-Identifier: MIT
// When the step timer of a host-driven motion loop fires: one tick every
// period, and never two ticks closer than one period.
//
// A loop on a real clock wakes late (scheduling latency, a stall of the whole
// process). Catching up on the ticks a stall has missed would fire them back
// to back and compress the motion beyond the speed limit; instead, the next
// tick is due one period after the tick that actually happened, so a late tick
// stretches the motion and never compresses it. A stall can also come inside
// a tick, after the wake-up and before the tick's line writes; EndTick()
// after the writes then moves the next tick a period past them:
//
//   hal::TickScheduler ticks(clock, 100);   // 10 kHz
//   for (;;) {
//     ticks.WaitForNextTick();
//     device.Tick(steppers, pen);
//     ticks.EndTick();
//   }
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/clock.h"

namespace fdsurf {
namespace hal {

class TickScheduler {
 public:
  /// `period_us` ≥ 1. The first tick is due at once.
  TickScheduler(Clock& clock, uint64_t period_us) : clock_(clock), period_us_(period_us) {}

  /// The period of `tick_hz` (≥ 1) ticks a second, µs, rounded up: a rate
  /// above tick_hz would be a speed above the device's limits.
  static uint64_t PeriodOf(uint32_t tick_hz) { return (1'000'000u + tick_hz - 1) / tick_hz; }

  /// Sleeps until the next tick is due and returns the clock's time on
  /// waking: the time of this tick. Successive results are at least one
  /// period apart, however late any wake-up was.
  uint64_t WaitForNextTick();

  /// Called when the tick's work (its outputs) is done. If that is more than
  /// half a period after the tick, the work was stalled (the process was
  /// preempted, the host stalled a guest) and its writes came late: the next
  /// tick is then due one period after now, not after the tick, so the next
  /// writes do not follow these too soon. Counted in stalled_ticks(). A
  /// tick's ordinary work (well under half a period) changes nothing, so
  /// the tick rate stays the configured one.
  void EndTick();

  FDSURF_NODISCARD uint64_t period_us() const { return period_us_; }
  /// Ticks so far.
  FDSURF_NODISCARD uint64_t ticks() const { return ticks_; }
  /// Ticks that came one period or more after they were due: at least one
  /// tick's worth of motion was delayed there.
  FDSURF_NODISCARD uint64_t late_ticks() const { return late_ticks_; }
  /// The longest wake-up delay beyond the due time, µs.
  FDSURF_NODISCARD uint64_t max_lateness_us() const { return max_lateness_us_; }
  /// Ticks whose work EndTick() found stalled past half a period.
  FDSURF_NODISCARD uint64_t stalled_ticks() const { return stalled_ticks_; }

 private:
  Clock& clock_;
  uint64_t period_us_;
  uint64_t last_tick_us_ = 0;
  uint64_t ticks_ = 0;
  uint64_t late_ticks_ = 0;
  uint64_t max_lateness_us_ = 0;
  uint64_t stalled_ticks_ = 0;
};

}  // namespace hal
}  // namespace fdsurf
