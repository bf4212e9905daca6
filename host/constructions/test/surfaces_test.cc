// SPDX-License-Identifier: MIT
// Rows 2-4 of docs/constructions.md: ruled, bilinear and Coons surfaces
// (seed 001).
#include <gtest/gtest.h>

#include "construction_test_support.h"

namespace fdsurf::host {
namespace {

// ---- Rows 2-4: ruled, bilinear, Coons (seed 001) ---------------------------

// A Bézier curve evaluated from the Bernstein polynomials, independently of
// the library.
Point3 Bezier(const std::array<Point3, 4>& p, double u) {
  const double w[4] = {(1 - u) * (1 - u) * (1 - u), 3 * u * (1 - u) * (1 - u), 3 * u * u * (1 - u),
                       u * u * u};
  Point3 r{};
  for (int k = 0; k < 4; ++k) {
    for (int c = 0; c < 3; ++c) r[c] += w[k] * p[k][c];
  }
  return r;
}

const std::array<Point3, 4> kLow = {{{0, 0, 0}, {1, -0.5, 0.3}, {2, 0.4, -0.2}, {3, 0, 0}}};
const std::array<Point3, 4> kHigh = {{{0, 3, 1}, {1.2, 3.5, 2}, {2.1, 2.6, 0.5}, {3, 3, 1.5}}};
const std::array<Point3, 4> kLeft = {{{0, 0, 0}, {-0.3, 1, 0.8}, {0.4, 2, 1.1}, {0, 3, 1}}};
const std::array<Point3, 4> kRight = {{{3, 0, 0}, {3.2, 1, -0.5}, {2.7, 2, 0.2}, {3, 3, 1.5}}};

TEST(Ruled, ItsBoundariesAreTheCurvesAndItsRulingsStraight) {
  const PatchSet set = AsSet(RuledSurface(BezierCurve(kLow), BezierCurve(kHigh)));
  ASSERT_EQ(set.patches.size(), 1u);
  for (int i = 0; i <= 20; ++i) {
    const double u = i / 20.0;
    for (int j = 0; j <= 10; ++j) {
      const double v = j / 10.0;
      const Point3 a = Bezier(kLow, u);
      const Point3 b = Bezier(kHigh, u);
      const Point3 expected{(1 - v) * a[0] + v * b[0], (1 - v) * a[1] + v * b[1],
                            (1 - v) * a[2] + v * b[2]};
      EXPECT_LT(Distance(EvaluateReference(set.patches[0], u, v), expected), 1e-12);
    }
  }
  EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
}

TEST(Bilinear, HasExactBoundaryLinesAndIsNotPlanarInGeneral) {
  const Point3 p00{0, 0, 0};
  const Point3 p10{2, 0, 0};
  const Point3 p01{0, 2, 0};
  const Point3 p11{2, 2, 1};
  const PatchSet set = AsSet(BilinearSurface(p00, p10, p01, p11));
  const Patch& patch = set.patches[0];
  const auto lerp = [](const Point3& a, const Point3& b, double x) {
    return Point3{a[0] + (b[0] - a[0]) * x, a[1] + (b[1] - a[1]) * x, a[2] + (b[2] - a[2]) * x};
  };
  for (int i = 0; i <= 16; ++i) {
    const double x = i / 16.0;
    EXPECT_LT(Distance(EvaluateReference(patch, x, 0), lerp(p00, p10, x)), 1e-12);
    EXPECT_LT(Distance(EvaluateReference(patch, x, 1), lerp(p01, p11, x)), 1e-12);
    EXPECT_LT(Distance(EvaluateReference(patch, 0, x), lerp(p00, p01, x)), 1e-12);
    EXPECT_LT(Distance(EvaluateReference(patch, 1, x), lerp(p10, p11, x)), 1e-12);
  }
  // The plane through p00, p10, p01 is z = 0; the centre lies at z = 1/4
  // (the mean of the corners), and the diagonal u = v bends: z = u².
  EXPECT_NEAR(EvaluateReference(patch, 0.5, 0.5)[2], 0.25, 1e-12);
  EXPECT_NEAR(EvaluateReference(patch, 0.3, 0.3)[2], 0.09, 1e-12);
  EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
}

void ExpectReproducesBoundaries(const Patch& patch) {
  for (int i = 0; i <= 32; ++i) {
    const double x = i / 32.0;
    EXPECT_LT(Distance(EvaluateReference(patch, x, 0), Bezier(kLow, x)), 1e-12) << x;
    EXPECT_LT(Distance(EvaluateReference(patch, x, 1), Bezier(kHigh, x)), 1e-12) << x;
    EXPECT_LT(Distance(EvaluateReference(patch, 0, x), Bezier(kLeft, x)), 1e-12) << x;
    EXPECT_LT(Distance(EvaluateReference(patch, 1, x), Bezier(kRight, x)), 1e-12) << x;
  }
}

TEST(Coons, LinearAndCubicReproduceAllFourBoundaries) {
  for (CoonsBlend blend : {CoonsBlend::kLinear, CoonsBlend::kCubic}) {
    const PatchSet set = AsSet(CoonsPatch(BezierCurve(kLow), BezierCurve(kHigh), BezierCurve(kLeft),
                                          BezierCurve(kRight), blend, 1e-9));
    ExpectReproducesBoundaries(set.patches[0]);
    EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
  }
}

TEST(Coons, LinearIsTheSumOfTwoRuledSurfacesMinusTheBilinear) {
  const PatchSet set = AsSet(CoonsPatch(BezierCurve(kLow), BezierCurve(kHigh), BezierCurve(kLeft),
                                        BezierCurve(kRight), CoonsBlend::kLinear, 1e-9));
  for (double u : {0.1, 0.45, 0.8}) {
    for (double v : {0.2, 0.5, 0.9}) {
      Point3 expected{};
      for (int c = 0; c < 3; ++c) {
        expected[c] = (1 - v) * Bezier(kLow, u)[c] + v * Bezier(kHigh, u)[c] +
                      (1 - u) * Bezier(kLeft, v)[c] + u * Bezier(kRight, v)[c] -
                      ((1 - u) * (1 - v) * kLow[0][c] + u * (1 - v) * kLow[3][c] +
                       (1 - u) * v * kHigh[0][c] + u * v * kHigh[3][c]);
      }
      EXPECT_LT(Distance(EvaluateReference(set.patches[0], u, v), expected), 1e-12);
    }
  }
}

TEST(Coons, RefusesBoundariesWhoseCornersDoNotMeet) {
  std::array<Point3, 4> right = kRight;
  right[0] = {3, 0.25, 0};
  try {
    CoonsPatch(BezierCurve(kLow), BezierCurve(kHigh), BezierCurve(kLeft), BezierCurve(right),
               CoonsBlend::kLinear, 1e-9);
    FAIL() << "accepted a gap";
  } catch (const ConstructionError& e) {
    EXPECT_EQ(std::string(e.what()),
              "corner (1,0): boundary 0 (r(u,0)) ends at (3, 0, 0) but boundary 3 (r(1,v)) "
              "starts at (3, 0.25, 0), 0.25 apart (tolerance 3.5e-09)");
  }
  EXPECT_EQ(
      InputErrorOf([] {
        ParseJson(R"({"construct": [{"type": "coons", "boundaries": [
          {"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]},
          {"basis": "bezier", "points": [[0,3],[1,3],[2,3],[3,3]]},
          {"basis": "bezier", "points": [[0,0],[0,1],[0,2],[0,3]]},
          {"basis": "bezier", "points": [[3,0],[3,1],[3,2],[3,3.5]]}]}]})",
                  "c.json");
      }),
      "c.json: construct[0].boundaries: corner (1,1): boundary 1 (r(u,1)) ends at (3, 3, 0) but "
      "boundary 3 (r(1,v)) ends at (3, 3.5, 0), 0.5 apart (tolerance 3.5e-09)");
}

