// SPDX-License-Identifier: MIT
#include "fdsurf/hal/tick_scheduler.h"

namespace fdsurf {
namespace hal {

uint64_t TickScheduler::WaitForNextTick() {
  // Due one period after the previous tick as it happened, not as it was
  // scheduled: ticks missed while late are not made up.
  const uint64_t due = ticks_ == 0 ? clock_.NowMicros() : last_tick_us_ + period_us_;
  clock_.SleepUntilMicros(due);
  const uint64_t now = clock_.NowMicros();  // never before `due` (Clock's contract)
  const uint64_t lateness = now > due ? now - due : 0;
  if (lateness >= period_us_) ++late_ticks_;
  if (lateness > max_lateness_us_) max_lateness_us_ = lateness;
  last_tick_us_ = now;
  ++ticks_;
  return now;
}

void TickScheduler::EndTick() {
  const uint64_t now = clock_.NowMicros();
  if (now - last_tick_us_ <= period_us_ / 2) return;
  ++stalled_ticks_;
  last_tick_us_ = now;
}

}  // namespace hal
}  // namespace fdsurf
