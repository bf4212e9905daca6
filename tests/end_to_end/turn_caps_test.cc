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

namespace fdsurf {
namespace {

using motion::EntryKind;
using motion::MakeEntry;
using motion::MotionLoop;

constexpr std::uint32_t kTickHz = 40000;
constexpr double kPi = 3.14159265358979323846;
constexpr double kWindow = 0.02;  // CheckMotion's default

struct Machine {
  std::uint32_t rate;        // steps/s
  std::uint32_t accel;       // path, steps/s²
  std::uint32_t axis_accel;  // each axis, steps/s² (0: not limited)
};

motion::TickLimits TickLimitsOf(const Machine& m) {
  motion::TickLimits limits{};
  const motion::MotionLimits si{kTickHz, m.rate, m.accel,
                                0,       m.rate, {m.axis_accel, m.axis_accel, 0}};
  EXPECT_TRUE(motion::ToTickLimits(si, &limits));
  return limits;
}

// Unit moves from the current point through `targets` (each rounded),
// one step per axis at most.
void AppendPath(const std::vector<std::array<double, 2>>& targets, std::array<std::int32_t, 2>* at,
                std::vector<std::uint8_t>* moves) {
  for (const auto& target : targets) {
    const std::array<std::int32_t, 2> goal = {static_cast<std::int32_t>(std::lround(target[0])),
                                              static_cast<std::int32_t>(std::lround(target[1]))};
    while ((*at)[0] != goal[0] || (*at)[1] != goal[1]) {
      std::int32_t delta[2];
      for (int a = 0; a < 2; ++a) {
        delta[a] = goal[a] > (*at)[a] ? 1 : goal[a] < (*at)[a] ? -1 : 0;
        (*at)[a] += delta[a];
      }
      moves->push_back(motion::MakeMove(delta, 2));
    }
  }
}

// A random stroke: arcs of random radius and sweep joined by corners of
// random angle, and straight stretches.
std::vector<std::uint8_t> RandomStroke(std::mt19937_64& rng, std::array<std::int32_t, 2>* at) {
  std::vector<std::uint8_t> moves;
  std::array<double, 2> p = {static_cast<double>((*at)[0]), static_cast<double>((*at)[1])};
  double heading = static_cast<double>(rng() % 628) / 100;
  for (int piece = 0; piece < 12; ++piece) {
    std::vector<std::array<double, 2>> targets;
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 0) {  // a corner, then a straight stretch
      heading += (static_cast<double>(rng() % 300) / 100 - 1.5);
      const double length = 50 + static_cast<double>(rng() % 1500);
      for (double s = 0.5; s <= length; s += 0.5) {
        targets.push_back({p[0] + s * std::cos(heading), p[1] + s * std::sin(heading)});
      }
      p = targets.back();
    } else {  // an arc
      const double r = 15 + static_cast<double>(rng() % 2000);
      const double sweep = (static_cast<double>(rng() % 600) / 100 + 0.2) * (rng() % 2 ? 1 : -1);
      const double side = sweep > 0 ? 1 : -1;
      const std::array<double, 2> centre = {p[0] - side * r * std::sin(heading),
                                            p[1] + side * r * std::cos(heading)};
      const double start = std::atan2(p[1] - centre[1], p[0] - centre[0]);
      const int n = static_cast<int>(std::fabs(sweep) * r / 0.5) + 1;
      for (int k = 1; k <= n; ++k) {
        const double angle = start + sweep * k / n;
        targets.push_back({centre[0] + r * std::cos(angle), centre[1] + r * std::sin(angle)});
      }
      heading += sweep;
      p = targets.back();
    }
    AppendPath(targets, at, &moves);
  }
  return moves;
}

struct Drawn {
  std::vector<hal::StepDirEvent> steps;
  std::vector<hal::PenEvent> pens;
  std::array<std::int32_t, 2> position{};
  bool idle = false;
};

// Feeds the entries as a producer with pauses would (a few entries between
// ticks, sometimes none for a while), flushing when it has nothing more, as
// Device::Fill() does.
Drawn Draw(const Machine& machine, const std::vector<std::uint8_t>& entries, std::mt19937_64& rng) {
  std::vector<std::uint8_t> storage(1024);
  MotionLoop loop(storage.data(), 1024);
  loop.Configure(TickLimitsOf(machine));
  Drawn drawn;
  std::size_t next = 0;
  std::uint64_t tick = 0;
  std::uint64_t starving_until = 0;
  while ((next < entries.size() || !loop.Idle()) && tick < 200'000'000) {
    if (tick >= starving_until) {
      const std::uint64_t feed = 1 + rng() % 4;
      for (std::uint64_t k = 0; k < feed && next < entries.size() && !loop.Full(); ++k) {
        EXPECT_TRUE(loop.Push(entries[next++]));
      }
      if (rng() % 20000 == 0) starving_until = tick + rng() % 4000;  // the host is late
    } else {
      (void)loop.Flush();
    }
    if (next == entries.size()) (void)loop.Flush();
    const motion::TickOutput out = loop.Tick();
    const std::uint64_t us = tick * (1'000'000 / kTickHz);
    if (out.step_mask != 0) drawn.steps.push_back({us, out.step_mask, out.negative_mask, true});
    if (out.pen != 0) drawn.pens.push_back({us, out.pen > 0});
    ++tick;
  }
  drawn.idle = loop.Idle();
  drawn.position = {loop.position()[0], loop.position()[1]};
  return drawn;
}

sim::MotionLimitsSi SiLimits(const Machine& m, double axis_accel) {
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = m.rate;
  limits.accel = m.accel;
  limits.axis_accel = axis_accel;
  return limits;
}

TEST(TurnCaps, RandomStrokesKeepEveryAxisWithinItsLimit) {
  std::mt19937_64 rng(15);
  int broken_without_caps = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Machine machine{4000 + static_cast<std::uint32_t>(rng() % 16000),
                          40000 + static_cast<std::uint32_t>(rng() % 300000), 0};
    Machine capped = machine;
    capped.axis_accel = static_cast<std::uint32_t>(machine.accel * (1.2 + (rng() % 30) / 10.0));
    std::array<std::int32_t, 2> at{0, 0};
    std::vector<std::uint8_t> entries;
    for (int stroke = 0; stroke < 3; ++stroke) {
      entries.push_back(MakeEntry(EntryKind::kPenDown));
      const std::vector<std::uint8_t> moves = RandomStroke(rng, &at);
      entries.insert(entries.end(), moves.begin(), moves.end());
      entries.push_back(MakeEntry(EntryKind::kPenUp));
    }
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

TEST(TurnCaps, ToTickLimitsGivesTheBudgetOfTheSmallestAxis) {
  motion::TickLimits limits{};
  // At 40 kHz: a = ⌊160000·2^24/1.6e9⌋ = 1677, A = ⌊320000·2^24/1.6e9⌋ =
  // 3355 on X and 6710 on Y: the budget is ⌊√(3355² − 1677²)⌋ = 2905.
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {320000, 640000, 0}}, &limits));
  EXPECT_EQ(limits.accel, 1677u);
  EXPECT_EQ(limits.turn_budget, 2905u);
  // No axis limit, no budget; an axis limit not above the path's: refused.
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {0, 0, 0}}, &limits));
  EXPECT_EQ(limits.turn_budget, 0u);
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, 8000, 160000, 0, 8000, {160000, 0, 0}}, &limits));
}

}  // namespace
}  // namespace fdsurf
