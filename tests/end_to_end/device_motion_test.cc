// SPDX-License-Identifier: MIT
// The firmware's motion side: the velocity profile of the motion loop, the
// path generator's expansion of patches, curves and moves, and the device's
// validation, STOP and faults. References are independent: exact curves in
// long double written out here, the ideal continuous trapezoid, and the
// simulator's event-based limit checks (whose own ability to fail is tested
// in sim_test.cc).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/sim/checks.h"
#include "fdsurf/sim/plotter.h"

namespace fdsurf {
namespace {

using motion::EntryKind;
using motion::MakeEntry;
using motion::MakeMove;
using motion::MotionLoop;
using motion::TickOutput;

constexpr std::uint32_t kTickHz = 40000;

motion::TickLimits Limits(std::uint32_t max_rate, std::uint32_t accel,
                          std::uint16_t pen_delay_ms = 0, std::uint8_t slice_ticks = 1) {
  motion::TickLimits limits{};
  EXPECT_TRUE(motion::ToTickLimits(
      {kTickHz, max_rate, accel, pen_delay_ms, max_rate, {0, 0, 0}, slice_ticks}, &limits));
  return limits;
}

// The slice lengths every profile test runs with: the tick itself, and the
// slices the boards use (docs/motion.md, "Slices").
constexpr std::uint8_t kSlices[] = {1, 4, 16};

// Runs the loop to idle, recording what it did as the sim HAL would.
struct Recording {
  std::vector<hal::StepDirEvent> steps;
  std::vector<hal::PenEvent> pens;
  std::uint64_t ticks = 0;
  std::uint32_t commands_done = 0;
};

void Record(const TickOutput& out, std::uint64_t tick, Recording* r) {
  const std::uint64_t us = tick * (1'000'000 / kTickHz);
  if (out.step_mask != 0) r->steps.push_back({us, out.step_mask, out.negative_mask, true});
  if (out.pen != 0) r->pens.push_back({us, out.pen > 0});
  r->commands_done += out.commands_done;
}

Recording RunToIdle(MotionLoop* loop, std::uint64_t limit = 50'000'000) {
  Recording r;
  while (!loop->Idle() && r.ticks < limit) {
    Record(loop->Tick(), r.ticks, &r);
    ++r.ticks;
  }
  return r;
}

sim::MotionLimitsSi SiLimits(double max_rate, double accel, double pen_delay_s = 0) {
  sim::MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = max_rate;
  limits.accel = accel;
  limits.pen_delay_s = pen_delay_s;
  return limits;
}

// The time a continuous trapezoid needs for `distance` from rest to rest.
double IdealSeconds(double distance, double speed, double accel) {
  if (distance >= speed * speed / accel) return distance / speed + speed / accel;
  return 2 * std::sqrt(distance / accel);
}

TEST(MotionLimits, RefusesWhatTheLoopCannotServe) {
  motion::TickLimits limits{};
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, kTickHz + 1, 1000, 0, 1000, {0, 0, 0}, 1},
                                    &limits));  // > 1 step/tick
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, 0, 1000, 0, 1000, {0, 0, 0}, 1}, &limits));
  // 10 steps/s² at 40 kHz is 10·2^24/1.6e9 ≈ 0.1 units per tick²: not representable.
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, 1000, 10, 0, 1000, {0, 0, 0}, 1}, &limits));
  // A slice is a power of two of ticks up to kMaxSliceTicks (0 counts as 1).
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, 8000, 160000, 100, 8000, {0, 0, 0}, 3}, &limits));
  EXPECT_FALSE(motion::ToTickLimits({kTickHz, 8000, 160000, 100, 8000, {0, 0, 0}, 32}, &limits));
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 8000, 160000, 100, 8000, {0, 0, 0}, 0}, &limits));
  EXPECT_EQ(limits.slice_shift, 0u);
  ASSERT_TRUE(motion::ToTickLimits({kTickHz, 8000, 160000, 100, 8000, {0, 0, 0}, 1}, &limits));
  EXPECT_EQ(limits.max_speed, 3355443u);  // 8000·2^24/40000, rounded down
  EXPECT_EQ(limits.accel, 1677u);         // 160000·2^24/40000², rounded down
  EXPECT_EQ(limits.pen_delay_ticks, 4000u);
}

TEST(MotionLoop, StraightRunIsATrapezoidWithinTheLimits) {
  std::vector<std::uint8_t> storage(4096);
  for (const std::uint8_t slice : kSlices) {
    for (const int steps : {1, 7, 150, 1000, 3000}) {
      SCOPED_TRACE(testing::Message() << int{slice} << " ticks a slice");
      MotionLoop loop(storage.data(), static_cast<std::uint16_t>(storage.size()));
      loop.Configure(Limits(8000, 160000, 0, slice));
      const std::int32_t right[2] = {1, 0};
      for (int i = 0; i < steps; ++i) ASSERT_TRUE(loop.Push(MakeMove(right, 2)));
      ASSERT_TRUE(loop.Push(MakeEntry(EntryKind::kPenUp)));  // a rest at the end
      const Recording r = RunToIdle(&loop);
      ASSERT_EQ(r.steps.size(), static_cast<std::size_t>(steps));
      EXPECT_EQ(loop.position()[0], steps);
      const sim::MotionReport report =
          sim::CheckMotion(r.steps, r.pens, SiLimits(8000, 160000), 0.02);
      EXPECT_EQ(report.violations, 0u) << steps << " steps: " << report.first_violation;
      // Not needlessly slow either: within 2% (plus a few ticks, and two
      // slices for the choices a slice late) of the ideal trapezoid.
      const double ideal = IdealSeconds(steps, 8000, 160000);
      EXPECT_LE(r.ticks, ideal * kTickHz * 1.02 + 5 + 2 * slice) << steps << " steps";
    }
  }
}

// Every unit move's length is √k·2^24 rounded up for the k axes it steps
// (never shorter than the move), computed here in long double.
TEST(MotionLoop, AMoveIsAsLongAsTheRootOfTheAxesItSteps) {
  for (int code = 0; code < 27; ++code) {
    const std::int32_t delta[3] = {code % 3 - 1, code / 3 % 3 - 1, code / 9 - 1};
    const int axes = (delta[0] != 0) + (delta[1] != 0) + (delta[2] != 0);
    const long double exact = std::sqrt(static_cast<long double>(axes)) * 16777216.0L;
    const std::uint32_t length = motion::LengthOfMove(motion::MakeMove(delta, 3));
    EXPECT_GE(static_cast<long double>(length), exact) << code;
    EXPECT_LT(static_cast<long double>(length), exact + 1) << code;
  }
}

TEST(MotionLoop, DiagonalMovesCountTheirLength) {
  std::vector<std::uint8_t> storage(4096);
  MotionLoop loop(storage.data(), 4096);
  loop.Configure(Limits(8000, 160000));
  const std::int32_t diagonal[3] = {1, -1, 1};
  for (int i = 0; i < 3000; ++i) ASSERT_TRUE(loop.Push(MakeMove(diagonal, 3)));
  ASSERT_TRUE(loop.Push(MakeEntry(EntryKind::kPenUp)));
  const Recording r = RunToIdle(&loop);
  const sim::MotionReport report = sim::CheckMotion(r.steps, r.pens, SiLimits(8000, 160000));
  EXPECT_EQ(report.violations, 0u) << report.first_violation;
  // The Euclidean path speed, √3 per move, tops out at the limit.
  EXPECT_GT(report.max_speed, 8000 * 0.97);
  EXPECT_EQ(loop.position()[1], -3000);
}

