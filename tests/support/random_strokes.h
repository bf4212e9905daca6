// SPDX-License-Identifier: MIT
// Random strokes of unit moves and a producer that feeds them to a motion
// loop as Device::Fill() does: the turn caps' tests and those of a device
// built without them (end_to_end/turn_caps_test.cc, no_turn_caps_test.cc)
// draw the same paths and check them with sim::CheckMotion.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "fdsurf/hal/sim.h"
#include "fdsurf/motion/entry.h"
#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/sim/checks.h"

namespace fdsurf {
namespace test {

inline constexpr std::uint32_t kTickHz = 40000;

struct Machine {
  std::uint32_t rate;        // steps/s
  std::uint32_t accel;       // path, steps/s²
  std::uint32_t axis_accel;  // each axis, steps/s² (0: not limited)
};

inline motion::TickLimits TickLimitsOf(const Machine& m) {
  motion::TickLimits limits{};
  const motion::MotionLimits si{
      kTickHz, m.rate, m.accel, 0, m.rate, {m.axis_accel, m.axis_accel, 0}, 1};
  EXPECT_TRUE(motion::ToTickLimits(si, &limits));
  return limits;
}

// Unit moves from the current point through `targets` (each rounded),
// one step per axis at most.
inline void AppendPath(const std::vector<std::array<double, 2>>& targets,
                       std::array<std::int32_t, 2>* at, std::vector<std::uint8_t>* moves) {
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
inline std::vector<std::uint8_t> RandomStroke(std::mt19937_64& rng,
                                              std::array<std::int32_t, 2>* at) {
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

// `strokes` random strokes from `at`, each between a pen-down and a pen-up
// entry; `at` ends where the last one does.
inline std::vector<std::uint8_t> PenStrokes(std::mt19937_64& rng, int strokes,
                                            std::array<std::int32_t, 2>* at) {
  std::vector<std::uint8_t> entries;
  for (int stroke = 0; stroke < strokes; ++stroke) {
    entries.push_back(motion::MakeEntry(motion::EntryKind::kPenDown));
    const std::vector<std::uint8_t> moves = RandomStroke(rng, at);
    entries.insert(entries.end(), moves.begin(), moves.end());
    entries.push_back(motion::MakeEntry(motion::EntryKind::kPenUp));
  }
  return entries;
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
inline Drawn Draw(const Machine& machine, const std::vector<std::uint8_t>& entries,
                  std::mt19937_64& rng) {
  std::vector<std::uint8_t> storage(1024);
  motion::MotionLoop loop(storage.data(), 1024);
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

inline sim::MotionLimitsSi SiLimits(const Machine& m, double axis_accel) {
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = m.rate;
  limits.accel = m.accel;
  limits.axis_accel = axis_accel;
  return limits;
}

}  // namespace test
}  // namespace fdsurf
