// SPDX-License-Identifier: MIT
// The Linux real-time clock: monotonic, and never wakes early.
#include "fdsurf/hal/monotonic_clock.h"

#include <gtest/gtest.h>

namespace fdsurf::hal {
namespace {

TEST(MonotonicClock, SleepsUntilTheAbsoluteTimeNeverEarly) {
  MonotonicClock clock;
  Clock& base = clock;
  const uint64_t start = base.NowMicros();
  for (uint64_t target = start + 1000; target <= start + 5000; target += 1000) {
    base.SleepUntilMicros(target);
    EXPECT_GE(base.NowMicros(), target);
  }
  const uint64_t before = base.NowMicros();
  base.SleepUntilMicros(start);  // in the past: returns at once
  EXPECT_LT(base.NowMicros() - before, 100000u);
}

TEST(MonotonicClock, BusyWaitReachesItsTarget) {
  const uint64_t target = MonotonicClock::Now() + 20;
  MonotonicClock::BusyWaitUntil(target);
  EXPECT_GE(MonotonicClock::Now(), target);
}

}  // namespace
}  // namespace fdsurf::hal