TEST(MotionLoop, RandomPathsWithPenEventsAndStarvationKeepTheLimits) {
  std::mt19937_64 rng(7);
  std::vector<std::uint8_t> storage(256);
  for (int trial = 0; trial < 30; ++trial) {
    MotionLoop loop(storage.data(), 256);
    const std::uint32_t rate = 2000 + static_cast<std::uint32_t>(rng() % 20000);
    const std::uint32_t accel = 20000 + static_cast<std::uint32_t>(rng() % 400000);
    const std::uint8_t slice = kSlices[trial % 3];
    loop.Configure(Limits(rate, accel, 5, slice));
    // The producer feeds a random number of entries between ticks, sometimes none.
    std::vector<std::uint8_t> entries;
    std::array<std::int64_t, 3> expected{0, 0, 0};
    for (int i = 0; i < 6000; ++i) {
      if (rng() % 400 == 0) {
        entries.push_back(MakeEntry(rng() % 2 ? EntryKind::kPenDown : EntryKind::kPenUp));
        continue;
      }
      std::int32_t delta[3];
      for (int a = 0; a < 3; ++a) delta[a] = static_cast<std::int32_t>(rng() % 3) - 1;
      if (delta[0] == 0 && delta[1] == 0 && delta[2] == 0) delta[0] = 1;
      for (int a = 0; a < 3; ++a) expected[a] += delta[a];
      entries.push_back(MakeMove(delta, 3));
    }
    entries.push_back(MakeEntry(EntryKind::kPenUp));
    entries.push_back(MakeEntry(EntryKind::kPenDown));  // the last rest is a pen event
    Recording r;
    std::size_t next = 0;
    while ((next < entries.size() || !loop.Idle()) && r.ticks < 100'000'000) {
      const std::uint64_t feed = rng() % 8 == 0 ? 0 : rng() % 6;
      for (std::uint64_t k = 0; k < feed && next < entries.size() && !loop.Full(); ++k) {
        ASSERT_TRUE(loop.Push(entries[next++]));
      }
      Record(loop.Tick(), r.ticks, &r);
      ++r.ticks;
    }
    ASSERT_TRUE(loop.Idle());
    for (int a = 0; a < 3; ++a) EXPECT_EQ(loop.position()[a], expected[a]) << "axis " << a;
    const sim::MotionReport report =
        sim::CheckMotion(r.steps, r.pens, SiLimits(rate, accel, 5e-3), 0.02);
    EXPECT_EQ(report.violations, 0u)
        << "trial " << trial << " (" << int{slice} << " ticks a slice): " << report.first_violation;
  }
}

// The length of each run between pen events is kept as it is pushed (a
// ring of kMaxPenEvents runs), not recounted when a pen event is passed: a
// run must take the same ticks whether it was the head run when pushed or
// was pushed behind pen events, and the same as the same run alone.
TEST(MotionLoop, RunsBehindPenEventsTakeTheTicksOfTheSameRunAlone) {
  std::vector<std::uint8_t> storage(1024);
  const std::int32_t right[2] = {1, 0};
  const std::int32_t diagonal[2] = {1, 1};
  // Runs of different lengths and move kinds, so that a length credited
  // to the wrong run changes some run's time.
  const int lengths[] = {150, 40, 300, 7, 90};
  std::vector<std::uint8_t> alone_storage(1024);
  const auto alone = [&](int steps, const std::int32_t* delta) {
    MotionLoop loop(alone_storage.data(), 1024);
    loop.Configure(Limits(8000, 160000));
    for (int i = 0; i < steps; ++i) EXPECT_TRUE(loop.Push(MakeMove(delta, 2)));
    EXPECT_TRUE(loop.Push(MakeEntry(EntryKind::kPenUp)));
    std::uint64_t ticks = 0;
    while (loop.position()[0] < steps && ticks < 1'000'000) {
      (void)loop.Tick();
      ++ticks;
    }
    return ticks;
  };
  MotionLoop loop(storage.data(), 1024);
  loop.Configure(Limits(8000, 160000));
  std::vector<std::uint8_t> entries;
  for (int k = 0; k < 5; ++k) {
    for (int i = 0; i < lengths[k]; ++i) entries.push_back(MakeMove(k % 2 ? diagonal : right, 2));
    entries.push_back(MakeEntry(k % 2 ? EntryKind::kPenUp : EntryKind::kPenDown));
  }
  // Everything the cap allows goes in at once, the rest as room appears.
  std::size_t next = 0;
  const auto feed = [&] {
    while (next < entries.size() && !loop.Full()) ASSERT_TRUE(loop.Push(entries[next++]));
  };
  feed();
  EXPECT_LT(next, entries.size()) << "the pen-event cap never held anything back";
  std::int32_t start = 0;
  for (int k = 0; k < 5; ++k) {
    std::uint64_t ticks = 0;
    while (loop.position()[0] < start + lengths[k] && ticks < 1'000'000) {
      (void)loop.Tick();
      feed();
      ++ticks;
    }
    start += lengths[k];
    ASSERT_EQ(ticks, alone(lengths[k], k % 2 ? diagonal : right)) << "run " << k;
    for (int t = 0; t < 10 && loop.pen_down() != (k % 2 == 0); ++t) (void)loop.Tick();
    ASSERT_EQ(loop.pen_down(), k % 2 == 0) << "pen event " << k << " not passed";
  }
}

TEST(MotionLoop, HoldsAtMostItsPenEventsAtOnce) {
  std::vector<std::uint8_t> storage(64);
  MotionLoop loop(storage.data(), 64);
  loop.Configure(Limits(8000, 160000));
  for (int k = 0; k < MotionLoop::kMaxPenEvents; ++k) {
    ASSERT_FALSE(loop.Full());
    ASSERT_TRUE(loop.Push(MakeEntry(k % 2 ? EntryKind::kPenUp : EntryKind::kPenDown)));
  }
  EXPECT_TRUE(loop.Full());
  EXPECT_FALSE(loop.Push(MakeEntry(EntryKind::kPenUp)));
  EXPECT_EQ(loop.Count(), MotionLoop::kMaxPenEvents);
}

TEST(MotionLoop, StopDeceleratesAlongThePathWithinTheLimit) {
  std::vector<std::uint8_t> storage(4096);
  for (const std::uint8_t slice : kSlices) {
    SCOPED_TRACE(testing::Message() << int{slice} << " ticks a slice");
    MotionLoop loop(storage.data(), 4096);
    const motion::TickLimits limits = Limits(8000, 160000, 0, slice);
    loop.Configure(limits);
    const std::int32_t right[2] = {1, 0};
    for (int i = 0; i < 4000; ++i) ASSERT_TRUE(loop.Push(MakeMove(right, 2)));
    for (int t = 0; t < 3000; ++t) loop.Tick();  // well under way, at full speed
    const std::uint32_t before = loop.speed();
    ASSERT_GT(before, limits.accel * 100);
    loop.Stop();
    std::uint32_t previous = before;
    int ticks = 0;
    while (loop.speed() > 0 && ticks < 100000) {
      loop.Tick();
      EXPECT_LE(previous - loop.speed(), limits.accel);  // never faster than the limit
      previous = loop.speed();
      ++ticks;
    }
    EXPECT_EQ(loop.speed(), 0u);
    // One choice a slice: the speed falls by a per slice, so the stop takes
    // at most that many slices (plus the one under way when it came).
    EXPECT_LE(ticks, (static_cast<int>(before / limits.accel) + 2) * slice);
    EXPECT_TRUE(loop.Stopping());
  }
}

