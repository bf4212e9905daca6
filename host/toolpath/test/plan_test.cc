// SPDX-License-Identifier: MIT
// The plan that plot and stream share (plan.h): curves drawn twice, the
// nearest-neighbour order, chains and 2-opt, that both commands find the
// same shared edges, and that stream's lines plan is as good as plot's.
#include "fdsurf/host/plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <string>

#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/motion/path_generator.h"

namespace fdsurf::host {
namespace {

SampledCurve Line(double dx, double dy) {
  SampledCurve samples;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    samples[k] = {10.0 * static_cast<double>(k) + dx, 3.0 * static_cast<double>(k) + dy, 0};
  }
  return samples;
}

TEST(Plan, DrawnCurvesKnowsACurveInEitherDirection) {
  DrawnCurves drawn;
  EXPECT_FALSE(drawn.CheckAndAdd(Line(0, 0)));
  EXPECT_TRUE(drawn.CheckAndAdd(Line(0, 0)));
  SampledCurve reversed = Line(0, 0);
  std::reverse(reversed.begin(), reversed.end());
  EXPECT_TRUE(drawn.CheckAndAdd(reversed));
  // Within 0.1 units of every sample: the same curve, rounded differently.
  EXPECT_TRUE(drawn.CheckAndAdd(Line(0.05, -0.05)));
  // Ends shared, the middle 0.2 off: another curve, which is then known.
  SampledCurve bent = Line(0, 0);
  bent[4][1] += 0.2;
  EXPECT_FALSE(drawn.CheckAndAdd(bent));
  EXPECT_TRUE(drawn.CheckAndAdd(bent));
}

TEST(Plan, PointsAreRecognised) {
  SampledCurve pole;
  pole.fill({5, 5, 5});
  EXPECT_TRUE(IsPoint(pole));
  EXPECT_FALSE(IsPoint(Line(0, 0)));
}

TEST(Plan, NearestNeighbourFromTheOrigin) {
  // Piece 0 far away, piece 1 nearest the origin, piece 2 entered best at its end.
  const std::vector<std::array<PlanPoint, 2>> ends = {
      {PlanPoint{10, 0, 0}, PlanPoint{11, 0, 0}},
      {PlanPoint{1, 0, 0}, PlanPoint{2, 0, 0}},
      {PlanPoint{5, 0, 0}, PlanPoint{3, 0, 0}},
  };
  const auto forward = OrderNearestNeighbour(ends, false, PlanMetric::kPlane);
  ASSERT_EQ(forward.size(), 3u);
  EXPECT_EQ(forward[0].index, 1u);  // 1 away
  EXPECT_EQ(forward[1].index, 2u);  // 3 from (2, 0), against 8 for piece 0
  EXPECT_EQ(forward[2].index, 0u);
  for (const Visit& v : forward) EXPECT_FALSE(v.reversed);

  const auto either = OrderNearestNeighbour(ends, true, PlanMetric::kPlane);
  EXPECT_EQ(either[0].index, 1u);
  EXPECT_FALSE(either[0].reversed);
  EXPECT_EQ(either[1].index, 2u);  // entered at (3, 0), 1 from (2, 0)
  EXPECT_TRUE(either[1].reversed);
  EXPECT_EQ(either[2].index, 0u);  // from (5, 0): 5 to (10, 0), 6 to (11, 0)
  EXPECT_FALSE(either[2].reversed);
}

TEST(Plan, TiesGoToTheLowerIndexAndZCountsOnlyInSpace) {
  const std::vector<std::array<PlanPoint, 2>> ends = {
      {PlanPoint{0, 3, 9}, PlanPoint{0, 3, 9}},
      {PlanPoint{3, 0, 0}, PlanPoint{3, 0, 0}},
  };
  // In the plane both are 3 away: the lower index wins.
  EXPECT_EQ(OrderNearestNeighbour(ends, false, PlanMetric::kPlane)[0].index, 0u);
  // In space piece 0 is √90 away.
  EXPECT_EQ(OrderNearestNeighbour(ends, false, PlanMetric::kSpace)[0].index, 1u);
}

// One planner: the edges `plot` removes as drawn twice are the edges
// `stream` leaves out of its PATCH commands.
TEST(Plan, PlotAndStreamFindTheSameSharedEdges) {
  const PatchSet set = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt");
  ToolpathOptions o;
  o.view = *NamedView("iso");
  o.fit = std::array<double, 2>{200, 150};
  o.margin = 5;
  o.lines_s = o.lines_t = 8;
  o.quantum = Quantum::Parse("0.001");
  Toolpath path = BuildToolpath(set, o, "mm");
  const PlanReport plan = PlanStrokes(set, &path);
  const StreamJob job = BuildStreamJob(set, o, MachineOptions{}, "mm");
  EXPECT_EQ(plan.duplicates_removed, 52u);
  EXPECT_EQ(job.shared_edges_skipped, plan.duplicates_removed);
}

}  // namespace
}  // namespace fdsurf::host

