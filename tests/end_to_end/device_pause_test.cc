// SPDX-License-Identifier: MIT
// PAUSE, RESUME and HALT on the firmware's Device (protocol version 3,
// docs/protocol.md): a pause comes to rest along the path within the
// braking distance, lifts the pen, holds and goes on where it stopped, so
// that the steps drawn with a pause are exactly the steps drawn without;
// HALT drops everything at once, lifts the pen and disables the drivers.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/sim/checks.h"

namespace fdsurf {
namespace {

constexpr std::uint32_t kTickHz = 40000;
constexpr std::uint32_t kMaxRate = 8000;
constexpr std::uint32_t kAccel = 160000;
constexpr std::uint16_t kPenDelayMs = 10;

protocol::Command ConfigCommand() {
  protocol::Command command;
  command.type = protocol::MessageType::kConfig;
  protocol::MachineConfig& config = command.body.config;
  config = protocol::MachineConfig{};
  config.axes = 2;
  config.steps_per_meter[0] = config.steps_per_meter[1] = 80000;
  config.travel_steps[0] = config.travel_steps[1] = 4000;
  config.max_rate = kMaxRate;
  config.accel = kAccel;
  config.pen_delay_ms = kPenDelayMs;
  config.travel_rate = config.max_rate;
  config.axis_accel[0] = config.axis_accel[1] = 2 * config.accel;
  return command;
}

protocol::Command PenCommand(bool down) {
  protocol::Command command;
  command.type = protocol::MessageType::kPen;
  command.body.pen.down = down;
  return command;
}

// A quarter circle of radius r about (cx, cy) from angle a0, as a Bézier.
protocol::Command QuarterCircle(double cx, double cy, double r, double a0) {
  const double k = 4 * (std::sqrt(2.0) - 1) / 3;
  const double a1 = a0 + std::acos(-1.0) / 2;
  const std::array<std::array<double, 2>, 4> b = {{
      {cx + r * std::cos(a0), cy + r * std::sin(a0)},
      {cx + r * (std::cos(a0) - k * std::sin(a0)), cy + r * (std::sin(a0) + k * std::cos(a0))},
      {cx + r * (std::cos(a1) + k * std::sin(a1)), cy + r * (std::sin(a1) - k * std::cos(a1))},
      {cx + r * std::cos(a1), cy + r * std::sin(a1)},
  }};
  protocol::Command curve;
  curve.type = protocol::MessageType::kCurve;
  curve.body.curve = protocol::CurveCommand{};
  curve.body.curve.basis = Basis::kBezier;
  curve.body.curve.dims = 2;
  curve.body.curve.tolerance_q8 = 256;
  for (int i = 0; i < 4; ++i) {
    for (int axis = 0; axis < 2; ++axis) {
      curve.body.curve.geometry[axis].g[i] =
          GeometryFixed::FromRaw(std::llround(b[i][axis] * 65536));
    }
  }
  return curve;
}

// Pen down, a circle of four quarters, pen up: 6 commands after the config.
std::vector<protocol::Command> CircleJob() {
  std::vector<protocol::Command> job = {ConfigCommand(), PenCommand(true)};
  for (int q = 0; q < 4; ++q)
    job.push_back(QuarterCircle(2000, 2000, 1500, q * 1.5707963267948966));
  job.push_back(PenCommand(false));
  return job;
}

// A device on the sim HAL with the circle job fed to it as credit allows.
struct Rig {
  using Device = device::Device<2, 4, 256>;
  Rig() : steps_(clock_, 2), pen_(clock_), device_(kTickHz) {}

  // Feeds the job's commands as credit allows (as the link would).
  void Feed() {
    while (next_ < job_.size() && device_.Credits() > 0) {
      std::uint8_t detail = 0;
      ASSERT_EQ(device_.Accept(job_[next_], &detail), protocol::ErrorCode::kNone);
      ++next_;
    }
  }
  void Turn() {
    Feed();
    device_.Fill();
    ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
    clock_.Advance(1'000'000 / kTickHz);
  }
  void RunUntilIdle() {
    for (int t = 0; t < 40'000'000; ++t) {
      Turn();
      if (next_ == job_.size() && device_.Idle() && Status().state == protocol::DeviceState::kIdle)
        return;
    }
    FAIL() << "not idle";
  }
  protocol::StatusReport Status() {
    protocol::StatusReport report{};
    device_.FillStatus(&report);
    return report;
  }
  // The step pulses only (masks and directions), without times or enables.
  std::vector<std::array<std::uint8_t, 2>> Path() const {
    std::vector<std::array<std::uint8_t, 2>> path;
    for (const hal::StepDirEvent& e : steps_.events()) {
      if (e.axis_mask != 0) path.push_back({e.axis_mask, e.negative_mask});
    }
    return path;
  }
  std::size_t StepCount() const { return Path().size(); }

