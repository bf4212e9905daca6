// SPDX-License-Identifier: MIT
// The plan that plot and stream share (plan.h): curves drawn twice, the
// nearest-neighbour order, and that both commands find the same shared edges.
#include "fdsurf/host/plan.h"

#include <gtest/gtest.h>

#include <string>

#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"

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
