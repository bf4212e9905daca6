// SPDX-License-Identifier: MIT
// A monotonic microsecond clock for the motion loop: real (CLOCK_MONOTONIC on
// Linux, a timer on an MCU) or virtual (the simulator).
//
// Pigweed style: non-virtual public methods, private pure virtual Do...(),
// protected non-virtual destructor.
#pragma once

#include <stdint.h>

namespace fdsurf {
namespace hal {

class Clock {
 public:
  Clock(const Clock&) = delete;
  Clock& operator=(const Clock&) = delete;

  /// Microseconds since an arbitrary fixed origin; never decreases. Cannot
  /// fail.
  uint64_t NowMicros() { return DoNowMicros(); }

  /// Returns once NowMicros() >= `t_us` (at once if that time has passed).
  /// Real clocks may return a little late (scheduling latency), never early.
  /// Cannot fail.
  void SleepUntilMicros(uint64_t t_us) { DoSleepUntilMicros(t_us); }

 protected:
  Clock() = default;
  ~Clock() = default;

 private:
  virtual uint64_t DoNowMicros() = 0;
  virtual void DoSleepUntilMicros(uint64_t t_us) = 0;
};

}  // namespace hal
}  // namespace fdsurf
