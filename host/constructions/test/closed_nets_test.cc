// SPDX-License-Identifier: MIT
// Row 11 of docs/constructions.md: closed spline nets (seed 004).
#include <gtest/gtest.h>

#include "construction_test_support.h"

namespace fdsurf::host {
namespace {

// ---- Row 11: closed spline nets (seed 004) ----------------------------------

std::vector<std::vector<Point3>> TorusNet(int rows, int cols) {
  std::vector<std::vector<Point3>> net(rows);
  const double pi = std::acos(-1.0);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const double a = 2 * pi * i / rows;
      const double b = 2 * pi * j / cols;
      const double r = 4 + std::cos(a) + 0.1 * j;  // not symmetric, to catch index slips
      net[i].push_back({r * std::cos(b), r * std::sin(b), std::sin(a) + 0.05 * i});
    }
  }
  return net;
}

TEST(ClosedNet, BSplineTorusClosesWithC1JoinsEverywhere) {
  const auto net = TorusNet(5, 7);
  const std::vector<Patch> patches = PeriodicNetPatches(net, Basis::kBSpline, true, true, "torus");
  ASSERT_EQ(patches.size(), 35u);
  // Patch (a,b) is the B-spline window of rows a..a+3, columns b..b+3 mod the
  // net: its corner (0,0) is (P + 4Q + R)/6 twice over, computed here again.
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 7; ++b) {
      Point3 expected{};
      const double w[3] = {1.0 / 6, 4.0 / 6, 1.0 / 6};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          for (int c = 0; c < 3; ++c) expected[c] += w[i] * w[j] * net[(a + i) % 5][(b + j) % 7][c];
        }
      }
      EXPECT_LT(Distance(EvaluateReference(patches[a * 7 + b], 0, 0), expected), 1e-12);
    }
  }
  // Every edge is shared (no boundary left), and every join is C1.
  const std::vector<EdgeJoin> joins = CheckBezierJoins(patches);
  EXPECT_EQ(joins.size(), 70u);
  for (const EdgeJoin& j : joins) EXPECT_EQ(j.join, "C1") << j.patch_a << " " << j.patch_b;
  PatchSet set;
  set.patches = patches;
  EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
}

TEST(ClosedNet, CatmullRomTubePassesThroughEveryPointOfTheClosedDirection) {
  const auto net = TorusNet(4, 6);
  const std::vector<Patch> patches =
      PeriodicNetPatches(net, Basis::kCatmullRom, true, false, "tube");
  ASSERT_EQ(patches.size(), 4u * 3u);
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 3; ++b) {
      EXPECT_LT(Distance(EvaluateReference(patches[a * 3 + b], 0, 0), net[(a + 1) % 4][b + 1]),
                1e-12);
      EXPECT_LT(Distance(EvaluateReference(patches[a * 3 + b], 1, 1), net[(a + 2) % 4][b + 2]),
                1e-12);
    }
  }
}

TEST(ClosedNet, RefusesTooSmallNetsAndOtherBases) {
  EXPECT_THROW(PeriodicNetPatches(TorusNet(2, 6), Basis::kBSpline, true, false, "x"),
               ConstructionError);
  EXPECT_THROW(PeriodicNetPatches(TorusNet(6, 3), Basis::kBSpline, true, false, "x"),
               ConstructionError);
  EXPECT_THROW(PeriodicNetPatches(TorusNet(6, 6), Basis::kBezier, true, false, "x"),
               ConstructionError);
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "closed-net", "basis": "bspline",
                "closed_s": true, "net": [[[0,0],[1,0],[2,0],[3,0]], [[0,1],[1,1],[2,1],[3,1]]]}]})",
                        "n.json");
            }),
            "n.json: construct[0]: the net is 2x4 but needs at least 3x4 points (closed rows, "
            "open columns)");
}

}  // namespace
}  // namespace fdsurf::host
