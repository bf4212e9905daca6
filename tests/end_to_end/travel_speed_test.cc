// SPDX-License-Identifier: MIT
// Separate pen-up (travel) and pen-down speed limits (issue 15): the motion
// loop switches its limit where it passes a pen event (at rest), the device
// refuses a travel rate or axis acceleration it cannot serve, and the
// simulator's checks hold each run to its own limit.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/sim/checks.h"

namespace fdsurf {
namespace {

constexpr std::uint32_t kTickHz = 40000;
constexpr std::uint32_t kDrawRate = 4000;    // steps/s, pen down
constexpr std::uint32_t kTravelRate = 8000;  // steps/s, pen up
constexpr std::uint32_t kAccel = 160000;     // steps/s²
constexpr int kRunSteps = 3000;              // per run: long enough to cruise at either speed

struct Recording {
  std::vector<hal::StepDirEvent> steps;
  std::vector<hal::PenEvent> pens;
};

// Pen up: a run along +x; pen down: a run along +y; pen up: a run along -x.
// The loop is fed as a producer would, whenever it has room.
Recording RunThreeStrokes() {
  motion::TickLimits limits{};
  EXPECT_TRUE(
      motion::ToTickLimits({kTickHz, kDrawRate, kAccel, 10, kTravelRate, {0, 0, 0}, 1}, &limits));
  EXPECT_EQ(limits.max_speed, 1677721u);     // 4000·2^24/40000, rounded down
  EXPECT_EQ(limits.travel_speed, 3355443u);  // 8000·2^24/40000, rounded down
  std::vector<std::uint8_t> storage(1024);
  motion::MotionLoop loop(storage.data(), 1024);
  loop.Configure(limits);
  std::vector<std::uint8_t> entries;
  const std::int32_t plus_x[2] = {1, 0};
  const std::int32_t plus_y[2] = {0, 1};
  const std::int32_t minus_x[2] = {-1, 0};
  for (int i = 0; i < kRunSteps; ++i) entries.push_back(motion::MakeMove(plus_x, 2));
  entries.push_back(motion::MakeEntry(motion::EntryKind::kPenDown));
  for (int i = 0; i < kRunSteps; ++i) entries.push_back(motion::MakeMove(plus_y, 2));
  entries.push_back(motion::MakeEntry(motion::EntryKind::kPenUp));
  for (int i = 0; i < kRunSteps; ++i) entries.push_back(motion::MakeMove(minus_x, 2));
  Recording r;
  std::size_t next = 0;
  for (std::uint64_t tick = 0; tick < 10'000'000; ++tick) {
    while (next < entries.size() && loop.Push(entries[next])) ++next;
    if (next == entries.size() && loop.Idle()) break;
    const motion::TickOutput out = loop.Tick();
    const std::uint64_t us = tick * (1'000'000 / kTickHz);
    if (out.step_mask != 0) r.steps.push_back({us, out.step_mask, out.negative_mask, true});
    if (out.pen != 0) r.pens.push_back({us, out.pen > 0});
  }
  EXPECT_EQ(next, entries.size());
  EXPECT_TRUE(loop.Idle());
  return r;
}

sim::MotionLimitsSi Limits(double travel_rate) {
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = kDrawRate;
  limits.travel_rate = travel_rate;
  limits.accel = kAccel;
  limits.pen_delay_s = 0.010;
  return limits;
}

TEST(TravelSpeed, PenUpReachesTheTravelRateAndPenDownKeepsMaxRate) {
  const Recording r = RunThreeStrokes();
  ASSERT_EQ(r.steps.size(), 3u * kRunSteps);
  ASSERT_EQ(r.pens.size(), 2u);
  const sim::MotionReport report = sim::CheckMotion(r.steps, r.pens, Limits(kTravelRate));
  EXPECT_EQ(report.violations, 0u) << report.first_violation;
  // Travel cruises at (nearly) twice the drawing speed; drawing stays at its own.
  EXPECT_GT(report.max_travel_speed, 0.97 * kTravelRate);
  EXPECT_LE(report.max_travel_speed, kTravelRate * 1.001 + 50);  // + one step per 20 ms window
  EXPECT_GT(report.max_draw_speed, 0.97 * kDrawRate);
  EXPECT_LE(report.max_draw_speed, kDrawRate * 1.001 + 50);
}

TEST(TravelSpeed, TheCheckHoldsPenUpRunsToTheirOwnLimit) {
  const Recording r = RunThreeStrokes();
  // Checked as if travel had to keep max_rate too: the fast travel is caught.
  const sim::MotionReport one_limit = sim::CheckMotion(r.steps, r.pens, Limits(0));
  EXPECT_GT(one_limit.violations, 0u);
  // And pen-up runs are held to travel_rate itself, not to the larger
  // limit: with the two swapped, the travel (x, the first run) is too fast.
  sim::MotionLimitsSi swapped = Limits(kDrawRate);
  swapped.max_rate = kTravelRate;
  const sim::MotionReport report = sim::CheckMotion(r.steps, r.pens, swapped);
  EXPECT_GT(report.violations, 0u);
  EXPECT_NE(report.first_violation.find("axis 0"), std::string::npos) << report.first_violation;
}

TEST(TravelSpeed, ToTickLimitsRefusesATravelRateTheLoopCannotServe) {
  motion::TickLimits limits{};
  EXPECT_FALSE(
      motion::ToTickLimits({kTickHz, kDrawRate, kAccel, 0, kTickHz + 1, {0, 0, 0}, 1}, &limits));
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, kDrawRate, kAccel, 0, 0, {0, 0, 0}, 1}, &limits));
  // accel above the travel speed per tick (a·1 tick > v_max): refused as for max_rate.
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, kDrawRate, kAccel, 0, 1, {0, 0, 0}, 1}, &limits));
  EXPECT_TRUE(
      motion::ToTickLimits({kTickHz, kDrawRate, kAccel, 0, kTickHz, {0, 0, 0}, 1}, &limits));
  EXPECT_EQ(limits.travel_speed, 1u << 24);  // one unit move per tick
}

