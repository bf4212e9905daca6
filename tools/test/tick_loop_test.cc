// SPDX-License-Identifier: MIT
// The GPIO runner's loop (tick_loop.h) with a real Device<2> and HostLink on
// a virtual clock that stalls once for 50 ticks in the middle of a move: the
// recorded steps are never closer than one tick period and never faster than
// the speed limit. The runner's old policy (an absolute schedule that fires
// the missed ticks back to back) runs through the same loop as the reference
// that must fail both checks. Also the pause between layers: the loop keeps
// ticking with the outputs at rest (RunIdleTicks).
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
  void EndTick() {}  // it had no such step

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
  config.travel_rate = kMaxRate;
  config.axis_accel[0] = config.axis_accel[1] = 2 * kAccel;
  return command;
}

protocol::Command Move(std::int32_t x) {
  protocol::Command command;
  command.type = protocol::MessageType::kMove;
  command.body.move = protocol::MoveCommand{{x, 0, 0}};
  return command;
}

protocol::Command Pen(bool down) {
  protocol::Command command;
  command.type = protocol::MessageType::kPen;
  command.body.pen.down = down ? 1 : 0;
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

// Two layers as the GPIO runner runs them: layer 1 (CONFIG, pen down, a
// 1000-step line, pen up) to the end, a pause of `pause_ticks` idle ticks
// (RunIdleTicks) or, with `tick_during_pause` false, the same time without
// ticks, then layer 2 (pen down, a line back to 0, pen up).
struct LayeredRun {
  std::size_t step_events_at_pause = 0;
  std::size_t pen_events_at_pause = 0;
  std::size_t step_events_after_pause = 0;
  std::size_t pen_events_after_pause = 0;
  std::uint32_t executed_at_pause = 0;
  bool pen_down_at_pause = true;
  bool idle_at_pause = false;
  std::uint64_t pause_ticks = 0;  // ticks made during the pause
  std::uint64_t late_ticks_before_layer2 = 0;
  std::uint64_t late_ticks = 0;
  std::uint64_t max_lateness_us = 0;
  std::uint32_t executed = 0;
  std::int64_t position = -1;
  bool finished = false;
  std::uint64_t violations = 0;
};

LayeredRun RunTwoLayers(std::uint64_t pause_ticks, bool tick_during_pause) {
  hal::SimClock time(1'000'000);
  StallingClock clock(time, UINT64_MAX, 0);
  hal::SimStepDir steppers(time, 2);
  hal::SimPen pen(time);
  auto device = std::make_unique<device::Device<2>>(kTickHz);
  HostLink link;
  hal::TickScheduler ticks(clock, kPeriod);
  const auto none = [](std::uint64_t) {};
  for (const protocol::Command& c : {Config(), Pen(true), Move(1000), Pen(false)}) {
    EXPECT_TRUE(link.Enqueue(c, "layer 1").ok());
  }
  EXPECT_EQ(RunTickLoop(clock, ticks, link, *device, steppers, pen, none), hal::IoStatus::kOk);
  LayeredRun run;
  run.step_events_at_pause = steppers.events().size();
  run.pen_events_at_pause = pen.events().size();
  run.executed_at_pause = device->executed();
  run.pen_down_at_pause = pen.down();
  run.idle_at_pause = device->Idle() && link.Finished();
  // The user takes the pause's time whatever the loop does meanwhile.
  const std::uint64_t pause_end = time.now_us() + pause_ticks * kPeriod;
  const std::uint64_t ticks_before_pause = ticks.ticks();
  if (tick_during_pause) {
    EXPECT_EQ(RunIdleTicks(clock, ticks, link, *device, steppers, pen, pause_ticks),
              hal::IoStatus::kOk);
  }
  time.Set(std::max(time.now_us(), pause_end));
  run.pause_ticks = ticks.ticks() - ticks_before_pause;
  run.step_events_after_pause = steppers.events().size();
  run.pen_events_after_pause = pen.events().size();
  run.late_ticks_before_layer2 = ticks.late_ticks();
  for (const protocol::Command& c : {Pen(true), Move(0), Pen(false)}) {
    EXPECT_TRUE(link.Enqueue(c, "layer 2").ok());
  }
  EXPECT_EQ(RunTickLoop(clock, ticks, link, *device, steppers, pen, none), hal::IoStatus::kOk);
  run.late_ticks = ticks.late_ticks();
  run.max_lateness_us = ticks.max_lateness_us();
  run.executed = device->executed();
  run.position = steppers.position(0);
  run.finished = link.Finished();
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = kMaxRate;
  limits.accel = kAccel;
  run.violations = sim::CheckMotion(steppers.events(), pen.events(), limits).violations;
  return run;
}

// A pause of 2 s (20000 ticks): nothing steps or moves the pen while it
// lasts, the device rests with the pen up and exactly layer 1 executed, the
// ticks keep their schedule (none late), and layer 2 then runs within the
// limits with every command executed once.
TEST(GpioTickLoop, ThePauseBetweenLayersKeepsTickingWithTheOutputsAtRest) {
  const LayeredRun run = RunTwoLayers(20000, true);
  EXPECT_EQ(run.executed_at_pause, 4u);
  EXPECT_TRUE(run.idle_at_pause);
  EXPECT_FALSE(run.pen_down_at_pause);
  EXPECT_EQ(run.step_events_after_pause, run.step_events_at_pause);
  EXPECT_EQ(run.pen_events_after_pause, run.pen_events_at_pause);
  EXPECT_EQ(run.pause_ticks, 20000u);
  EXPECT_EQ(run.late_ticks, 0u);
  ASSERT_TRUE(run.finished);
  EXPECT_EQ(run.executed, 7u);
  EXPECT_EQ(run.position, 0);
  EXPECT_EQ(run.violations, 0u);
}

TEST(GpioTickLoop, APauseWithoutTicksWouldBeReportedAsALateTick) {
  // Why the pause ticks: the same wait without ticks is one tick 2 s late,
  // which the runner's summary would report as a stretched motion.
  const LayeredRun run = RunTwoLayers(20000, false);
  ASSERT_TRUE(run.finished);
  EXPECT_EQ(run.late_ticks_before_layer2, 0u);
  EXPECT_EQ(run.late_ticks, 1u);
  EXPECT_GE(run.max_lateness_us, 20000 * kPeriod - kPeriod);
}

}  // namespace
}  // namespace fdsurf::host