// A slice changes how often the speed is chosen, never the path: the same
// entries give the same unit moves in the same order at any slice length,
// the speed still changes by at most a per tick, the choice runs about once
// a slice, and the drawing takes about as long (within 2 %).
TEST(MotionLoop, SlicesChangeOnlyWhenTheSpeedIsChosen) {
  std::mt19937_64 rng(11);
  std::vector<std::uint8_t> entries;
  for (int i = 0; i < 20000; ++i) {
    if (rng() % 700 == 0) {
      entries.push_back(MakeEntry(rng() % 2 ? EntryKind::kPenDown : EntryKind::kPenUp));
      continue;
    }
    // Runs of one direction, so that the profile reaches full speed.
    static std::int32_t delta[2] = {1, 0};
    if (rng() % 200 == 0) {
      delta[0] = static_cast<std::int32_t>(rng() % 3) - 1;
      delta[1] = delta[0] == 0 ? 1 : static_cast<std::int32_t>(rng() % 3) - 1;
    }
    entries.push_back(MakeMove(delta, 2));
  }
  entries.push_back(MakeEntry(EntryKind::kPenUp));
  std::vector<std::uint8_t> storage(1024);
  // The simulated plotter's tick and speed (the top speed 2000 accelerations
  // a tick), the same with turn caps (axis limits twice the path's: the
  // profile then follows the end of the moves whose caps are final), and an
  // Uno's (2 kHz, the top speed it keeps without turn caps: 7.6
  // accelerations a tick, where a slice of acceleration overshoots it).
  struct Machine {
    std::uint32_t tick_hz;
    std::uint32_t max_rate;
    std::uint32_t axis_accel;
  };
  for (const Machine machine :
       {Machine{kTickHz, 8000, 0}, Machine{kTickHz, 8000, 320000}, Machine{2000, 607, 0}}) {
    std::vector<std::pair<std::uint8_t, std::uint8_t>> reference;
    std::uint64_t reference_ticks = 0;
    for (const std::uint8_t slice : kSlices) {
      SCOPED_TRACE(testing::Message() << machine.tick_hz << " Hz, axes " << machine.axis_accel
                                      << ", " << int{slice} << " ticks a slice");
      MotionLoop loop(storage.data(), 1024);
      motion::TickLimits limits{};
      ASSERT_TRUE(motion::ToTickLimits({machine.tick_hz,
                                        machine.max_rate,
                                        160000,
                                        2,
                                        machine.max_rate,
                                        {machine.axis_accel, machine.axis_accel, 0},
                                        slice},
                                       &limits));
      loop.Configure(limits);
      std::vector<std::pair<std::uint8_t, std::uint8_t>> moves;
      std::size_t next = 0;
      std::uint64_t ticks = 0;
      std::uint32_t speed = 0;
      while ((next < entries.size() || !loop.Idle()) && ticks < 10'000'000) {
        while (next < entries.size() && !loop.Full()) ASSERT_TRUE(loop.Push(entries[next++]));
        const TickOutput out = loop.Tick();
        // The speed changes by a at most per tick, whatever the slice.
        const std::uint32_t now = loop.speed();
        ASSERT_LE(now > speed ? now - speed : speed - now, limits.accel) << ticks;
        speed = now;
        if (out.step_mask != 0) moves.emplace_back(out.step_mask, out.negative_mask);
        if (out.pen != 0) moves.emplace_back(0, out.pen > 0 ? 1 : 2);
        ++ticks;
      }
      ASSERT_TRUE(loop.Idle());
      // The profile's choice runs about once a slice (one-tick slices near
      // a stop, the top speed and a cap): at 16, 11,556 choices in 179,901
      // ticks; with turn caps 26,999 in 360,314 (34,710 when a tick of
      // acceleration comes before a slice of cruising); at 2 kHz 6,053 in
      // 87,041.
      EXPECT_LE(loop.slices(), ticks / slice * 1.25 + 50);
      if (slice == 1) {
        reference = moves;
        reference_ticks = ticks;
        continue;
      }
      EXPECT_EQ(moves, reference);
      EXPECT_LE(ticks, reference_ticks * 1.02);
    }
  }
}

// --- The path generator --------------------------------------------------

// x(u) per axis from power coefficients in 2^-16 steps, in long double.
long double Evaluate(const PowerCurve1& c, long double u) {
  return (((c.c[0] * u + c.c[1]) * u + c.c[2]) * u + c.c[3]) / 65536.0L;
}

TEST(ReverseCurve, RunsTheSameCurveBackwards) {
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<std::int64_t> coefficient(-(std::int64_t{1} << 40),
                                                          std::int64_t{1} << 40);
  for (int trial = 0; trial < 200; ++trial) {
    PowerCurve1 curve[2];
    for (auto& axis : curve) {
      for (auto& c : axis.c) c = coefficient(rng);
    }
    PowerCurve1 reversed[2] = {curve[0], curve[1]};
    motion::ReverseCurve(reversed);
    for (int k = 0; k <= 16; ++k) {
      const long double u = k / 16.0L;
      for (int a = 0; a < 2; ++a) {
        EXPECT_NEAR(static_cast<double>(Evaluate(reversed[a], u)),
                    static_cast<double>(Evaluate(curve[a], 1 - u)), 1e-6);
      }
    }
  }
}

protocol::MachineConfig Config(std::int32_t travel) {
  protocol::MachineConfig config{};
  config.axes = 2;
  config.steps_per_meter[0] = config.steps_per_meter[1] = 80000;
  config.travel_steps[0] = config.travel_steps[1] = travel;
  config.max_rate = 8000;
  config.accel = 160000;
  config.pen_delay_ms = 10;
  config.travel_rate = 8000;
  config.axis_accel[0] = config.axis_accel[1] = 320000;
  return config;
}

// A Bézier patch over [x0, x0 + size]², a bump of `height` in y.
protocol::Command BumpPatch(double x0, double size, double height, std::uint16_t lines,
                            std::uint32_t tolerance_q8 = 512) {
  protocol::Command command;
  command.type = protocol::MessageType::kPatch;
  command.seq = 0;
  protocol::PatchCommand& patch = command.body.patch;
  patch = protocol::PatchCommand{};
  patch.basis = Basis::kBezier;
  patch.dims = 2;
  patch.lines_s = lines;
  patch.lines_t = lines;
  patch.tolerance_q8 = tolerance_q8;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double x = x0 + size * j / 3 + (i == 1 || i == 2 ? 0.3 * size * (j % 2) : 0.0);
      const double y = x0 + size * i / 3 + ((i == 1 || i == 2) && (j == 1 || j == 2) ? height : 0);
      patch.geometry[0].g[i][j] = GeometryFixed::FromRaw(std::llround(x * 65536));
      patch.geometry[1].g[i][j] = GeometryFixed::FromRaw(std::llround(y * 65536));
    }
  }
  return command;
}

// The exact point of a Bézier patch (geometry from the command) in long double.
std::array<long double, 2> ExactBezier(const protocol::PatchCommand& patch, long double s,
                                       long double t) {
  const auto bernstein = [](long double u, int k) {
    const long double v = 1 - u;
    const long double b[4] = {v * v * v, 3 * u * v * v, 3 * u * u * v, u * u * u};
    return b[k];
  };
  std::array<long double, 2> p{0, 0};
  for (int a = 0; a < 2; ++a) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        p[a] += bernstein(s, i) * bernstein(t, j) * patch.geometry[a].g[i][j].Raw() / 65536.0L;
      }
    }
  }
  return p;
}