namespace fdsurf::host {
namespace {

using Key = std::array<std::int64_t, 3>;

TEST(Plan, ChainTouchingJoinsPiecesThatMeetInEitherDirection) {
  // 0: (0)→(1); 1: (2)→(1) meets 0's end backwards; 2: (5)→(6) alone;
  // 3: (−1)→(0) meets 0's start.
  const std::vector<std::array<Key, 2>> ends = {
      {Key{0, 0, 0}, Key{1, 0, 0}},
      {Key{2, 0, 0}, Key{1, 0, 0}},
      {Key{5, 0, 0}, Key{6, 0, 0}},
      {Key{-1, 0, 0}, Key{0, 0, 0}},
  };
  const std::vector<std::vector<Visit>> chains = ChainTouching(ends);
  ASSERT_EQ(chains.size(), 2u);
  // Drawn as one stroke: (−1)→(0)→(1)→(2).
  ASSERT_EQ(chains[0].size(), 3u);
  EXPECT_EQ(chains[0][0].index, 3u);
  EXPECT_FALSE(chains[0][0].reversed);
  EXPECT_EQ(chains[0][1].index, 0u);
  EXPECT_FALSE(chains[0][1].reversed);
  EXPECT_EQ(chains[0][2].index, 1u);
  EXPECT_TRUE(chains[0][2].reversed);
  ASSERT_EQ(chains[1].size(), 1u);
  EXPECT_EQ(chains[1][0].index, 2u);
}

TEST(Plan, TwoOptUndoesACrossing) {
  // Four points. Nearest neighbour from the origin goes 1, 0, 2, 3:
  // √5 + 3 + √20 + √89 = 19.14; reversing the run 1, 0, 2 starts at the far
  // point 2 instead: √20 + √20 + 3 + √10 = 15.11.
  const std::vector<std::array<PlanPoint, 2>> ends = {
      {PlanPoint{2, -2, 0}, PlanPoint{2, -2, 0}},
      {PlanPoint{-1, -2, 0}, PlanPoint{-1, -2, 0}},
      {PlanPoint{4, 2, 0}, PlanPoint{4, 2, 0}},
      {PlanPoint{-4, -3, 0}, PlanPoint{-4, -3, 0}},
  };
  std::vector<Visit> order = OrderNearestNeighbour(ends, true, PlanMetric::kPlane);
  const auto travel = [&](const std::vector<Visit>& o) {
    PlanPoint at{0, 0, 0};
    double sum = 0;
    for (const Visit& v : o) {
      const PlanPoint& in = ends[v.index][v.reversed ? 1 : 0];
      sum += std::hypot(in[0] - at[0], in[1] - at[1]);
      at = ends[v.index][v.reversed ? 0 : 1];
    }
    return sum;
  };
  const double before = travel(order);
  ImproveByTwoOpt(ends, PlanMetric::kPlane, PlanPoint{0, 0, 0}, &order);
  EXPECT_NEAR(before, std::sqrt(5.0) + 3 + std::sqrt(20.0) + std::sqrt(89.0), 1e-9);
  EXPECT_NEAR(travel(order), 2 * std::sqrt(20.0) + 3 + std::sqrt(10.0), 1e-9);
  // Still every piece once.
  std::vector<std::size_t> seen;
  for (const Visit& v : order) seen.push_back(v.index);
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<std::size_t>{0, 1, 2, 3}));
}