  std::vector<protocol::Command> job_ = CircleJob();
  std::size_t next_ = 0;
  hal::SimClock clock_;
  hal::SimStepDir steps_;
  hal::SimPen pen_;
  Device device_;
};

sim::MotionLimitsSi Limits() {
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = kMaxRate;
  limits.accel = kAccel;
  limits.pen_delay_s = kPenDelayMs * 1e-3;
  return limits;
}

std::vector<std::array<std::uint8_t, 2>> PathWithoutPause() {
  Rig plain;
  plain.RunUntilIdle();
  return plain.Path();
}

class PauseTest : public ::testing::Test, protected Rig {};

TEST_F(PauseTest, APauseMidCurveRestsWithinTheBrakingDistanceAndDrawsTheSamePath) {
  const std::vector<std::array<std::uint8_t, 2>> reference = PathWithoutPause();
  ASSERT_GT(reference.size(), 5000u);
  for (int t = 0; t < 20000; ++t) Turn();  // 0.5 s: at full speed on the first quarter
  ASSERT_TRUE(pen_.down());
  const std::size_t at_pause = StepCount();
  device_.Pause();
  EXPECT_EQ(Status().state, protocol::DeviceState::kPaused);
  for (int t = 0; t < 8000; ++t) Turn();  // 0.2 s: decelerated and the pen lifted
  const std::size_t at_rest = StepCount();
  // v²/2a at 8000 steps/s and 160000 steps/s² is 200 steps (+ 2 for the
  // discrete profile's rounding).
  EXPECT_GT(at_rest, at_pause);
  EXPECT_LE(at_rest - at_pause, 200u * 2 + 2);  // path steps, diagonal ones count once
  EXPECT_FALSE(pen_.down());
  EXPECT_FALSE(Status().pen_down);
  EXPECT_EQ(Status().state, protocol::DeviceState::kPaused);
  // Holding: nothing moves for 1 s, whatever arrives meanwhile.
  for (int t = 0; t < 40000; ++t) Turn();
  EXPECT_EQ(StepCount(), at_rest);
  EXPECT_FALSE(pen_.down());
  const std::size_t pen_events = pen_.events().size();
  device_.Resume();
  for (int t = 0; t < 10; ++t) Turn();
  EXPECT_TRUE(pen_.down());  // lowered where it left off, before any step
  EXPECT_EQ(StepCount(), at_rest);
  EXPECT_EQ(pen_.events().size(), pen_events + 1);
  RunUntilIdle();
  // Not a step lost or repeated: the same sequence of unit moves.
  EXPECT_EQ(Path(), reference);
  EXPECT_EQ(Status().executed, job_.size());
  // The limits held through the pause: deceleration, pen delays, restart.
  const sim::MotionReport report = sim::CheckMotion(steps_.events(), pen_.events(), Limits());
  EXPECT_EQ(report.violations, 0u) << report.first_violation;
}

TEST_F(PauseTest, AResumeWhileDeceleratingGoesOnAndAPauseWithThePenUpLeavesItUp) {
  const std::vector<std::array<std::uint8_t, 2>> reference = PathWithoutPause();
  for (int t = 0; t < 20000; ++t) Turn();
  device_.Pause();
  for (int t = 0; t < 500; ++t) Turn();  // not at rest yet
  const std::size_t pen_events = pen_.events().size();
  device_.Resume();
  EXPECT_EQ(Status().state, protocol::DeviceState::kRunning);
  for (int t = 0; t < 4000; ++t) Turn();
  EXPECT_EQ(pen_.events().size(), pen_events);  // never lifted
  RunUntilIdle();
  EXPECT_EQ(Path(), reference);
  // At the end the pen is up: a pause now changes no pen and holds.
  ASSERT_FALSE(pen_.down());
  device_.Pause();
  for (int t = 0; t < 2000; ++t) Turn();
  EXPECT_EQ(Status().state, protocol::DeviceState::kPaused);
  EXPECT_EQ(pen_.events().size(), pen_events + 1);  // only the job's own final lift
  device_.Resume();
  Turn();
  EXPECT_EQ(Status().state, protocol::DeviceState::kIdle);
}

TEST_F(PauseTest, StopDuringAPauseDropsTheRestAndLeavesThePenUp) {
  for (int t = 0; t < 20000; ++t) Turn();
  device_.Pause();
  for (int t = 0; t < 20000; ++t) Turn();
  ASSERT_FALSE(pen_.down());
  device_.Stop();
  for (int t = 0; t < 2000; ++t) Turn();
  EXPECT_EQ(Status().state, protocol::DeviceState::kIdle);
  EXPECT_FALSE(pen_.down());
  EXPECT_FALSE(Status().pen_down);
  const std::size_t steps = StepCount();
  device_.Resume();  // nothing to resume
  for (int t = 0; t < 2000; ++t) Turn();
  EXPECT_EQ(StepCount(), steps);
}

TEST_F(PauseTest, HaltStopsAtOnceLiftsThePenAndDisablesTheDrivers) {
  for (int t = 0; t < 20000; ++t) Turn();
  ASSERT_TRUE(pen_.down());
  ASSERT_TRUE(steps_.enabled());
  ASSERT_GT(device_.motion().speed(), 0u);
  const std::size_t at_halt = StepCount();
  device_.Halt();
  Turn();
  EXPECT_FALSE(pen_.down());
  EXPECT_FALSE(steps_.enabled());
  EXPECT_EQ(StepCount(), at_halt);  // no deceleration: not one more step
  next_ = job_.size();              // the host sends nothing more
  for (int t = 0; t < 2000; ++t) Turn();
  EXPECT_EQ(StepCount(), at_halt);
  const protocol::StatusReport status = Status();
  EXPECT_EQ(status.state, protocol::DeviceState::kIdle);
  EXPECT_EQ(status.queued, 0);
  EXPECT_FALSE(status.pen_down);
  EXPECT_FALSE(steps_.enabled());
  // Work is accepted again, and enables the drivers with its first step.
  std::uint8_t detail = 0;
  protocol::Command move;
  move.type = protocol::MessageType::kMove;
  move.body.move.target[0] = 100;
  move.body.move.target[1] = 100;
  move.body.move.target[2] = 0;
  ASSERT_EQ(device_.Accept(move, &detail), protocol::ErrorCode::kNone);
  for (int t = 0; t < 40000 && !device_.Idle(); ++t) Turn();
  EXPECT_TRUE(steps_.enabled());
  EXPECT_EQ(Status().position[0], 100);
}

}  // namespace
}  // namespace fdsurf
