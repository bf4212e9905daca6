// SPDX-License-Identifier: MIT
// The real-time clock of a Linux host: CLOCK_MONOTONIC, slept on with
// clock_nanosleep(TIMER_ABSTIME) so that sleeps do not drift.
#pragma once

#include <stdint.h>

#include "fdsurf/hal/clock.h"

namespace fdsurf {
namespace hal {

class MonotonicClock final : public Clock {
 public:
  MonotonicClock() = default;
  ~MonotonicClock() = default;

  /// CLOCK_MONOTONIC in microseconds (since boot, roughly).
  static uint64_t Now();
  /// Spins (without sleeping) until Now() >= t_us: for pulse widths of a few
  /// microseconds, far below the scheduler's wake-up latency.
  static void BusyWaitUntil(uint64_t t_us);

 private:
  uint64_t DoNowMicros() override { return Now(); }
  /// Sleeps with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME), resuming
  /// after signals, so the wake-up time does not drift across calls.
  void DoSleepUntilMicros(uint64_t t_us) override;
};

}  // namespace hal
}  // namespace fdsurf
