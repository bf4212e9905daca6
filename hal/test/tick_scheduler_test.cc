// SPDX-License-Identifier: MIT
// The tick scheduling of a host-driven motion loop: late wake-ups stretch the
// tick sequence and never compress it. The old policy (an absolute schedule,
// next += period, which fires the ticks a stall missed back to back) is kept
// here as the reference the checks must catch.
#include "fdsurf/hal/tick_scheduler.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace fdsurf::hal {
namespace {

constexpr std::uint64_t kPeriod = 100;  // µs: 10 kHz

// A clock whose sleeps wake exactly on time, except for the injected delays:
// the sleep numbered `stall_at` wakes `stall_us` late, and every sleep up to
// `jitter_us` late (seeded).
class FakeClock final : public Clock {
 public:
  FakeClock(std::uint64_t stall_at, std::uint64_t stall_us, std::uint64_t jitter_us = 0)
      : stall_at_(stall_at), stall_us_(stall_us), jitter_us_(jitter_us) {}
  FDSURF_NODISCARD std::uint64_t sleeps() const { return sleeps_; }
  /// Time passing while the tick works (a stall between the wake-up and
  /// the writes, when large).
  void Advance(std::uint64_t us) { now_ += us; }

 private:
  std::uint64_t DoNowMicros() override { return now_; }
  void DoSleepUntilMicros(std::uint64_t t_us) override {
    if (t_us > now_) now_ = t_us;
    if (sleeps_++ == stall_at_) now_ += stall_us_;
    if (jitter_us_ != 0) now_ += random_() % (jitter_us_ + 1);
  }
  std::uint64_t now_ = 1'000'000;
  std::uint64_t sleeps_ = 0;
  std::uint64_t stall_at_;
  std::uint64_t stall_us_;
  std::uint64_t jitter_us_;
  std::mt19937_64 random_{12};
};

// The policy the GPIO runner had: ticks on an absolute schedule.
class CatchUpScheduler {
 public:
  CatchUpScheduler(Clock& clock, std::uint64_t period_us)
      : clock_(clock), period_us_(period_us), next_(clock.NowMicros()) {}
  std::uint64_t WaitForNextTick() {
    next_ += period_us_;
    clock_.SleepUntilMicros(next_);
    return clock_.NowMicros();
  }

 private:
  Clock& clock_;
  std::uint64_t period_us_;
  std::uint64_t next_;
};

template <class Scheduler>
std::vector<std::uint64_t> TickTimes(Scheduler& scheduler, int count) {
  std::vector<std::uint64_t> times;
  for (int i = 0; i < count; ++i) times.push_back(scheduler.WaitForNextTick());
  return times;
}

// The shortest time between two consecutive ticks.
std::uint64_t ShortestInterval(const std::vector<std::uint64_t>& times) {
  std::uint64_t shortest = UINT64_MAX;
  for (std::size_t i = 1; i < times.size(); ++i) {
    EXPECT_GE(times[i], times[i - 1]);
    shortest = std::min(shortest, times[i] - times[i - 1]);
  }
  return shortest;
}

TEST(TickScheduler, AStallStretchesTheTicksAndNeverBurstsAfterwards) {
  FakeClock clock(/*stall_at=*/100, /*stall_us=*/50 * kPeriod);
  TickScheduler scheduler(clock, kPeriod);
  const std::vector<std::uint64_t> times = TickTimes(scheduler, 400);
  EXPECT_EQ(ShortestInterval(times), kPeriod);
  // The stall shows as one long interval, and the ticks after it keep the
  // period: 400 ticks take 399 periods plus the stall.
  EXPECT_EQ(times.back() - times.front(), 399 * kPeriod + 50 * kPeriod);
  EXPECT_EQ(scheduler.ticks(), 400u);
  EXPECT_EQ(scheduler.late_ticks(), 1u);
  EXPECT_EQ(scheduler.max_lateness_us(), 50 * kPeriod);
}

TEST(TickScheduler, TheOldAbsoluteScheduleFailsTheSameCheck) {
  // The reference: after the stall the 50 missed ticks come back to back.
  FakeClock clock(100, 50 * kPeriod);
  CatchUpScheduler scheduler(clock, kPeriod);
  const std::vector<std::uint64_t> times = TickTimes(scheduler, 400);
  EXPECT_EQ(ShortestInterval(times), 0u);
  std::size_t compressed = 0;
  for (std::size_t i = 1; i < times.size(); ++i) compressed += times[i] - times[i - 1] < kPeriod;
  EXPECT_EQ(compressed, 50u);
}

TEST(TickScheduler, JitterNeverBringsTwoTicksCloserThanAPeriod) {
  // Every wake-up up to 0.9 periods late, and a stall: intervals vary
  // between one period and the stall, never below.
  FakeClock clock(700, 50 * kPeriod, 90);
  TickScheduler scheduler(clock, kPeriod);
  const std::vector<std::uint64_t> times = TickTimes(scheduler, 2000);
  EXPECT_GE(ShortestInterval(times), kPeriod);
  EXPECT_EQ(scheduler.late_ticks(), 1u);
  // The absolute schedule under the same jitter compresses intervals.
  FakeClock old_clock(700, 50 * kPeriod, 90);
  CatchUpScheduler old(old_clock, kPeriod);
  EXPECT_LT(ShortestInterval(TickTimes(old, 2000)), kPeriod);
}

TEST(TickScheduler, TheFirstTickIsDueAtOnceAndEachSleepsOnce) {
  FakeClock clock(UINT64_MAX, 0);
  TickScheduler scheduler(clock, kPeriod);
  EXPECT_EQ(scheduler.WaitForNextTick(), 1'000'000u);
  EXPECT_EQ(scheduler.WaitForNextTick(), 1'000'000u + kPeriod);
  EXPECT_EQ(clock.sleeps(), 2u);
  EXPECT_EQ(scheduler.late_ticks(), 0u);
  EXPECT_EQ(scheduler.period_us(), kPeriod);
}

// The time of each tick's writes, made `work_us` after the wake-up, and
// `stall_us` after it at tick `stall_at`; EndTick() after them when
// `end_tick`.
std::vector<std::uint64_t> WriteTimes(bool end_tick, int stall_at, std::uint64_t stall_us,
                                      std::uint64_t work_us) {
  FakeClock clock(UINT64_MAX, 0);
  TickScheduler scheduler(clock, kPeriod);
  std::vector<std::uint64_t> writes;
  for (int i = 0; i < 400; ++i) {
    scheduler.WaitForNextTick();
    clock.Advance(i == stall_at ? stall_us : work_us);
    writes.push_back(clock.NowMicros());
    if (end_tick) scheduler.EndTick();
  }
  EXPECT_EQ(scheduler.stalled_ticks(), end_tick && stall_us > kPeriod / 2 ? 1u : 0u);
  return writes;
}

TEST(TickScheduler, AStallInsideATickDelaysTheNextTickPastItsWrites) {
  // 1.5 periods between a wake-up and its writes: without EndTick() the
  // next tick, already due, writes its work's 5 µs after them.
  EXPECT_EQ(ShortestInterval(WriteTimes(false, 100, 3 * kPeriod / 2, 5)), 5u);
  EXPECT_EQ(ShortestInterval(WriteTimes(true, 100, 3 * kPeriod / 2, 5)), kPeriod);
  // Ordinary work moves nothing: 400 ticks in 399 periods, as without it.
  const std::vector<std::uint64_t> plain = WriteTimes(true, -1, 0, kPeriod / 2);
  EXPECT_EQ(plain.back() - plain.front(), 399 * kPeriod);
}

}  // namespace
}  // namespace fdsurf::hal
