// SPDX-License-Identifier: MIT
// The GPIO runner's loop (tick_loop.h) with a real Device<2> and HostLink on
// a virtual clock that stalls once for 50 ticks in the middle of a move: the
// recorded steps are never closer than one tick period and never faster than
// the speed limit. The runner's old policy (an absolute schedule that fires
// the missed ticks back to back) runs through the same loop as the reference
// that must fail both checks.
#include "../fdsurf/runners/tick_loop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/hal/tick_scheduler.h"
#include "fdsurf/host/link.h"
#include "fdsurf/protocol/messages.h"
#include "fdsurf/sim/checks.h"

namespace fdsurf::host {
namespace {

constexpr std::uint32_t kTickHz = 10000;
constexpr std::uint64_t kPeriod = 1'000'000 / kTickHz;
constexpr std::uint32_t kMaxRate = 8000;  // steps/s: 0.8 steps per tick
constexpr std::uint32_t kAccel = 160000;

// The simulated clock the outputs record with; the sleep numbered
// `stall_at` wakes `stall_us` late, as a preempted process would.
class StallingClock final : public hal::Clock {
 public:
  StallingClock(hal::SimClock& time, std::uint64_t stall_at, std::uint64_t stall_us)
      : time_(time), stall_at_(stall_at), stall_us_(stall_us) {}

 private:
  std::uint64_t DoNowMicros() override { return time_.now_us(); }
  void DoSleepUntilMicros(std::uint64_t t_us) override {
    time_.Set(t_us);
    if (sleeps_++ == stall_at_) time_.Advance(stall_us_);
  }
  hal::SimClock& time_;
  std::uint64_t stall_at_;
  std::uint64_t stall_us_;
  std::uint64_t sleeps_ = 0;
};

// The runner's policy before: next += period; sleep until next.
class CatchUpScheduler {
 public:
  CatchUpScheduler(hal::Clock& clock, std::uint64_t period_us)
      : clock_(clock), period_us_(period_us), next_(clock.NowMicros()) {}
  std::uint64_t WaitForNextTick() {
    next_ += period_us_;
    clock_.SleepUntilMicros(next_);
    return clock_.NowMicros();
  }

 private:
  hal::Clock& clock_;
  std::uint64_t period_us_;
  std::uint64_t next_;
};

protocol::Command Config() {
  protocol::Command command;
  command.type = protocol::MessageType::kConfig;
  protocol::MachineConfig& config = command.body.config;
  config = protocol::MachineConfig{};
  config.axes = 2;
  config.steps_per_meter[0] = config.steps_per_meter[1] = 80000;
  config.travel_steps[0] = config.travel_steps[1] = 4000;
  config.max_rate = kMaxRate;
  config.accel = kAccel;
  config.pen_delay_ms = 0;
  return command;
}

protocol::Command Move(std::int32_t x) {
  protocol::Command command;
  command.type = protocol::MessageType::kMove;
  command.body.move = protocol::MoveCommand{{x, 0, 0}};
  return command;
}

struct RunResult {
  sim::MotionReport report;
  std::vector<std::uint64_t> step_times;  // µs, one per Step() call
  std::int64_t position = 0;
  std::uint32_t executed = 0;
  bool finished = false;
};

// A 3000-step move (0.4 s: 500 ticks of acceleration, then cruising) with a
// stall of 50 ticks at tick 2000, at full speed.
template <class Scheduler>
RunResult MoveThroughAStall() {
  hal::SimClock time(1'000'000);
  StallingClock clock(time, 2000, 50 * kPeriod);
  hal::SimStepDir steppers(time, 2);
  hal::SimPen pen(time);
  auto device = std::make_unique<device::Device<2>>(kTickHz);
  HostLink link;
  EXPECT_TRUE(link.Enqueue(Config(), "config").ok());
  EXPECT_TRUE(link.Enqueue(Move(3000), "move").ok());
  Scheduler ticks(clock, kPeriod);
  const hal::IoStatus status =
      RunTickLoop(clock, ticks, link, *device, steppers, pen, [](std::uint64_t) {});
  EXPECT_EQ(status, hal::IoStatus::kOk);
  RunResult run;
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = kMaxRate;
  limits.accel = kAccel;
  run.report = sim::CheckMotion(steppers.events(), pen.events(), limits);
  for (const hal::StepDirEvent& e : steppers.events()) {
    if (e.axis_mask != 0) run.step_times.push_back(e.time_us);
  }
  run.position = steppers.position(0);
  run.executed = device->executed();
  run.finished = link.Finished();
  return run;
}

// The shortest time in which `n` + 1 consecutive steps were made, µs.
std::uint64_t ShortestSpan(const std::vector<std::uint64_t>& times, std::size_t n) {
  std::uint64_t shortest = UINT64_MAX;
  for (std::size_t i = 0; i + n < times.size(); ++i) {
    shortest = std::min(shortest, times[i + n] - times[i]);
  }
  return shortest;
}

// 8 steps at the speed limit take 1 ms; the device rounds to whole ticks.
constexpr std::uint64_t kEightStepsUs = 8 * 1'000'000 / kMaxRate - kPeriod;

TEST(GpioTickLoop, AStallStretchesTheMotionAndNeverCompressesIt) {
  const RunResult run = MoveThroughAStall<hal::TickScheduler>();
  ASSERT_TRUE(run.finished);
  EXPECT_EQ(run.executed, 2u);
  EXPECT_EQ(run.position, 3000);
  ASSERT_EQ(run.step_times.size(), 3000u);
  EXPECT_GE(ShortestSpan(run.step_times, 1), kPeriod);  // never two steps in one period
  EXPECT_GE(ShortestSpan(run.step_times, 8), kEightStepsUs);
  EXPECT_LE(run.report.max_speed, kMaxRate * 1.02);
  // Stretched: the 50 ticks of the stall are added to the ideal 0.4 s (+ a tick or two).
  EXPECT_GE(run.report.duration_s, 0.4 + 50.0 / kTickHz - 0.002);
}

TEST(GpioTickLoop, TheOldAbsoluteScheduleBurstsAfterTheStall) {
  // The reference policy fails both checks above: this is what they catch.
  const RunResult run = MoveThroughAStall<CatchUpScheduler>();
  ASSERT_TRUE(run.finished);
  EXPECT_EQ(run.position, 3000);
  ASSERT_EQ(run.step_times.size(), 3000u);
  EXPECT_EQ(ShortestSpan(run.step_times, 1), 0u);  // steps back to back
  EXPECT_EQ(ShortestSpan(run.step_times, 8), 0u);  // 40 of them in no time
}

}  // namespace
}  // namespace fdsurf::host