// What a job makes the pen do, read from its commands (steps): how often it
// is lifted, and how far it travels lifted, in the plane, from the origin.
struct PenFigures {
  std::size_t lifts = 0;
  double up_steps = 0;
};

PenFigures PenFiguresOf(const StreamJob& job) {
  PenFigures out;
  bool down = false;
  std::array<double, 2> at{0, 0};
  for (const protocol::Command& c : job.commands) {
    if (c.type == protocol::MessageType::kPen) {
      if (down && !c.body.pen.down) ++out.lifts;
      down = c.body.pen.down;
    } else if (c.type == protocol::MessageType::kMove) {
      const std::array<double, 2> to{static_cast<double>(c.body.move.target[0]),
                                     static_cast<double>(c.body.move.target[1])};
      if (!down) out.up_steps += std::hypot(to[0] - at[0], to[1] - at[1]);
      at = to;
    } else if (c.type == protocol::MessageType::kCurve) {
      // Where a power-basis curve ends: the sum of its coefficients.
      for (std::size_t a = 0; a < 2; ++a) {
        double sum = 0;
        for (const GeometryFixed g : c.body.curve.geometry[a].g)
          sum += static_cast<double>(g.Raw());
        at[a] = std::round(sum / 65536.0);
      }
    } else if (c.type == protocol::MessageType::kPatch) {
      at = {std::nan(""), std::nan("")};  // the device's order; counted apart
    }
  }
  return out;
}

// The lifts of a job of PATCH commands as the device draws them
// (path_generator.h): within a patch, before every line that does not start
// where the one before ended; and at the end of every patch.
std::size_t PatchPlanLifts(const StreamJob& job) {
  std::size_t lifts = 0;
  for (const protocol::Command& c : job.commands) {
    if (c.type != protocol::MessageType::kPatch) continue;
    std::optional<std::array<std::int64_t, 2>> at;
    for (const IsolineFamily family : {IsolineFamily::kSLines, IsolineFamily::kTLines}) {
      (void)motion::ForEachDrawnLine<2>(c.body.patch, family, [&](const PowerCurve1(&line)[2]) {
        const std::array<std::int64_t, 2> start{std::llround(line[0].c[3] / 65536.0),
                                                std::llround(line[1].c[3] / 65536.0)};
        if (at && *at != start) ++lifts;
        at = std::array<std::int64_t, 2>{
            std::llround((line[0].c[0] + line[0].c[1] + line[0].c[2] + line[0].c[3]) / 65536.0),
            std::llround((line[1].c[0] + line[1].c[1] + line[1].c[2] + line[1].c[3]) / 65536.0)};
        return true;
      });
    }
    ++lifts;
  }
  return lifts;
}

struct PlanCase {
  double width, height;
  int lines_s, lines_t;
};

ToolpathOptions TeapotOptions(const PlanCase& c) {
  ToolpathOptions o;
  o.view = *NamedView("iso");
  o.fit = std::array<double, 2>{c.width, c.height};
  o.margin = 5;
  o.lines_s = c.lines_s;
  o.lines_t = c.lines_t;
  o.quantum = MachineOptions{}.step;  // one motor step, as stream maps the drawing
  return o;
}

