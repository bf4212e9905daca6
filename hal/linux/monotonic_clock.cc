// SPDX-License-Identifier: MIT
#include "fdsurf/hal/monotonic_clock.h"

#include <time.h>

#include <cerrno>

namespace fdsurf {
namespace hal {

uint64_t MonotonicClock::Now() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);  // cannot fail for CLOCK_MONOTONIC
  return static_cast<uint64_t>(now.tv_sec) * 1000000u + static_cast<uint64_t>(now.tv_nsec) / 1000u;
}

void MonotonicClock::BusyWaitUntil(uint64_t t_us) {
  while (Now() < t_us) {
  }
}

void MonotonicClock::DoSleepUntilMicros(uint64_t t_us) {
  timespec until{};
  until.tv_sec = static_cast<time_t>(t_us / 1000000u);
  until.tv_nsec = static_cast<long>(t_us % 1000000u) * 1000;
  // clock_nanosleep returns the error number itself (not -1/errno); EINTR
  // means a signal arrived: sleep again towards the same absolute time.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr) == EINTR) {
  }
}

}  // namespace hal
}  // namespace fdsurf
