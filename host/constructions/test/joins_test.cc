// SPDX-License-Identifier: MIT
// Row 10 of docs/constructions.md: joins between Bézier patches (seed 004).
#include <gtest/gtest.h>

#include "construction_test_support.h"

namespace fdsurf::host {
namespace {

// ---- Row 10: Bézier joins (seed 004) ----------------------------------------

TEST(BezierJoins, ClassifiesC1G1AndC0) {
  // Patch a ends at x = 3 with its last leg (1, 0, 0) flat; b starts there.
  const Patch a = FlatPatch(0, 1, 0.5, 0);
  const Patch b_c1 = FlatPatch(3, 1, 0, 0.5);
  const Patch b_g1 = FlatPatch(3, 2, 0, 0.5);
  const Patch b_c0 = FlatPatch(3, 1, 0.2, 0.5);
  const auto join_of = [&](const Patch& b) {
    const std::vector<EdgeJoin> joins = CheckBezierJoins({a, b});
    EXPECT_EQ(joins.size(), 1u);
    EXPECT_EQ(joins[0].edge_a, "s=1");
    EXPECT_EQ(joins[0].edge_b, "s=0");
    return joins[0];
  };
  EXPECT_EQ(join_of(b_c1).join, "C1");
  const EdgeJoin g1 = join_of(b_g1);
  EXPECT_EQ(g1.join, "G1");
  EXPECT_NEAR(g1.worst_ratio_error, 1.0, 1e-12);
  const EdgeJoin c0 = join_of(b_c0);
  EXPECT_EQ(c0.join, "C0");
  EXPECT_NEAR(c0.worst_angle_deg, std::atan(0.2) * 180 / std::acos(-1.0), 1e-9);
  // The same join seen from a patch whose edge runs the other way.
  Patch reversed = b_c1;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) reversed.g[i][j] = b_c1.g[i][3 - j];
  }
  EXPECT_EQ(CheckBezierJoins({a, reversed}).at(0).join, "C1");
  // Patches that share no edge have no join.
  EXPECT_TRUE(CheckBezierJoins({a, FlatPatch(10, 1, 0, 0)}).empty());
}

TEST(BezierJoins, TheTeapotIsG1EverywhereItsPatchesMeet) {
  const PatchSet teapot = ReadPatchFile(FDSURF_EXAMPLES_DIR "/teapot.bpt");
  const std::vector<EdgeJoin> joins = CheckBezierJoins(teapot.patches);
  int c1 = 0;
  int g1 = 0;
  for (const EdgeJoin& j : joins) {
    c1 += j.join == "C1" ? 1 : 0;
    g1 += j.join == "G1" ? 1 : 0;
  }
  EXPECT_EQ(joins.size(), 52u);
  EXPECT_EQ(c1, 46);
  EXPECT_EQ(g1, 6);  // rim to body (legs 1:4), the spout's rings (4:1)
}

}  // namespace
}  // namespace fdsurf::host