TEST(Constructions, CountsThatMustBeExactSayExactly) {
  // Too few is refused as "exactly", like too many: nothing else is accepted.
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "ruled", "curves": [
                {"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]}]}]})",
                        "r.json");
            }),
            "r.json: construct[0].curves: a ruled surface takes exactly 2 curves, got 1");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "bilinear", "corners": [[0,0],[1,0],[0,1]]}]})",
                        "b.json");
            }),
            "b.json: construct[0].corners: needs exactly 4 corners [P00, P10, P01, P11], got 3");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "cubic", "basis": "bezier",
                                        "points": [[0,0],[1,0],[2,0]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].points: a cubic needs exactly 4 points, got 3");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite", "points": [[0,0]],
                                        "vectors": [[1,0]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].points: a hermite segment has exactly 2 points, got 1; use "
            "hermite-chain");
}

TEST(Ruled, RefusesAPiecewiseCurveWhoseSegmentsDoNotMeet) {
  // The second segment of curve 1 starts 0.5 above where the first ends.
  const auto read = [](const char* second_start) {
    ParseJson(std::string(R"({"construct": [{"type": "ruled", "curves": [
      [{"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]},
       {"basis": "bezier", "points": [[3,0],[4,0],[5,0],[6,0]]}],
      [{"basis": "bezier", "points": [[0,3],[1,3],[2,3],[3,3]]},
       {"basis": "bezier", "points": [)") +
                  second_start + R"(,[4,3],[5,3],[6,3]]}]]}]})",
              "r.json");
  };
  EXPECT_EQ(InputErrorOf([&] { read("[3,3.5]"); }),
            "r.json: construct[0].curves[1]: construct[0].curves[1][0] ends at (3, 3, 0) but "
            "construct[0].curves[1][1] starts at (3, 3.5, 0), 0.5 apart (tolerance 6e-09): the "
            "segments of a piecewise curve must meet");
  // Within the tolerance (10⁻⁹ of the curve's size) it is a join.
  EXPECT_EQ(InputErrorOf([&] { read("[3,3.000000001]"); }), "(no error)");
  EXPECT_EQ(InputErrorOf([&] { read("[3,3]"); }), "(no error)");
}

// F(u,v) = (u, v, sin(u)·cos(v) + u·v/4) and its first derivatives.
Point3 F(double u, double v) { return {u, v, std::sin(u) * std::cos(v) + u * v / 4}; }
Point3 Fu(double u, double v) { return {1, 0, std::cos(u) * std::cos(v) + v / 4}; }
Point3 Fv(double u, double v) { return {0, 1, -std::sin(u) * std::sin(v) + u / 4}; }

// Patch (a,b) of a 2×2 grid on [0,2]², bounded by the C¹ Hermite splines
// through F along the grid lines.
Patch GridPatch(int a, int b, CoonsBlend blend) {
  const Curve r1 = HermiteSegment(F(a, b), F(a + 1, b), Fu(a, b), Fu(a + 1, b));
  const Curve r2 = HermiteSegment(F(a, b + 1), F(a + 1, b + 1), Fu(a, b + 1), Fu(a + 1, b + 1));
  const Curve r3 = HermiteSegment(F(a, b), F(a, b + 1), Fv(a, b), Fv(a, b + 1));
  const Curve r4 = HermiteSegment(F(a + 1, b), F(a + 1, b + 1), Fv(a + 1, b), Fv(a + 1, b + 1));
  return AsSet(CoonsPatch(r1, r2, r3, r4, blend, 1e-9)).patches[0];
}

double WorstDerivativeJump(CoonsBlend blend) {
  const Patch p00 = GridPatch(0, 0, blend);
  const Patch p10 = GridPatch(1, 0, blend);
  const Patch p01 = GridPatch(0, 1, blend);
  double worst = 0;
  for (int k = 0; k <= 20; ++k) {
    const double x = k / 20.0;
    // Across u = 1: patch (0,0) at s = 1 against patch (1,0) at s = 0.
    EXPECT_LT(Distance(EvaluateReference(p00, 1, x), EvaluateReference(p10, 0, x)), 1e-12);
    worst = std::max(worst, Distance(Derivative(p00, 1, x, 0), Derivative(p10, 0, x, 0)));
    // Across v = 1: patch (0,0) at t = 1 against patch (0,1) at t = 0.
    EXPECT_LT(Distance(EvaluateReference(p00, x, 1), EvaluateReference(p01, x, 0)), 1e-12);
    worst = std::max(worst, Distance(Derivative(p00, x, 1, 1), Derivative(p01, x, 0, 1)));
  }
  return worst;
}

TEST(Coons, CubicBlendingJoinsAGridWithContinuousTangentPlanes) {
  // Equal parameter steps, so C¹ in the patch parameters: both first partial
  // derivatives, hence the tangent plane, agree across every shared edge.
  EXPECT_LT(WorstDerivativeJump(CoonsBlend::kCubic), 1e-5);
  // The linear patch does not: the cross derivative jumps.
  EXPECT_GT(WorstDerivativeJump(CoonsBlend::kLinear), 1e-2);
}

}  // namespace
}  // namespace fdsurf::host