protocol::Command ConfigCommand() {
  protocol::Command command;
  command.type = protocol::MessageType::kConfig;
  protocol::MachineConfig& config = command.body.config;
  config = protocol::MachineConfig{};
  config.axes = 2;
  config.steps_per_meter[0] = config.steps_per_meter[1] = 80000;
  config.travel_steps[0] = config.travel_steps[1] = 4000;
  config.max_rate = kDrawRate;
  config.accel = kAccel;
  config.pen_delay_ms = 10;
  config.travel_rate = kTravelRate;
  config.axis_accel[0] = config.axis_accel[1] = 2 * kAccel;
  return command;
}

TEST(TravelSpeed, DeviceRefusesTravelRateAndAxisAccelItCannotServe) {
  device::Device<2, 4, 256> device(kTickHz);
  std::uint8_t detail = 0;
  protocol::Command config = ConfigCommand();
  config.body.config.travel_rate = kTickHz + 1;
  EXPECT_EQ(device.Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldTravelRate);
  // An axis limit must exceed the path's per tick (the excess is the turn
  // budget). At 40 kHz the path's 160000 steps/s² is ⌊160000·2^24/1.6e9⌋ =
  // 1677 units per tick²; so is an axis's 160026, while 160027 gives 1678.
  config = ConfigCommand();
  config.body.config.axis_accel[1] = kAccel;
  EXPECT_EQ(device.Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldAxisAccel + 1);
  config = ConfigCommand();
  config.body.config.axis_accel[0] = 160026;
  EXPECT_EQ(device.Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldAxisAccel);
  config = ConfigCommand();
  config.body.config.axis_accel[0] = 160027;
  EXPECT_EQ(device.Accept(config, &detail), protocol::ErrorCode::kNone);
  EXPECT_EQ(device.Credits(), 3);  // only the last was queued
}

}  // namespace
}  // namespace fdsurf