// A patch's 5 + 5 isolines as the generator expands them: in order and
// direction, ending on their ends rounded, one step per axis at most, and
// every point within the tolerance of the exact line (dense samples).
void CheckPatchIsolines(std::uint32_t tolerance_q8) {
  const protocol::Command command = BumpPatch(100, 900, 250, 5, tolerance_q8);
  const protocol::PatchCommand& patch = command.body.patch;
  uint8_t detail = 0;
  ASSERT_EQ(motion::ValidateCommand<2>(command, Config(4000), &detail), protocol::ErrorCode::kNone);
  motion::PathGenerator<2> generator;
  const std::int32_t origin[2] = {0, 0};
  generator.Reset(origin, false);
  generator.Start(command);
  std::array<long double, 2> position{0, 0};
  bool pen = false;
  std::vector<std::vector<std::array<long double, 2>>> strokes;
  int done = 0;
  std::uint8_t entry = 0;
  while (generator.Next(&entry)) {
    switch (motion::KindOf(entry)) {
      case EntryKind::kPenDown:
        ASSERT_FALSE(pen);
        pen = true;
        strokes.push_back({position});
        break;
      case EntryKind::kPenUp:
        ASSERT_TRUE(pen);
        pen = false;
        break;
      case EntryKind::kCommandDone:
        ++done;
        break;
      case EntryKind::kMove:
        for (int a = 0; a < 2; ++a) {
          if ((entry >> (2 * a) & 1) != 0) position[a] += (entry >> (2 * a) & 2) != 0 ? -1 : 1;
        }
        if (pen) strokes.back().push_back(position);
        break;
    }
  }
  EXPECT_FALSE(generator.failed());
  EXPECT_EQ(done, 1);
  EXPECT_FALSE(pen);               // a patch ends with the pen up
  ASSERT_EQ(strokes.size(), 10u);  // 5 s-lines, 5 t-lines
  // Each stroke follows its isoline: s-lines first, every other one reversed.
  const long double tolerance = patch.tolerance_q8 / 256.0L;
  for (std::size_t k = 0; k < strokes.size(); ++k) {
    const bool s_line = k < 5;
    const long double fixed = (k % 5) / 4.0L;
    const bool reversed = (k % 5) % 2 == 1;
    const auto exact = [&](long double u) {
      const long double along = reversed ? 1 - u : u;
      return s_line ? ExactBezier(patch, fixed, along) : ExactBezier(patch, along, fixed);
    };
    const auto& stroke = strokes[k];
    const auto start = exact(0);
    const auto end = exact(1);
    EXPECT_LE(std::fabs(stroke.front()[0] - start[0]), 0.5L);
    EXPECT_LE(std::fabs(stroke.front()[1] - start[1]), 0.5L);
    EXPECT_LE(std::fabs(stroke.back()[0] - end[0]), 0.5L);
    EXPECT_LE(std::fabs(stroke.back()[1] - end[1]), 0.5L);
    // Every chord within the tolerance of the curve: dense samples of the
    // curve lie near the polyline, and every polyline vertex near the curve.
    std::vector<std::array<long double, 2>> samples;
    for (int i = 0; i <= 4000; ++i) samples.push_back(exact(i / 4000.0L));
    for (const auto& p : stroke) {
      long double best = 1e30L;
      for (const auto& q : samples) best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1]));
      EXPECT_LE(best, tolerance) << "stroke " << k;
    }
    for (std::size_t i = 1; i < stroke.size(); ++i) {
      EXPECT_LE(std::fabs(stroke[i][0] - stroke[i - 1][0]), 1.0L);
      EXPECT_LE(std::fabs(stroke[i][1] - stroke[i - 1][1]), 1.0L);
    }
  }
}

TEST(PathGenerator, PatchIsolinesAreStepExactAndWithinTheTolerance) { CheckPatchIsolines(3 * 256); }

// At 0.72 steps, within 0.015 of the least tolerance in 2-D (0.708), the
// chords' budget is 2^-8 (ChordBudgetBits), as the bound needs (with 2^-6 it
// would be 0.736 steps): shorter chords, and every point within 0.72.
TEST(PathGenerator, PatchIsolinesAreWithinTheToleranceAtTheLeastOne) { CheckPatchIsolines(185); }

TEST(PathGenerator, LeavesOutTheEdgesAnotherPatchDraws) {
  for (const std::uint8_t skip : {0, 1, 2, 4, 8, 5, 15}) {
    protocol::Command command = BumpPatch(100, 900, 250, 4);
    command.body.patch.skip_lines = skip;
    std::uint8_t detail = 0;
    ASSERT_EQ(motion::ValidateCommand<2>(command, Config(4000), &detail),
              protocol::ErrorCode::kNone);
    motion::PathGenerator<2> generator;
    const std::int32_t origin[2] = {0, 0};
    generator.Reset(origin, false);
    generator.Start(command);
    int strokes = 0;
    std::uint8_t entry = 0;
    while (generator.Next(&entry)) strokes += motion::KindOf(entry) == EntryKind::kPenDown ? 1 : 0;
    int skipped = 0;
    for (int bit = 0; bit < 4; ++bit) skipped += (skip >> bit) & 1;
    EXPECT_EQ(strokes, 8 - skipped) << "skip_lines " << int{skip};
  }
}

TEST(PathGenerator, MoveStepsThroughRoundedPointsOfTheStraightLine) {
  motion::PathGenerator<2> generator;
  const std::int32_t start[2] = {17, 5};
  generator.Reset(start, true);
  protocol::Command move;
  move.type = protocol::MessageType::kMove;
  move.body.move.target[0] = 1017;
  move.body.move.target[1] = 382;
  move.body.move.target[2] = 0;
  generator.Start(move);
  std::array<long double, 2> p{17, 5};
  std::uint8_t entry = 0;
  int moves = 0;
  while (generator.Next(&entry)) {
    if (motion::KindOf(entry) != EntryKind::kMove) continue;
    ++moves;
    for (int a = 0; a < 2; ++a) {
      if ((entry >> (2 * a) & 1) != 0) p[a] += (entry >> (2 * a) & 2) != 0 ? -1 : 1;
    }
    // Each point is a point of the line 17 + 1000u, 5 + 377u with both
    // coordinates rounded: u is within 0.5/1000 of (x − 17)/1000, so y is
    // within 0.5 + 0.377·0.5 of the line at that u.
    const long double u = (p[0] - 17) / 1000.0L;
    EXPECT_LE(std::fabs(p[1] - (5 + 377 * u)), 0.5L + 0.377L * 0.5L + 1e-9L);
  }
  // x steps at most once a move; y's roundings sometimes change at other
  // parameters than x's, which costs a move of its own.
  EXPECT_GE(moves, 1000);
  EXPECT_LE(moves, 1000 + 377);
  EXPECT_EQ(p[0], 1017);
  EXPECT_EQ(p[1], 382);
}

// A straight move is stepped by a 32-bit counter, not the adaptive cursor:
// it must emit the points the adaptive cursor emits for the move's line at
// StraightMoveLevel (with Int128, which takes every length), at lengths from
// 0 to 2^20 steps on the longest axis, negative and positive, and every
// point must be the rounded point of the line at j/2^L (halves up, computed
// here in __int128).
TEST(StraightMoveCursor, EmitsTheAdaptiveCursorsPointsOfTheMove) {
  std::mt19937_64 rng(20261206);
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = motion::kLineToleranceQ8;
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int bits = trial % 21;
    const std::int32_t longest = static_cast<std::int32_t>(rng() % ((1u << bits) + 1));
    std::int32_t from[3];
    std::int32_t to[3];
    PowerCurve1 line[3];
    for (int c = 0; c < 3; ++c) {
      from[c] = static_cast<std::int32_t>(rng() % (1u << 26));
      const std::int32_t length =
          c == 0 ? longest : static_cast<std::int32_t>(rng() % (std::uint64_t(longest) + 1));
      to[c] = rng() % 2 == 0 && from[c] >= length ? from[c] - length : from[c] + length;
      line[c] =
          PowerCurve1{{0, 0, std::int64_t{to[c] - from[c]} << 16, std::int64_t{from[c]} << 16}};
    }
    const int level = motion::StraightMoveLevel(line);
    PreparedAdaptiveCurve<3> prepared;
    ASSERT_EQ(PrepareAdaptiveCurveAtLevel(line, level, settings, &prepared), Status::kOk);
    AdaptiveCurveCursor<Int128, 3> adaptive(prepared);
    motion::StraightMoveCursor<3> straight;
    straight.Reset(from, to, level);
    std::int32_t expected[3];
    std::int32_t point[3];
    std::uint32_t position = 0;
    while (adaptive.Next(expected, &position)) {
      ASSERT_TRUE(straight.Next(point)) << trial;
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(point[c], expected[c]) << trial << " at " << position;
        const __int128 twice = (__int128{2} * from[c] + 1) * (__int128{1} << level) +
                               __int128{2} * (to[c] - from[c]) * position;
        ASSERT_EQ(point[c], static_cast<std::int32_t>(twice >> (level + 1))) << trial;
      }
      ++checked;
    }
    EXPECT_FALSE(straight.Next(point)) << trial;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(point[c], to[c]) << trial;
  }
  EXPECT_GT(checked, 1000000);
}