// issue 36: the job a device is sent lifts the pen no more often, and travels
// lifted no farther, than `fdsurf plot`'s plan of the same drawing; the
// patches plan (the device's own order) does worse, which shows the check
// can fail.
TEST(StreamPlan, TheLinesPlanLiftsAndTravelsNoMoreThanPlotsPlan) {
  const PatchSet set = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt");
  const double step_mm = MachineOptions{}.step.value();
  for (const PlanCase& c : {PlanCase{60, 45, 0, 4}, PlanCase{200, 150, 8, 8}}) {
    SCOPED_TRACE(std::to_string(c.lines_s) + "x" + std::to_string(c.lines_t));
    const ToolpathOptions o = TeapotOptions(c);
    Toolpath path = BuildToolpath(set, o, "mm");
    const PlanReport plot = PlanStrokes(set, &path);
    const PenFigures lines =
        PenFiguresOf(BuildStreamJob(set, o, MachineOptions{}, "mm", StreamPlan::kLines));
    EXPECT_LE(lines.lifts, plot.strokes_after);
    EXPECT_LE(lines.up_steps * step_mm, plot.pen_up_after + 1e-6);

    const StreamJob patches = BuildStreamJob(set, o, MachineOptions{}, "mm", StreamPlan::kPatches);
    EXPECT_GT(PatchPlanLifts(patches), plot.strokes_after);
  }
}

// The lines plan draws every line the PATCH commands draw, once each (either
// way round), and nothing else.
TEST(StreamPlan, TheLinesPlanDrawsTheLinesThePatchesDraw) {
  const PatchSet set = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt");
  const ToolpathOptions o = TeapotOptions(PlanCase{200, 150, 8, 8});
  const StreamJob patches = BuildStreamJob(set, o, MachineOptions{}, "mm", StreamPlan::kPatches);
  const StreamJob lines = BuildStreamJob(set, o, MachineOptions{}, "mm", StreamPlan::kLines);
  using Line = std::array<std::int64_t, 8>;
  const auto key = [](PowerCurve1(&power)[2]) {
    Line forward{};
    for (std::size_t a = 0; a < 2; ++a) {
      for (std::size_t k = 0; k < 4; ++k) forward[4 * a + k] = power[a].c[k];
    }
    motion::ReverseCurve<2>(power);
    Line backward{};
    for (std::size_t a = 0; a < 2; ++a) {
      for (std::size_t k = 0; k < 4; ++k) backward[4 * a + k] = power[a].c[k];
    }
    return std::min(forward, backward);
  };
  std::multiset<Line> from_patches;
  for (const protocol::Command& c : patches.commands) {
    if (c.type != protocol::MessageType::kPatch) continue;
    for (const IsolineFamily family : {IsolineFamily::kSLines, IsolineFamily::kTLines}) {
      ASSERT_EQ(motion::ForEachDrawnLine<2>(c.body.patch, family,
                                            [&](const PowerCurve1(&line)[2]) {
                                              PowerCurve1 copy[2] = {line[0], line[1]};
                                              from_patches.insert(key(copy));
                                              return true;
                                            }),
                Status::kOk);
    }
  }
  std::multiset<Line> from_curves;
  for (const protocol::Command& c : lines.commands) {
    ASSERT_NE(c.type, protocol::MessageType::kPatch);
    if (c.type != protocol::MessageType::kCurve) continue;
    ASSERT_EQ(c.body.curve.basis, Basis::kPower);
    PowerCurve1 power[2];
    for (std::size_t a = 0; a < 2; ++a) {
      for (std::size_t k = 0; k < 4; ++k) power[a].c[k] = c.body.curve.geometry[a].g[k].Raw();
    }
    from_curves.insert(key(power));
  }
  // 32 patches of 8 + 8 lines, less the 52 shared edges and the 8 poles (an
  // edge line of each of the lid's top 4 patches and the bottom's 4).
  EXPECT_EQ(from_patches.size(), 32u * 16u - 52u - 8u);
  EXPECT_EQ(from_curves, from_patches);
  EXPECT_EQ(lines.shared_edges_skipped, 52u);
  EXPECT_EQ(lines.patches.size(), 32u);
}

}  // namespace
}  // namespace fdsurf::host
