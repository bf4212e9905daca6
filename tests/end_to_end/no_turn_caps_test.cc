// SPDX-License-Identifier: MIT
// The motion loop of a device built without turn caps
// (FDSURF_DEVICE_TURN_CAPS=0, the Arduino Uno's firmware: the core variant
// fdsurf_core_narrow): it keeps every axis within its limit by the lower
// top speed of ToTickLimits() alone (docs/motion.md, "A device without turn
// caps"), checked by sim::CheckMotion on the same random strokes as the
// capped loop's test (turn_caps_test.cc).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/motion/turn_caps.h"
#include "fdsurf/sim/checks.h"
#include "random_strokes.h"

#if FDSURF_DEVICE_TURN_CAPS
#error "built against the core with turn caps: link fdsurf_core_narrow"
#endif

namespace fdsurf {
namespace {

using test::kTickHz;
using test::Machine;

TEST(NoTurnCaps, ToTickLimitsLowersBothSpeedsToWhereNoChordBinds) {
  motion::TickLimits limits{};
  // At 40 kHz: a = 1677 and a budget of ⌊√(3355² − 1677²)⌋ = 2905 (the
  // capped test's figures); ⌊√(2905·2^26/3)⌋ = 254 919, 2^-24 steps per
  // tick: 607.8 steps/s instead of 8000.
  ASSERT_TRUE(
      motion::ToTickLimits({kTickHz, 8000, 160000, 0, 6000, {320000, 640000, 0}, 1}, &limits));
  EXPECT_EQ(limits.turn_budget, 2905u);
  EXPECT_EQ(limits.max_speed, 254919u);
  EXPECT_EQ(limits.travel_speed, 254919u);
  // Slower than the bound, or no axis limit: the speeds are the configured
  // ones.
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 500, 16000, 0, 400, {320000, 640000, 0}, 1}, &limits));
  EXPECT_EQ(limits.max_speed, (500ull << 24) / kTickHz);
  EXPECT_EQ(limits.travel_speed, (400ull << 24) / kTickHz);
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {0, 0, 0}, 1}, &limits));
  EXPECT_EQ(limits.max_speed, (8000ull << 24) / kTickHz);
  // An axis limit so close to the path's that the bound is below one
  // acceleration step: refused.
  EXPECT_FALSE(motion::ToTickLimits({1000, 1000, 999000, 0, 1000, {999999, 0, 0}, 1}, &limits));
}

TEST(NoTurnCaps, RandomStrokesKeepEveryAxisWithinItsLimit) {
  std::mt19937_64 rng(15);
  for (int trial = 0; trial < 12; ++trial) {
    Machine machine{4000 + static_cast<std::uint32_t>(rng() % 16000),
                    40000 + static_cast<std::uint32_t>(rng() % 300000), 0};
    machine.axis_accel = static_cast<std::uint32_t>(machine.accel * (1.2 + (rng() % 30) / 10.0));
    std::array<std::int32_t, 2> at{0, 0};
    const std::vector<std::uint8_t> entries = test::PenStrokes(rng, 3, &at);
    std::mt19937_64 feed_rng(trial);
    const test::Drawn drawn = test::Draw(machine, entries, feed_rng);
    ASSERT_TRUE(drawn.idle) << "trial " << trial;
    EXPECT_EQ(drawn.position, at) << "trial " << trial;
    const sim::MotionReport report =
        sim::CheckMotion(drawn.steps, drawn.pens, test::SiLimits(machine, machine.axis_accel));
    EXPECT_EQ(report.violations, 0u) << "trial " << trial << ": " << report.first_violation;
  }
}

}  // namespace
}  // namespace fdsurf