// The DDA of a line's chords against the closed form it promises: event k
// of N = ⌈max |Q − P| / 2^8⌉ lands on floor((P + k·(Q − P)/N) / 2^8), computed
// here in 64 bits from unwrapped points while the DDA gets them wrapped to 32
// bits, near the wrap and far from it, over chains of chords; every point
// moves each axis at most one step, repeats are left out, and the chain ends
// on the last point rounded.
TEST(ChordDda, EveryPointIsTheExactChordPointRounded) {
  std::mt19937_64 rng(20261207);
  int events_checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // Near the int32 wrap (2^31 / 2^8 steps) on odd trials.
    std::int64_t fine[3];
    for (auto& f : fine) {
      f = static_cast<std::int64_t>(rng() % (1u << 20)) +
          (trial % 2 == 1 ? (std::int64_t{1} << 31) - (1 << 19) : 0);
    }
    const auto floor256 = [](std::int64_t v) { return v >= 0 ? v / 256 : -((-v + 255) / 256); };
    const auto wrapped = [](std::int64_t v) {
      return static_cast<std::int32_t>(static_cast<std::uint32_t>(static_cast<std::uint64_t>(v)));
    };
    std::int32_t start[3];
    std::int32_t point[3];
    for (int c = 0; c < 3; ++c) {
      start[c] = wrapped(fine[c]);
      point[c] = static_cast<std::int32_t>(floor256(fine[c]));
    }
    motion::ChordDda<3> dda;
    dda.Start(start, point);
    std::array<std::int64_t, 3> at{point[0], point[1], point[2]};
    for (int chord = 0; chord < 8; ++chord) {
      const std::int64_t reach = std::int64_t{1} << (rng() % 17);  // up to 256 steps
      std::int64_t delta[3];
      std::int32_t next[3];
      std::int64_t events = 1;
      for (int c = 0; c < 3; ++c) {
        delta[c] = static_cast<std::int64_t>(rng() % (2 * reach + 1)) - reach;
        next[c] = wrapped(fine[c] + delta[c]);
        events = std::max<std::int64_t>(events, (std::llabs(delta[c]) + 255) / 256);
      }
      dda.Chord(next, false);
      std::vector<std::array<std::int64_t, 3>> expected;
      for (std::int64_t k = 1; k <= events; ++k) {
        std::array<std::int64_t, 3> p{};
        for (int c = 0; c < 3; ++c) {
          const std::int64_t numerator = events * fine[c] + k * delta[c];
          const std::int64_t modulus = 256 * events;
          p[c] = numerator >= 0 ? numerator / modulus : -((-numerator + modulus - 1) / modulus);
        }
        if (p != (expected.empty() ? at : expected.back())) expected.push_back(p);
      }
      for (const auto& p : expected) {
        ASSERT_TRUE(dda.Next(point)) << trial;
        for (int c = 0; c < 3; ++c) {
          ASSERT_EQ(point[c], static_cast<std::int32_t>(p[c])) << trial << " chord " << chord;
          ASSERT_LE(std::llabs(p[c] - at[c]), 1) << trial;
        }
        at = p;
        ++events_checked;
      }
      ASSERT_FALSE(dda.Next(point)) << trial;
      for (int c = 0; c < 3; ++c) {
        fine[c] += delta[c];
        EXPECT_EQ(at[c], floor256(fine[c])) << trial;
      }
    }
  }
  EXPECT_GT(events_checked, 100000);
}

// A finest step is one event: its ends, each the curve's point rounded, are
// at most one step apart, and the chord between them (whose error the
// budget does not bound) is not sampled. The same chord as an ordinary one
// is two events, and the first lands on its midpoint rounded.
TEST(ChordDda, AFinestStepIsOneEventToItsEnd) {
  const std::int32_t start[2] = {127, 250};  // the point (0, 0)
  const std::int32_t origin[2] = {0, 0};
  const std::int32_t end[2] = {127 + 257, 300};  // (1, 1), 257/256 steps along x
  std::int32_t point[2];
  motion::ChordDda<2> finest;
  finest.Start(start, origin);
  finest.Chord(end, true);
  ASSERT_TRUE(finest.Next(point));
  EXPECT_EQ(point[0], 1);
  EXPECT_EQ(point[1], 1);
  EXPECT_FALSE(finest.Next(point));
  motion::ChordDda<2> ordinary;
  ordinary.Start(start, origin);
  ordinary.Chord(end, false);
  ASSERT_TRUE(ordinary.Next(point));
  EXPECT_EQ(point[0], 0);  // floor((2·127 + 257) / 512)
  EXPECT_EQ(point[1], 1);  // floor((2·250 + 50) / 512)
  ASSERT_TRUE(ordinary.Next(point));
  EXPECT_EQ(point[0], 1);
  EXPECT_EQ(point[1], 1);
  EXPECT_FALSE(ordinary.Next(point));
}

TEST(ValidateCommand, RefusesWhatWouldLeaveTheTravelOrTheEngine) {
  std::uint8_t detail = 0;
  // Inside.
  EXPECT_EQ(motion::ValidateCommand<2>(BumpPatch(100, 900, 250, 4), Config(4000), &detail),
            protocol::ErrorCode::kNone);
  // The bump pokes out at the top (y), though the corners are inside.
  EXPECT_EQ(motion::ValidateCommand<2>(BumpPatch(100, 900, 3100, 4), Config(1500), &detail),
            protocol::ErrorCode::kOutOfTravel);
  EXPECT_EQ(detail, 1);
  // A curve that dips below y = 0 is refused; one whose control points lie
  // below 0 but whose curve stays above is accepted: the hull test alone
  // would refuse it, halving the hull decides.
  protocol::Command curve;
  curve.type = protocol::MessageType::kCurve;
  curve.body.curve.basis = Basis::kBezier;
  curve.body.curve.dims = 2;
  curve.body.curve.tolerance_q8 = 512;
  const double xs[4] = {10, 400, 800, 1190};
  const double ys[4] = {40, -40, -40, 40};  // the curve dips to y = -20: outside
  for (int i = 0; i < 4; ++i) {
    curve.body.curve.geometry[0].g[i] = GeometryFixed::FromRaw(std::llround(xs[i] * 65536));
    curve.body.curve.geometry[1].g[i] = GeometryFixed::FromRaw(std::llround(ys[i] * 65536));
  }
  EXPECT_EQ(motion::ValidateCommand<2>(curve, Config(1200), &detail),
            protocol::ErrorCode::kOutOfTravel);
  EXPECT_EQ(detail, 1);
  const double inside[4] = {40, -4, -4, 40};  // hull below 0, curve dips only to 13
  for (int i = 0; i < 4; ++i) {
    curve.body.curve.geometry[1].g[i] = GeometryFixed::FromRaw(std::llround(inside[i] * 65536));
  }
  EXPECT_EQ(motion::ValidateCommand<2>(curve, Config(1200), &detail), protocol::ErrorCode::kNone);
  // A tolerance whole steps cannot meet.
  EXPECT_EQ(motion::ValidateCommand<2>(BumpPatch(100, 900, 250, 4, 100), Config(4000), &detail),
            protocol::ErrorCode::kPlannerRefused);
  EXPECT_EQ(detail, static_cast<std::uint8_t>(Status::kToleranceUnreachable));
  // Dimensions.
  EXPECT_EQ(motion::ValidateCommand<3>(BumpPatch(100, 900, 250, 4), Config(4000), &detail),
            protocol::ErrorCode::kDimsMismatch);
  // Moves.
  protocol::Command move;
  move.type = protocol::MessageType::kMove;
  move.body.move.target[0] = 1201;
  move.body.move.target[1] = 0;
  EXPECT_EQ(motion::ValidateCommand<2>(move, Config(1200), &detail),
            protocol::ErrorCode::kOutOfTravel);
  EXPECT_EQ(detail, 0);
}

