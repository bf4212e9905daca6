// SPDX-License-Identifier: MIT
// The turn caps of the motion loop (fdsurf/motion/turn_caps.h,
// docs/motion.md "Each axis on curves"): every axis within its limit on
// curves and corners, the loop never running ahead of the caps that are not
// final yet, and Flush() for a producer that has nothing more.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "fdsurf/motion/entry.h"
#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/motion/turn_caps.h"
#include "fdsurf/sim/checks.h"
#include "random_strokes.h"

namespace fdsurf {
namespace {

using motion::EntryKind;
using motion::MakeEntry;
using motion::MotionLoop;

using test::Draw;
using test::Drawn;
using test::kTickHz;
using test::Machine;
using test::PenStrokes;
using test::SiLimits;
using test::TickLimitsOf;

TEST(TurnCaps, RandomStrokesKeepEveryAxisWithinItsLimit) {
  std::mt19937_64 rng(15);
  int broken_without_caps = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Machine machine{4000 + static_cast<std::uint32_t>(rng() % 16000),
                          40000 + static_cast<std::uint32_t>(rng() % 300000), 0};
    Machine capped = machine;
    capped.axis_accel = static_cast<std::uint32_t>(machine.accel * (1.2 + (rng() % 30) / 10.0));
    std::array<std::int32_t, 2> at{0, 0};
    const std::vector<std::uint8_t> entries = PenStrokes(rng, 3, &at);
    std::mt19937_64 feed_rng(trial);
    const Drawn drawn = Draw(capped, entries, feed_rng);
    ASSERT_TRUE(drawn.idle) << "trial " << trial;
    EXPECT_EQ(drawn.position, at) << "trial " << trial;
    const sim::MotionReport report =
        sim::CheckMotion(drawn.steps, drawn.pens, SiLimits(capped, capped.axis_accel));
    EXPECT_EQ(report.violations, 0u) << "trial " << trial << ": " << report.first_violation;

    // The same strokes without caps break the axis limit (on most trials:
    // those whose arcs are tight for their speed).
    std::mt19937_64 same_feed(trial);
    const Drawn uncapped = Draw(machine, entries, same_feed);
    const sim::MotionReport without =
        sim::CheckMotion(uncapped.steps, uncapped.pens, SiLimits(machine, capped.axis_accel));
    if (without.violations > 0) ++broken_without_caps;
  }
  EXPECT_GE(broken_without_caps, 6);
}

TEST(TurnCaps, TheLoopRunsNoFurtherThanTheFinalMovesUntilFlushed) {
  std::vector<std::uint8_t> storage(1024);
  MotionLoop loop(storage.data(), 1024);
  loop.Configure(TickLimitsOf({8000, 160000, 320000}));
  ASSERT_TRUE(loop.Push(MakeEntry(EntryKind::kPenDown)));
  const std::int32_t right[2] = {1, 0};
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(loop.Push(motion::MakeMove(right, 2)));
  for (int t = 0; t < 100'000; ++t) (void)loop.Tick();
  // Every move but the pending ones, and at rest there.
  EXPECT_EQ(loop.position()[0], 500 - motion::TurnCaps::kPendingMoves);
  EXPECT_EQ(loop.speed(), 0u);
  EXPECT_FALSE(loop.Idle());
  ASSERT_TRUE(loop.Flush());
  std::uint32_t top = 0;
  for (int t = 0; t < 400'000 && !loop.Idle(); ++t) {
    (void)loop.Tick();
    top = std::max(top, loop.speed());
  }
  EXPECT_TRUE(loop.Idle());
  EXPECT_EQ(loop.position()[0], 500);
  EXPECT_GT(top, 0u);
  // A flush after nothing new does nothing, and nothing is pending.
  EXPECT_TRUE(loop.Flush());
}

// A right angle between axis-parallel lines: the speed through the corner
// is within the cap of docs/motion.md's example (the 4-move chord: turn
// (4, 4) less rounding (2, 2), doubled norm bound 2·2 + 2 = 6, h = 4 steps),
// and without an axis limit the loop goes through at full speed.
TEST(TurnCaps, ARightAngleIsTakenWithinTheCornerCap) {
  const auto corner_speed = [](const Machine& machine) {
    std::vector<std::uint8_t> storage(4096);
    MotionLoop loop(storage.data(), 4096);
    const motion::TickLimits limits = TickLimitsOf(machine);
    loop.Configure(limits);
    std::vector<std::uint8_t> entries = {MakeEntry(EntryKind::kPenDown)};
    const std::int32_t right[2] = {1, 0};
    const std::int32_t up[2] = {0, 1};
    for (int i = 0; i < 1500; ++i) entries.push_back(motion::MakeMove(right, 2));
    for (int i = 0; i < 1500; ++i) entries.push_back(motion::MakeMove(up, 2));
    entries.push_back(MakeEntry(EntryKind::kPenUp));
    std::size_t next = 0;
    std::uint32_t at_corner = 0;
    for (int t = 0; t < 2'000'000 && (next < entries.size() || !loop.Idle()); ++t) {
      while (next < entries.size() && !loop.Full()) EXPECT_TRUE(loop.Push(entries[next++]));
      const motion::TickOutput out = loop.Tick();
      const std::int32_t x = loop.position()[0];
      const std::int32_t y = loop.position()[1];
      // The speed of each tick that completes one of the 4 moves either side
      // of the corner at (1500, 0) (the chord's region: moves to x = 1497 ..
      // 1500 and to y = 1 .. 4; a tick that only reaches x = 1496 may still
      // be faster, it has not moved inside).
      if (out.step_mask != 0 && ((x >= 1497 && y == 0) || (x == 1500 && y <= 4))) {
        at_corner = std::max(at_corner, loop.speed());
      }
    }
    EXPECT_TRUE(loop.Idle());
    return static_cast<double>(at_corner) / (1 << motion::kLengthFracBits) * kTickHz;  // steps/s
  };
  const Machine free{8000, 160000, 0};
  EXPECT_GT(corner_speed(free), 7900);
  const Machine capped{8000, 160000, 320000};
  const double budget = std::sqrt(320000.0 * 320000.0 - 160000.0 * 160000.0);  // steps/s²
  const double cap = std::sqrt(2 * budget * 16 / 6);
  const double speed = corner_speed(capped);
  EXPECT_LE(speed, cap);
  EXPECT_GT(speed, 0.9 * cap);  // coarsening takes at most 6 %
  std::printf("right angle: %.0f steps/s through the corner (cap %.0f)\n", speed, cap);
}

// Whether any move of `moves` (3-D unit moves), measured by turn caps with
// `budget` and top speed `top`, gets a cap.
bool AnyMoveCapped(std::uint32_t budget, std::uint32_t top,
                   const std::vector<std::uint8_t>& moves) {
  const std::uint32_t accel = 1000;
  std::uint32_t skip[motion::TurnCaps::kChords];
  motion::TurnCaps::SkipThresholds(budget, top, skip);
  motion::TurnCaps caps;
  caps.Configure(budget, accel, top, skip);
  bool capped = false;
  for (const std::uint8_t move : moves) {
    const motion::TurnCaps::Final final = caps.Measure(move, motion::LengthOfMove(move));
    capped = capped || final.capped;
    if (caps.HasRoom()) caps.Commit(final);
  }
  return capped || caps.MeasureAll(false).capped;
}

// Two straight runs of m moves each way around every corner: every pair of
// the 26 unit moves, for every chord length.
std::vector<std::vector<std::uint8_t>> EveryCorner() {
  std::vector<std::uint8_t> kinds;
  for (int code = 0; code < 27; ++code) {
    const std::int32_t delta[3] = {code % 3 - 1, code / 3 % 3 - 1, code / 9 - 1};
    if (delta[0] != 0 || delta[1] != 0 || delta[2] != 0)
      kinds.push_back(motion::MakeMove(delta, 3));
  }
  std::vector<std::vector<std::uint8_t>> corners;
  for (int k = 0; k < motion::TurnCaps::kChords; ++k) {
    const int m = 4 << k;
    for (const std::uint8_t before : kinds) {
      for (const std::uint8_t after : kinds) {
        std::vector<std::uint8_t> moves(static_cast<std::size_t>(m), before);
        moves.insert(moves.end(), static_cast<std::size_t>(m), after);
        corners.push_back(moves);
      }
    }
  }
  return corners;
}

// A device without turn caps runs no faster than TopSpeedNoChordBinds():
// measured by the caps themselves, no corner and no random path of 3-D unit
// moves gets a cap at that speed, for budgets from the smallest to the
// largest. At √1.53 times that speed (top² = 2.04·budget·2^24), corners
// bind (the worst one, four moves on one axis then four on three axes, has
// its cap at top² = 2·budget·2^24): the bound is within √1.5 of the caps'
// own worst case.
TEST(TurnCaps, AtTheTopSpeedNoChordBindsNothingIsEverCapped) {
  const std::vector<std::vector<std::uint8_t>> corners = EveryCorner();
  std::mt19937_64 rng(17);
  for (const std::uint32_t budget : {1u, 77u, 2905u, 1u << 20, (1u << 24) - 1}) {
    const std::uint32_t top = motion::TurnCaps::TopSpeedNoChordBinds(budget);
    const double exact = std::sqrt(static_cast<double>(budget) * 67108864.0 / 3);
    EXPECT_LE(top, exact) << budget;
    EXPECT_GT(top + 1.0, exact) << budget;
    int binding_faster = 0;
    for (const std::vector<std::uint8_t>& corner : corners) {
      EXPECT_FALSE(AnyMoveCapped(budget, top, corner)) << "budget " << budget;
      if (AnyMoveCapped(budget, static_cast<std::uint32_t>(top * std::sqrt(1.53)), corner)) {
        ++binding_faster;
      }
    }
    if (budget >= 77) {
      EXPECT_GT(binding_faster, 0) << "budget " << budget;
    }
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<std::uint8_t> moves;
      for (int i = 0; i < 2000; ++i) {
        const std::int32_t delta[3] = {static_cast<std::int32_t>(rng() % 3) - 1,
                                       static_cast<std::int32_t>(rng() % 3) - 1,
                                       static_cast<std::int32_t>(rng() % 3) - 1};
        if (delta[0] != 0 || delta[1] != 0 || delta[2] != 0)
          moves.push_back(motion::MakeMove(delta, 3));
      }
      EXPECT_FALSE(AnyMoveCapped(budget, top, moves)) << "budget " << budget;
    }
  }
  EXPECT_EQ(motion::TurnCaps::TopSpeedNoChordBinds(0), 1u << motion::kLengthFracBits);
}

TEST(TurnCaps, ToTickLimitsGivesTheBudgetOfTheSmallestAxis) {
  motion::TickLimits limits{};
  // At 40 kHz: a = ⌊160000·2^24/1.6e9⌋ = 1677, A = ⌊320000·2^24/1.6e9⌋ =
  // 3355 on X and 6710 on Y: the budget is ⌊√(3355² − 1677²)⌋ = 2905.
  ASSERT_TRUE(
      motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {320000, 640000, 0}, 1}, &limits));
  EXPECT_EQ(limits.accel, 1677u);
  EXPECT_EQ(limits.turn_budget, 2905u);
  // No axis limit, no budget; an axis limit not above the path's: refused.
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {0, 0, 0}, 1}, &limits));
  EXPECT_EQ(limits.turn_budget, 0u);
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {160000, 0, 0}, 1}, &limits));
}

}  // namespace
}  // namespace fdsurf