// Every straight move between two points of the largest travel the device
// accepts is planned by the engine: the execution of a move (and the travel
// before a line) can never be refused, wherever the machine is.
TEST(ValidateCommand, EveryMoveInsideTheLargestTravelIsPlannable) {
  const std::int64_t t = std::int64_t{motion::kMaxPlannableTravelSteps} << 16;
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = motion::kLineToleranceQ8;
  const auto line = [](std::int64_t from, std::int64_t to) {
    PowerCurve1 axis{};
    axis.c[2] = to - from;
    axis.c[3] = from;
    return axis;
  };
  PreparedAdaptiveCurve<3> prepared3;
  PreparedAdaptiveCurve<2> prepared2;
  for (const auto& [from, to] : {std::pair{t, std::int64_t{0}}, std::pair{std::int64_t{0}, t}}) {
    PowerCurve1 curve3[3] = {line(from, to), line(from, to), line(from, to)};
    EXPECT_EQ(PrepareAdaptiveCurve(curve3, settings, &prepared3), Status::kOk);
    PowerCurve1 curve2[2] = {line(from, to), line(to, from)};
    EXPECT_EQ(PrepareAdaptiveCurve(curve2, settings, &prepared2), Status::kOk);
    // Execution sets moves up at StraightMoveLevel without the planner.
    EXPECT_EQ(motion::StraightMoveLevel(curve2), prepared2.finest_level);
    PreparedAdaptiveCurve<2> at_level;
    EXPECT_EQ(
        PrepareAdaptiveCurveAtLevel(curve2, motion::StraightMoveLevel(curve2), settings, &at_level),
        Status::kOk);
  }
  // The move's level is the planner's for every length, 0 to 2^26 steps.
  for (int bits = 0; bits <= 42; ++bits) {
    for (const std::int64_t length :
         {(std::int64_t{1} << bits) - 1, std::int64_t{1} << bits, (std::int64_t{1} << bits) + 1}) {
      if (length > t) continue;  // over the cap (refused above)
      PowerCurve1 curve2[2] = {line(0, length), line(length / 3, 0)};
      ASSERT_EQ(PrepareAdaptiveCurve(curve2, settings, &prepared2), Status::kOk) << length;
      EXPECT_EQ(motion::StraightMoveLevel(curve2), prepared2.finest_level) << length;
    }
  }
  // One step more and the engine refuses: the cap is where it has to be.
  PowerCurve1 longer[2] = {line(t + 65536, 0), line(0, 0)};
  EXPECT_EQ(PrepareAdaptiveCurve(longer, settings, &prepared2), Status::kPrecisionUnreachable);
  // Beyond the cap nothing is accepted against such a configuration.
  protocol::MachineConfig config = Config(motion::kMaxPlannableTravelSteps + 1);
  protocol::Command move;
  move.type = protocol::MessageType::kMove;
  move.body.move.target[0] = 1;
  move.body.move.target[1] = 1;
  std::uint8_t detail = 9;
  EXPECT_EQ(motion::ValidateCommand<2>(move, config, &detail), protocol::ErrorCode::kOutOfTravel);
  EXPECT_EQ(detail, 0);
}

// The travel check is sound and nearly exact: random cubics against an
// exact dense evaluation. Never accepted when the curve reaches
// travel + 1/2 (or −1/2); always accepted when it stays 1/16 step inside.
TEST(ValidateCommand, TheTravelCheckIsSoundAndNearlyExact) {
  std::mt19937_64 random(12);
  std::uniform_real_distribution<double> unit(-1, 1);
  constexpr std::int32_t kTravel = 16000;
  const protocol::MachineConfig config = Config(kTravel);
  int accepted = 0;
  int refused = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    protocol::Command curve;
    curve.type = protocol::MessageType::kCurve;
    curve.body.curve = protocol::CurveCommand{};
    curve.body.curve.basis = Basis::kBezier;
    curve.body.curve.dims = 2;
    curve.body.curve.tolerance_q8 = 512;
    const double spread = trial % 3 == 0 ? 30 : trial % 3 == 1 ? 3000 : 20000;
    for (int i = 0; i < 4; ++i) {
      curve.body.curve.geometry[0].g[i] = GeometryFixed::FromRaw(
          std::llround((kTravel / 2 + 0.4 * kTravel * unit(random)) * 65536));
      // y near the top: control points above it, the curve near it.
      const bool inner = i == 1 || i == 2;
      const double y = kTravel + spread * (inner ? 0.4 * unit(random) : -0.5 + 0.3 * unit(random));
      curve.body.curve.geometry[1].g[i] = GeometryFixed::FromRaw(std::llround(y * 65536));
    }
    PowerCurve1 power[2];
    CurveGeometry1 geometry[2] = {curve.body.curve.geometry[0], curve.body.curve.geometry[1]};
    ASSERT_EQ(CurvePowerCoefficients(geometry, Basis::kBezier, power), Status::kOk);
    long double low = 1e30L;
    long double high = -1e30L;
    for (int k = 0; k <= 20000; ++k) {
      const long double y = Evaluate(power[1], k / 20000.0L);
      low = std::min(low, y);
      high = std::max(high, y);
    }
    std::uint8_t detail = 0;
    const protocol::ErrorCode error = motion::ValidateCommand<2>(curve, config, &detail);
    if (high >= kTravel + 0.5L || low < -0.5L) {
      EXPECT_EQ(error, protocol::ErrorCode::kOutOfTravel) << trial << " reaches " << high;
    } else if (high < kTravel + 0.5L - 1.0L / 16) {
      EXPECT_EQ(error, protocol::ErrorCode::kNone) << trial << " stays below " << high;
    }
    (error == protocol::ErrorCode::kNone ? accepted : refused) += 1;
  }
  EXPECT_GT(accepted, 100);
  EXPECT_GT(refused, 100);
}

// The travel check's pieces are rounded (64-bit, docs/motion.md): every
// coefficient of a piece at depth D is within 3D/2 units of the exact one,
// checked against the piece's exact Bernstein coefficients in __int128 (times
// 8^D, so that they are integers) for random lines up to the largest travel.
TEST(ValidateCommand, TheTravelHullIsWithinItsSlackOfTheExactPiece) {
  std::mt19937_64 random(31);
  __extension__ using Wide = __int128;
  int rounded = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int bits = 4 + static_cast<int>(random() % 44);  // coefficients up to 2^47
    std::int64_t k[4];
    for (std::int64_t& value : k) {
      value = static_cast<std::int64_t>(random() % (std::uint64_t{1} << bits)) -
              (std::int64_t{1} << (bits - 1));
    }
    const std::int32_t travel = 1 + static_cast<std::int32_t>(random() % (1u << 26));
    std::uint64_t whole[4];
    std::uint64_t low3 = 0;
    std::uint64_t high3 = 0;
    const int shift = motion::internal::TravelHullOf(k, travel, whole, &low3, &high3);
    ASSERT_GE(shift, 8);
    const Wide offset = Wide{1} << 62;
    EXPECT_EQ(Wide(low3) - offset, Wide{-3 * 32768} << shift);
    EXPECT_EQ(Wide(high3) - offset, (Wide{3} * (Wide{travel} * 65536 + 32768)) << shift);
    const int depth = static_cast<int>(random() % (motion::kHullMaxDepth + 1));
    const std::uint64_t j = random() % (std::uint64_t{1} << depth);
    std::uint64_t hull[4] = {whole[0], whole[1], whole[2], whole[3]};
    for (int bit = depth - 1; bit >= 0; --bit) {
      motion::internal::KeepHalfOfHull(hull, ((j >> bit) & 1u) != 0);
    }
    // The piece in its own parameter, times 8^D: a, 3aj + b·2^D,
    // 3aj² + 2bj·2^D + c·4^D, aj³ + bj²·2^D + cj·4^D + d·8^D.
    const Wide a = k[0];
    const Wide b = k[1];
    const Wide c = k[2];
    const Wide d = k[3];
    const Wide h = Wide{1} << depth;
    const Wide jj = static_cast<Wide>(j);
    const Wide pa = a;
    const Wide pb = 3 * a * jj + b * h;
    const Wide pc = 3 * a * jj * jj + 2 * b * jj * h + c * h * h;
    const Wide pd = a * jj * jj * jj + b * jj * jj * h + c * jj * h * h + d * h * h * h;
    const Wide exact[4] = {3 * pd, 3 * pd + pc, 3 * pd + 2 * pc + pb, 3 * (pa + pb + pc + pd)};
    const Wide slack = Wide{3} * depth * (h * h * h) / 2;
    for (int i = 0; i < 4; ++i) {
      const Wide error = (Wide(hull[i]) - offset) * (h * h * h) - (exact[i] << shift);
      EXPECT_LE(error, 0) << trial << " coefficient " << i;  // rounded down
      EXPECT_GE(error, -slack) << trial << " coefficient " << i << " depth " << depth;
      rounded += error != 0 ? 1 : 0;
    }
  }
  EXPECT_GT(rounded, 1000);  // the rounding does happen: the bound is not vacuous
}

// A curve whose peak is exactly at T + 1/2 (it would round to T + 1) is
// refused, and one 1/64 step below is accepted: the rounded pieces decide the
// edge as the exact curve does. The peak is at a parameter 15 halvings deep,
// where the pieces' coefficients are rounded.
// A PREPARED_CURVE of `power` at the level the planner chooses.
protocol::Command PreparedAtThePlannersLevel(const PowerCurve1 (&power)[2]) {
  protocol::Command command;
  command.type = protocol::MessageType::kPreparedCurve;
  command.body.prepared_curve = protocol::PreparedCurveCommand{};
  protocol::PreparedCurveCommand& prepared = command.body.prepared_curve;
  prepared.dims = 2;
  prepared.tolerance_q8 = 512;
  prepared.power[0] = power[0];
  prepared.power[1] = power[1];
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = prepared.tolerance_q8;
  PreparedAdaptiveCurve<2> planned;
  EXPECT_EQ(PrepareAdaptiveCurve(power, settings, &planned), Status::kOk);
  prepared.level = planned.finest_level;
  return command;
}

TEST(ValidateCommand, ACurvePeakingOnTheEdgeIsRefusedDespiteTheRounding) {
  constexpr std::int32_t kTravel = 16000;
  const protocol::MachineConfig config = Config(kTravel);
  // y(u) = M − 3·4^15·(u − 16385/2^15)², x a short line inside.
  const std::int64_t apex = 16385;
  for (const std::int64_t below : {std::int64_t{0}, std::int64_t{1024}}) {
    PowerCurve1 power[2] = {};
    power[0].c[2] = 100 * 65536;
    power[0].c[3] = 5000 * 65536;
    power[1].c[1] = -3 * (std::int64_t{1} << 30);
    power[1].c[2] = 6 * (std::int64_t{1} << 15) * apex;
    power[1].c[3] = std::int64_t{kTravel} * 65536 + 32768 - below - 3 * apex * apex;
    std::uint8_t detail = 0;
    const protocol::ErrorCode error =
        motion::ValidateCommand<2>(PreparedAtThePlannersLevel(power), config, &detail);
    if (below == 0) {
      EXPECT_EQ(error, protocol::ErrorCode::kOutOfTravel);
      EXPECT_EQ(detail & 0x7f, 1);
    } else {
      EXPECT_EQ(error, protocol::ErrorCode::kNone) << int{detail};
    }
  }
}

// 3000 random cubics moved so that their top is within 3·2^-16 step below
// T + 1/2 (and as many near −1/2): every one is accepted, within the budget
// of hull tests. docs/motion.md quotes the most tests one took.
TEST(ValidateCommand, CurvesGrazingTheEdgeAreAcceptedWithinTheBudget) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<long double> unit(0, 1);
  constexpr std::int32_t kTravel = 16000;
  const protocol::MachineConfig config = Config(kTravel);
  std::uint32_t most = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const bool top = trial % 2 == 0;
    const long double spread = trial % 3 == 0 ? 30 : trial % 3 == 1 ? 3000 : 7000;
    PowerCurve1 power[2] = {};
    power[0].c[2] = 100 * 65536;
    power[0].c[3] = 5000 * 65536;
    // A Bézier hump (or dip) with its ends 0..1 of spread inside the edge,
    // at most 2.2 spreads long: inside the travel.
    long double p[4];
    for (int i = 0; i < 4; ++i) {
      const bool inner = i == 1 || i == 2;
      p[i] = spread * (inner ? 0.2L + unit(random) : -unit(random));
      if (!top) p[i] = -p[i];
    }
    const long double k[4] = {-p[0] + 3 * p[1] - 3 * p[2] + p[3], 3 * p[0] - 6 * p[1] + 3 * p[2],
                              -3 * p[0] + 3 * p[1], p[0]};
    for (int i = 0; i < 3; ++i) power[1].c[i] = std::llround(k[i] * 65536);
    // The extreme of the integer cubic (d = 0), by a dense search refined
    // around its best sample.
    PowerCurve1 shape = power[1];
    long double best_u = 0;
    long double extreme = 0;
    for (int step = 0; step <= 4096; ++step) {
      const long double u = step / 4096.0L;
      const long double y = Evaluate(shape, u) * (top ? 1 : -1);
      if (step == 0 || y > extreme) extreme = y, best_u = u;
    }
    for (long double width = 1.0L / 4096; width > 1e-12L; width /= 2) {
      for (const long double u : {best_u - width / 2, best_u + width / 2}) {
        if (u < 0 || u > 1) continue;
        const long double y = Evaluate(shape, u) * (top ? 1 : -1);
        if (y > extreme) extreme = y, best_u = u;
      }
    }
    // Put the extreme 1.5..2.5 units (2^-16 step) inside the edge, rounding
    // d down (top) or up (bottom) by at most one more unit.
    const long double inside = (1.5L + unit(random)) / 65536;
    const long double edge = top ? kTravel + 0.5L : -0.5L;
    const long double d = top ? edge - extreme - inside : edge + extreme + inside;
    power[1].c[3] = top ? static_cast<std::int64_t>(std::floor(d * 65536))
                        : static_cast<std::int64_t>(std::ceil(d * 65536));
    motion::ValidationWork work{0, 0, 0};
    std::uint8_t detail = 0;
    EXPECT_EQ(motion::ValidateCommand<2>(PreparedAtThePlannersLevel(power), config, &detail, &work),
              protocol::ErrorCode::kNone)
        << trial << " detail " << int{detail};
    most = std::max(most, work.hull_tests);
  }
  EXPECT_LE(most, motion::kHullTestBudget);
  RecordProperty("most_hull_tests", static_cast<int>(most));
  std::printf("3000 grazing curves: at most %u hull tests\n", most);
}

// Defect 2 of issue 12: a 1025×1025-line frame whose every inner line's hull
// crosses the travel took seconds, stepping every point. Its validation now
// has a fixed bound per line, counted here (not timed).
TEST(ValidateCommand, AFrameOf1025LinesValidatesWithinItsBudget) {
  // x rises and falls along one parameter, y along the other: every line's
  // control points reach 20 000, every line stays below 15 250.
  protocol::Command patch = BumpPatch(100, 1000, 0, 1025);
  const double bump[4] = {1000, 20000, 20000, 1000};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      patch.body.patch.geometry[0].g[i][j] = GeometryFixed::FromRaw(std::llround(bump[j] * 65536));
      patch.body.patch.geometry[1].g[i][j] = GeometryFixed::FromRaw(std::llround(bump[i] * 65536));
    }
  }
  const protocol::MachineConfig config = Config(16000);
  motion::ValidationWork work{0, 0, 0};
  std::uint8_t detail = 0;
  EXPECT_EQ(motion::ValidateCommand<2>(patch, config, &detail, &work), protocol::ErrorCode::kNone)
      << int{detail};
  EXPECT_EQ(work.lines, 2u * 1025u);
  // The documented bound: kDims · kHullTestBudget hull tests per line.
  EXPECT_LE(work.hull_tests, work.lines * 2u * motion::kHullTestBudget);
  // In fact a few per crossing line (docs/motion.md quotes this figure).
  EXPECT_GT(work.hull_tests, 1000u);  // the hull does cross: the test is not vacuous
  EXPECT_LE(work.hull_tests, work.lines * 40u);
  RecordProperty("hull_tests", static_cast<int>(work.hull_tests));
  std::printf("frame of 1025x1025 lines: %u lines, %u hull tests\n", work.lines, work.hull_tests);
}

// --- The device ------------------------------------------------------------

class DeviceTest : public ::testing::Test {
 protected:
  using Device = device::Device<2, 4, 256>;
  DeviceTest() : steps_(clock_, 2), pen_(clock_), device_(kTickHz) {}

  protocol::ErrorCode Accept(const protocol::Command& command, std::uint8_t* detail) {
    return device_.Accept(command, detail);
  }
  protocol::Command Configure(std::int32_t travel = 4000) {
    protocol::Command command;
    command.type = protocol::MessageType::kConfig;
    command.body.config = Config(travel);
    return command;
  }
  // Main loop and step timer until idle (or `limit` ticks).
  void RunUntilIdle(std::uint64_t limit = 20'000'000) {
    for (std::uint64_t t = 0; t < limit; ++t) {
      device_.Fill();
      ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
      clock_.Advance(25);
      if (device_.Idle()) return;
    }
    FAIL() << "not idle after " << limit << " ticks";
  }
  protocol::StatusReport Status() {
    protocol::StatusReport report{};
    device_.FillStatus(&report);
    return report;
  }

  hal::SimClock clock_;
  hal::SimStepDir steps_;
  hal::SimPen pen_;
  Device device_;
};

TEST_F(DeviceTest, RefusesMotionBeforeConfigurationAndConfigurationsItCannotServe) {
  std::uint8_t detail = 0;
  EXPECT_EQ(Accept(BumpPatch(100, 900, 250, 4), &detail), protocol::ErrorCode::kNotConfigured);
  protocol::Command config = Configure();
  config.body.config.axes = 3;
  EXPECT_EQ(Accept(config, &detail), protocol::ErrorCode::kDimsMismatch);
  config = Configure();
  config.body.config.max_rate = kTickHz + 1;
  EXPECT_EQ(Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldMaxRate);
  config = Configure();
  config.body.config.accel = 1;
  EXPECT_EQ(Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldAccel);
  // Issue 12, defect 1: a travel whose moves the engine cannot plan (70 m at
  // 1 µm steps) was accepted, and a long move then faulted the device.
  config = Configure(70'000'000);
  EXPECT_EQ(Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldTravel);
  config = Configure(motion::kMaxPlannableTravelSteps);
  config.body.config.travel_steps[1] = motion::kMaxPlannableTravelSteps + 1;
  EXPECT_EQ(Accept(config, &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kConfigFieldTravel + 1);
  EXPECT_EQ(device_.Credits(), 4);  // nothing was queued
}

TEST_F(DeviceTest, ExecutesInOrderAndCountsEveryCommandOnce) {
  std::uint8_t detail = 0;
  ASSERT_EQ(Accept(Configure(), &detail), protocol::ErrorCode::kNone);
  ASSERT_EQ(Accept(BumpPatch(100, 900, 250, 3), &detail), protocol::ErrorCode::kNone);
  protocol::Command pen;
  pen.type = protocol::MessageType::kPen;
  pen.body.pen.down = true;
  ASSERT_EQ(Accept(pen, &detail), protocol::ErrorCode::kNone);
  protocol::Command move;
  move.type = protocol::MessageType::kMove;
  move.body.move.target[0] = 3000;
  move.body.move.target[1] = 200;
  move.body.move.target[2] = 0;
  ASSERT_EQ(Accept(move, &detail), protocol::ErrorCode::kNone);
  EXPECT_EQ(device_.Credits(), 0);
  RunUntilIdle();
  const protocol::StatusReport status = Status();
  EXPECT_EQ(status.state, protocol::DeviceState::kIdle);
  EXPECT_EQ(status.executed, 4u);  // config, patch, pen, move
  EXPECT_EQ(status.position[0], 3000);
  EXPECT_EQ(status.position[1], 200);
  EXPECT_TRUE(status.pen_down);  // the last command put it down
  EXPECT_EQ(steps_.position(0), 3000);
  EXPECT_EQ(steps_.position(1), 200);
}

TEST_F(DeviceTest, StopDropsTheQueueComesToRestAndLiftsThePen) {
  std::uint8_t detail = 0;
  ASSERT_EQ(Accept(Configure(), &detail), protocol::ErrorCode::kNone);
  ASSERT_EQ(Accept(BumpPatch(100, 900, 250, 6), &detail), protocol::ErrorCode::kNone);
  ASSERT_EQ(Accept(BumpPatch(1200, 900, 250, 6), &detail), protocol::ErrorCode::kNone);
  for (int t = 0; t < 200000; ++t) {  // 5 s: well into the first patch
    device_.Fill();
    ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
    clock_.Advance(25);
  }
  ASSERT_TRUE(pen_.down() || !pen_.events().empty());
  device_.Stop();
  EXPECT_EQ(Accept(BumpPatch(100, 900, 250, 3), &detail), protocol::ErrorCode::kStopped);
  RunUntilIdle();
  EXPECT_FALSE(pen_.down());
  EXPECT_EQ(Status().state, protocol::DeviceState::kIdle);
  EXPECT_EQ(Status().queued, 0);
  // The stop kept the acceleration limit: the recorded motion passes the checks.
  const sim::MotionReport report =
      sim::CheckMotion(steps_.events(), pen_.events(), SiLimits(8000, 160000, 0.010));
  EXPECT_EQ(report.violations, 0u) << report.first_violation;
  // It accepts work again afterwards, from where it stopped.
  ASSERT_EQ(Accept(BumpPatch(100, 900, 250, 3), &detail), protocol::ErrorCode::kNone);
  RunUntilIdle();
  EXPECT_EQ(Status().state, protocol::DeviceState::kIdle);
}

TEST_F(DeviceTest, AFailingOutputFaultsTheDevice) {
  std::uint8_t detail = 0;
  ASSERT_EQ(Accept(Configure(), &detail), protocol::ErrorCode::kNone);
  ASSERT_EQ(Accept(BumpPatch(100, 900, 250, 3), &detail), protocol::ErrorCode::kNone);
  for (int t = 0; t < 40000; ++t) {
    device_.Fill();
    ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
    clock_.Advance(25);
  }
  steps_.InjectError(hal::IoStatus::kIoError);
  hal::IoStatus status = hal::IoStatus::kOk;
  for (int t = 0; t < 1000 && status == hal::IoStatus::kOk; ++t) {
    device_.Fill();
    status = device_.Tick(steps_, pen_);
  }
  EXPECT_EQ(status, hal::IoStatus::kIoError);
  const protocol::StatusReport report = Status();
  EXPECT_EQ(report.state, protocol::DeviceState::kFault);
  EXPECT_EQ(report.error, protocol::ErrorCode::kOutputFailed);
  EXPECT_EQ(report.error_detail, static_cast<std::uint8_t>(hal::IoStatus::kIoError));
  // Nothing moves after that.
  const std::size_t events = steps_.events().size();
  for (int t = 0; t < 1000; ++t) (void)device_.Tick(steps_, pen_);  // faulted: only no steps count
  EXPECT_EQ(steps_.events().size(), events);
}

}  // namespace
}  // namespace fdsurf
