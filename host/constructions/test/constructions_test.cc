// SPDX-License-Identifier: MIT
// Constructions (docs/constructions.md): every test checks a defining property
// against the construction's formula evaluated here again in double, not
// against the code under test, and the engine's bound on the result.
#include "fdsurf/host/constructions.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "fdsurf/host/fixed_curve.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quadric_hermite.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {
namespace {

double Distance(const Point3& a, const Point3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

std::string InputErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// The largest |fixed − reference| in quanta over a grid, for every patch.
double WorstFixedError(const PatchSet& set, int n, int m, const Quantum& q) {
  double worst = 0;
  for (const Patch& patch : set.patches) {
    const PreparedPatch<3> prepared = PrepareFixedPatch(patch, q, n, m);
    ForEachGridPoint(prepared, [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      const Point3 exact =
          EvaluateReference(patch, static_cast<double>(i) / n, static_cast<double>(j) / m);
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(k[c] - q.ToQuanta(exact[c])));
    });
  }
  return worst;
}

// ---- Row 1: Hermite curves (seed 002) ---------------------------------------

TEST(HermiteCurve, ReproducesTheSeedsWorkedExample) {
  // A(1,1), B(3,1), C(5,1); v = (0,1) at A, w = (0,-1) at B, s = (1,0) at C.
  const HermiteChain chain =
      MakeHermiteChain({{1, 1, 0}, {3, 1, 0}, {5, 1, 0}}, {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}},
                       {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}});
  ASSERT_EQ(chain.segments.size(), 2u);
  // The seed's product [a0 a1 a2 a3]ᵀ = M·[P0 P1 T0 T1]ᵀ with its matrix for
  // ascending powers, written out here.
  const double m[4][4] = {{1, 0, 0, 0}, {0, 0, 1, 0}, {-3, 3, -2, -1}, {2, -2, 1, 1}};
  const double gx[4] = {1, 3, 0, 0};
  const double gy[4] = {1, 1, 1, -1};
  const VecPoly p = CurvePolynomial(chain.segments[0]);
  for (int r = 0; r < 4; ++r) {
    double ax = 0;
    double ay = 0;
    for (int k = 0; k < 4; ++k) {
      ax += m[r][k] * gx[k];
      ay += m[r][k] * gy[k];
    }
    EXPECT_DOUBLE_EQ(p[r][0], ax) << r;
    EXPECT_DOUBLE_EQ(p[r][1], ay) << r;
  }
  // x(u) = 1 + 6u² − 4u³, y(u) = 1 + u − u².
  EXPECT_EQ(p[0], (Point3{1, 1, 0}));
  EXPECT_EQ(p[1], (Point3{0, 1, 0}));
  EXPECT_EQ(p[2], (Point3{6, -1, 0}));
  EXPECT_EQ(p[3], (Point3{-4, 0, 0}));
  ASSERT_EQ(chain.joins.size(), 1u);
  EXPECT_EQ(chain.joins[0], JoinClass::kParametric);
}

TEST(HermiteCurve, InterpolatesEndPointsAndEndVectors) {
  const Point3 p0{1, -2, 3};
  const Point3 p1{4, 0.5, -1};
  const Point3 t0{2, 7, -3};
  const Point3 t1{-1, 0, 5};
  const Curve c = HermiteSegment(p0, p1, t0, t1);
  EXPECT_LT(Distance(EvaluateCurve(c, 0), p0), 1e-12);
  EXPECT_LT(Distance(EvaluateCurve(c, 1), p1), 1e-12);
  const VecPoly p = CurvePolynomial(c);
  // p'(0) = a1, p'(1) = a1 + 2a2 + 3a3.
  Point3 d1{};
  for (int k = 0; k < 3; ++k) d1[k] = p[1][k] + 2 * p[2][k] + 3 * p[3][k];
  EXPECT_LT(Distance(p[1], t0), 1e-12);
  EXPECT_LT(Distance(d1, t1), 1e-12);
}

TEST(HermiteCurve, ClassifiesJoins) {
  EXPECT_EQ(ClassifyJoin({1, 2, 3}, {1, 2, 3}), JoinClass::kParametric);
  EXPECT_EQ(ClassifyJoin({1, 2, 3}, {2, 4, 6}), JoinClass::kGeometric);
  EXPECT_EQ(ClassifyJoin({1, 2, 3}, {-1, -2, -3}), JoinClass::kNotSmooth);  // opposite
  EXPECT_EQ(ClassifyJoin({1, 0, 0}, {1, 0.001, 0}), JoinClass::kNotSmooth);
  EXPECT_EQ(ClassifyJoin({0, 0, 0}, {1, 0, 0}), JoinClass::kNotSmooth);
  const HermiteChain chain = MakeHermiteChain({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}},
                                              {{1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}},
                                              {{1, 0, 0}, {2, 2, 0}, {1, 0, 0}, {1, 0, 0}});
  ASSERT_EQ(chain.joins.size(), 2u);
  EXPECT_EQ(chain.joins[0], JoinClass::kGeometric);
  EXPECT_EQ(chain.joins[1], JoinClass::kNotSmooth);
  // Each segment leaves with the out vector and arrives with the in vector.
  EXPECT_EQ(chain.segments[1].g[2], (Point3{2, 2, 0}));
  EXPECT_EQ(chain.segments[1].g[3], (Point3{0, 1, 0}));
}

TEST(HermiteCurve, FixedStepperStaysWithinTheBound) {
  const Quantum q = Quantum::Parse("0.001");
  const Curve curves[] = {
      HermiteSegment({1, 1, 0}, {3, 1, 0}, {0, 1, 0}, {0, -1, 0}),
      HermiteSegment({-120.5, 33.25, 7}, {250, -80, 12.125}, {400, 300, -20}, {-50, 900, 3})};
  for (const Curve& c : curves) {
    for (int steps : {1, 7, 64, 1000, 65535}) {
      const PreparedCurve<3> prepared = PrepareFixedCurve(c, q, steps);
      double worst = 0;
      ForEachCurvePoint(prepared, [&](std::uint32_t i, const std::int32_t(&k)[3]) {
        const Point3 exact = EvaluateCurve(c, static_cast<double>(i) / steps);
        for (int a = 0; a < 3; ++a) worst = std::max(worst, std::fabs(k[a] - q.ToQuanta(exact[a])));
      });
      EXPECT_LE(worst, 0.51) << steps;
    }
  }
}

TEST(HermiteCurve, JsonChainsAndTheirErrors) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/hermite-chain.json");
  EXPECT_TRUE(set.patches.empty());
  ASSERT_EQ(set.curves.size(), 5u);
  EXPECT_EQ(set.curves[0].g[0], (Point3{1, 1, 0}));
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite-chain", "points": [[0,0]],
                                        "vectors": [[1,0]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].points: needs at least 2 points, got 1");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite-chain", "points": [[0,0],[1,0]],
                                        "vectors": [[1,0]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].vectors: needs one vector per point (2)");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"curves": [{"type": "hermite", "points": [[0,0],[1,0]],
                                        "vectors": [[1,0], [1, "x"]]}]})",
                        "c.json");
            }),
            "c.json: curves[0].vectors[1][1]: must be a number");
}

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

Curve BezierCurve(const std::array<Point3, 4>& p) {
  Curve c;
  c.basis = Basis::kBezier;
  c.g = p;
  return c;
}

PatchSet AsSet(const PolySurface& surface) {
  PatchSet set;
  AppendPatches(surface, 1, "test", &set.patches);
  return set;
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

// One-sided second-order difference of the patch along s (dir 0) or t at a
// boundary: forward from 0 or backward from 1.
Point3 Derivative(const Patch& p, double s, double t, int dir) {
  const double h = 1e-4;
  const double sign = (dir == 0 ? s : t) == 0 ? 1 : -1;
  const auto at = [&](double k) {
    return dir == 0 ? EvaluateReference(p, s + sign * k * h, t)
                    : EvaluateReference(p, s, t + sign * k * h);
  };
  Point3 d{};
  for (int c = 0; c < 3; ++c) d[c] = sign * (-3 * at(0)[c] + 4 * at(1)[c] - at(2)[c]) / (2 * h);
  return d;
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

// ---- Row 10: Bézier joins (seed 004) ----------------------------------------

// A flat Bézier patch on [x0, x0 + 3·w] × [0, 3] with control columns spaced
// by w, and z bumps on the inner points.
Patch FlatPatch(double x0, double w, double z_first_inner, double z_last_inner) {
  Patch p;
  p.basis = Basis::kBezier;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) p.g[i][j] = {x0 + w * i, static_cast<double>(j), 0};
  }
  for (int j = 0; j < 4; ++j) {
    p.g[1][j][2] = z_first_inner;
    p.g[2][j][2] = z_last_inner;
  }
  return p;
}

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

// ---- Rows 5, 6, 9: interpolation and families (seeds 001, 003) -------------

// The Lagrange cardinal function k on `nodes`, from its product formula.
double Cardinal(const std::vector<double>& nodes, std::size_t k, double x) {
  double value = 1;
  for (std::size_t m = 0; m < nodes.size(); ++m) {
    if (m != k) value *= (x - nodes[m]) / (nodes[k] - nodes[m]);
  }
  return value;
}

Point3 PointAt(int k, int l) { return {k + 0.3 * l, 0.5 * k * k - l, std::sin(k + 2.0 * l)}; }

TEST(LagrangeGrid, CardinalFunctionsAreDeltasAtTheNodesAndSumToOne) {
  const std::vector<double> nodes = {-1, 0.25, 0.5, 2};
  const std::vector<Poly> basis = LagrangeBasis(nodes);
  ASSERT_EQ(basis.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    for (std::size_t l = 0; l < 4; ++l) {
      const double x = (nodes[l] - nodes[0]) / (nodes[3] - nodes[0]);
      EXPECT_NEAR(EvaluatePoly(basis[k], x), k == l ? 1.0 : 0.0, 1e-13);
    }
  }
  for (double x : {0.0, 0.1, 0.37, 0.9, 1.0}) {
    double sum = 0;
    for (const Poly& b : basis) sum += EvaluatePoly(b, x);
    EXPECT_NEAR(sum, 1.0, 1e-13);
  }
  EXPECT_THROW(LagrangeBasis({0, 1, 1}), ConstructionError);
  EXPECT_THROW(LagrangeBasis({0}), ConstructionError);
}

TEST(LagrangeGrid, InterpolatesANonUniformGridExactlyAsOnePatch) {
  const std::vector<double> u = {0, 0.3, 1.7, 2};
  const std::vector<double> v = {1, 1.5, 4};
  std::vector<std::vector<Point3>> points(4);
  for (int k = 0; k < 4; ++k) {
    for (int l = 0; l < 3; ++l) points[k].push_back(PointAt(k, l));
  }
  const PatchSet set = AsSet(LagrangeGrid(u, v, points));
  ASSERT_EQ(set.patches.size(), 1u);
  const Patch& patch = set.patches[0];
  for (int k = 0; k < 4; ++k) {
    for (int l = 0; l < 3; ++l) {
      EXPECT_LT(Distance(EvaluateReference(patch, u[k] / 2, (v[l] - 1) / 3), points[k][l]), 1e-12);
    }
  }
  // Anywhere: r = Σ c_kl·r_kl with c_kl = L_k(u)·M_l(v), summing to 1.
  for (double s : {0.1, 0.6}) {
    for (double t : {0.2, 0.75}) {
      Point3 expected{};
      double sum = 0;
      for (int k = 0; k < 4; ++k) {
        for (int l = 0; l < 3; ++l) {
          const double c = Cardinal(u, k, 2 * s) * Cardinal(v, l, 1 + 3 * t);
          sum += c;
          for (int a = 0; a < 3; ++a) expected[a] += c * points[k][l][a];
        }
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_LT(Distance(EvaluateReference(patch, s, t), expected), 1e-12);
    }
  }
  EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
}

TEST(LagrangeGrid, HigherDegreesArePiecesWithinTheirBound) {
  const std::vector<double> u = {0, 0.2, 0.5, 0.6, 0.8, 1};  // degree 5
  const std::vector<double> v = {0, 0.5, 1};
  std::vector<std::vector<Point3>> points(6);
  for (int k = 0; k < 6; ++k) {
    for (int l = 0; l < 3; ++l) points[k].push_back(PointAt(k, l));
  }
  const double tolerance = 1e-6;
  PatchSet set;
  const double bound = AppendPatches(LagrangeGrid(u, v, points), tolerance, "t", &set.patches);
  EXPECT_GT(set.patches.size(), 1u);
  EXPECT_GT(bound, 0);
  EXPECT_LE(bound, tolerance);
  // The pieces tile [0,1]² in order: K_s rows of K_t pieces.
  const auto kt =
      static_cast<int>(std::count_if(set.patches.begin(), set.patches.end(), [](const Patch& p) {
        return p.origin.find("piece (0,") != std::string::npos;
      }));
  const int ks = static_cast<int>(set.patches.size()) / kt;
  double worst = 0;
  for (int a = 0; a < ks; ++a) {
    for (int b = 0; b < kt; ++b) {
      for (double x : {0.0, 0.3, 0.5, 0.8, 1.0}) {
        for (double y : {0.0, 0.4, 1.0}) {
          const double s = (a + x) / ks;
          const double t = (b + y) / kt;
          Point3 exact{};
          for (int k = 0; k < 6; ++k) {
            for (int l = 0; l < 3; ++l) {
              const double c = Cardinal(u, k, s) * Cardinal(v, l, t);
              for (int i = 0; i < 3; ++i) exact[i] += c * points[k][l][i];
            }
          }
          const Point3 got = EvaluateReference(set.patches[a * kt + b], x, y);
          for (int i = 0; i < 3; ++i) worst = std::max(worst, std::fabs(got[i] - exact[i]));
        }
      }
    }
  }
  EXPECT_LE(worst, bound + 1e-12);
  EXPECT_LE(WorstFixedError(set, 8, 8, Quantum::Parse("0.001")), 0.51);
}

// A family of cubic curves c_i(u), each a Bézier curve lifted by i.
std::vector<Curve> Family(int count) {
  std::vector<Curve> curves;
  for (int i = 0; i < count; ++i) {
    const double z = i * 1.5;
    const double y = std::sin(i);
    curves.push_back(BezierCurve(
        {{{0, y, z}, {1, y + 1, z + 0.5 * i}, {2, y - 1, z}, {3, y, z + 0.1 * i * i}}}));
  }
  return curves;
}

std::vector<VecPoly> Polys(const std::vector<Curve>& curves) {
  std::vector<VecPoly> p;
  for (const Curve& c : curves) p.push_back(CurvePolynomial(c));
  return p;
}

TEST(LagrangeFamily, EveryVLineIsTheLagrangeCurveThroughTheFamily) {
  const std::vector<double> v = {0, 1, 3, 4};  // non-uniform
  const std::vector<Curve> family = Family(4);
  const PatchSet set = AsSet(BlendCurves(Polys(family), LagrangeBasis(v)));
  ASSERT_EQ(set.patches.size(), 1u);
  for (double u : {0.0, 0.3, 1.0}) {
    for (int i = 0; i < 4; ++i) {
      EXPECT_LT(
          Distance(EvaluateReference(set.patches[0], u, v[i] / 4), EvaluateCurve(family[i], u)),
          1e-12);
    }
    for (double t : {0.1, 0.5, 0.9}) {
      Point3 expected{};
      for (int i = 0; i < 4; ++i) {
        const double w = Cardinal(v, i, 4 * t);
        const Point3 c = EvaluateCurve(family[i], u);
        for (int a = 0; a < 3; ++a) expected[a] += w * c[a];
      }
      EXPECT_LT(Distance(EvaluateReference(set.patches[0], u, t), expected), 1e-12);
    }
  }
  EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
}

TEST(BezierFamily, TheCurvesAreControlCurves) {
  for (int count : {2, 3, 4}) {
    const std::vector<Curve> family = Family(count);
    const PatchSet set = AsSet(BlendCurves(Polys(family), BernsteinBasis(count - 1)));
    ASSERT_EQ(set.patches.size(), 1u);
    for (double u : {0.0, 0.4, 1.0}) {
      EXPECT_LT(Distance(EvaluateReference(set.patches[0], u, 0), EvaluateCurve(family[0], u)),
                1e-12);
      EXPECT_LT(Distance(EvaluateReference(set.patches[0], u, 1), EvaluateCurve(family.back(), u)),
                1e-12);
      for (double t : {0.25, 0.6}) {
        // de Casteljau in v over the curves' points at u.
        std::vector<Point3> p;
        for (const Curve& c : family) p.push_back(EvaluateCurve(c, u));
        for (std::size_t level = p.size() - 1; level > 0; --level) {
          for (std::size_t i = 0; i < level; ++i) {
            for (int a = 0; a < 3; ++a) p[i][a] += t * (p[i + 1][a] - p[i][a]);
          }
        }
        EXPECT_LT(Distance(EvaluateReference(set.patches[0], u, t), p[0]), 1e-12);
      }
    }
  }
}

TEST(Families, RefuseTooFewCurvesAndMismatchedParameters) {
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "lagrange-curves", "curves": [
                {"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]}]}]})",
                        "f.json");
            }),
            "f.json: construct[0].curves: needs at least 2 curves, got 1");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "lagrange-curves", "v": [0, 0], "curves": [
                {"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]},
                {"basis": "bezier", "points": [[0,1],[1,1],[2,1],[3,1]]}]}]})",
                        "f.json");
            }),
            "f.json: construct[0]: nodes[1] = 0 is not greater than nodes[0] = 0 (parameters must "
            "increase)");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "bezier-curves", "curves": [
                {"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]},
                [{"basis": "bezier", "points": [[0,1],[1,1],[2,1],[3,1]]},
                 {"basis": "bezier", "points": [[3,1],[4,1],[5,1],[6,1]]}]]}]})",
                        "f.json");
            }),
            "f.json: construct[0].curves[1]: has 2 segments but curve 0 has 1 (the curves must "
            "have matching parameters)");
}

// ---- Row 7: Hermite surface over a family (seed 003, eq. 2.18) -------------

// c(u, v) = A(u) + v·B(u) + v²·C(u): a family on which the three-point
// derivative is exact, r_v = B + 2v·C.
Curve QuadraticFamilyCurve(double v) {
  std::array<Point3, 4> p{};
  for (int k = 0; k < 4; ++k) {
    const double a = k;
    p[k] = {a + 0.1 * v * v, v + 0.2 * k * v, 0.3 * k * k - 0.5 * v * v + k * v};
  }
  return BezierCurve(p);
}
Point3 QuadraticFamilyDerivative(double v, double u) {
  const double h = 1e-6;  // exact up to rounding: the family is quadratic in v
  const Point3 a = EvaluateCurve(QuadraticFamilyCurve(v + h), u);
  const Point3 b = EvaluateCurve(QuadraticFamilyCurve(v - h), u);
  return {(a[0] - b[0]) / (2 * h), (a[1] - b[1]) / (2 * h), (a[2] - b[2]) / (2 * h)};
}

TEST(HermiteFamily, InterpolatesTheCurvesWithThreePointDerivativesAndNaturalEnds) {
  const std::vector<double> v = {0, 0.5, 2, 2.5, 4};
  std::vector<Curve> family;
  for (double x : v) family.push_back(QuadraticFamilyCurve(x));
  const std::vector<VecPoly> curves = Polys(family);
  const std::vector<VecPoly> d = EstimateFamilyDerivatives(curves, v, false);
  const std::vector<PolySurface> pieces = HermiteFamily(curves, d, v, false);
  ASSERT_EQ(pieces.size(), 4u);
  for (double u : {0.0, 0.3, 0.7, 1.0}) {
    for (std::size_t i = 1; i + 1 < v.size(); ++i) {
      EXPECT_LT(Distance(EvaluatePoly(d[i], u), QuadraticFamilyDerivative(v[i], u)), 1e-6) << i;
    }
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const double delta = v[i + 1] - v[i];
      const Patch patch = AsSet(pieces[i]).patches[0];
      EXPECT_LT(Distance(EvaluateReference(patch, u, 0), EvaluateCurve(family[i], u)), 1e-12);
      EXPECT_LT(Distance(EvaluateReference(patch, u, 1), EvaluateCurve(family[i + 1], u)), 1e-12);
      // r_v = r_w / Δ at both ends is the estimated derivative: C¹ in v.
      const Point3 start = PolySurfaceDerivative(pieces[i], 0, 1, u, 0);
      const Point3 end = PolySurfaceDerivative(pieces[i], 0, 1, u, 1);
      const Point3 d0 = EvaluatePoly(d[i], u);
      const Point3 d1 = EvaluatePoly(d[i + 1], u);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(start[c] / delta, d0[c], 1e-9);
        EXPECT_NEAR(end[c] / delta, d1[c], 1e-9);
      }
    }
    // Natural ends: r_vv = 0 across the edge curves.
    const Point3 first = PolySurfaceDerivative(pieces.front(), 0, 2, u, 0);
    const Point3 last = PolySurfaceDerivative(pieces.back(), 0, 2, u, 1);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(first[c], 0, 1e-9);
      EXPECT_NEAR(last[c], 0, 1e-9);
    }
  }
}

TEST(HermiteFamily, ClosesInVWhenAskedAndInUWhenEveryCurveIsClosed) {
  const std::vector<double> v = {0, 1, 2.5, 3};  // 3 curves, closing at v = 3
  std::vector<Curve> family;
  for (int i = 0; i < 3; ++i) {
    const double z = i == 1 ? 1.0 : 0.0;
    // A closed cubic: its first and last control points coincide.
    family.push_back(BezierCurve(
        {{{3.0 + i, 0, z}, {4.0 + i, 3, z + 1}, {2.0 + i, 3, z - 1}, {3.0 + i, 0, z}}}));
  }
  const std::vector<VecPoly> curves = Polys(family);
  const std::vector<VecPoly> d = EstimateFamilyDerivatives(curves, v, true);
  const std::vector<PolySurface> pieces = HermiteFamily(curves, d, v, true);
  ASSERT_EQ(pieces.size(), 3u);
  for (double u : {0.0, 0.4, 1.0}) {
    // The last piece returns to curve 0, with the same v-derivative.
    EXPECT_LT(Distance(EvaluatePolySurface(pieces[2], u, 1), EvaluateCurve(family[0], u)), 1e-12);
    const Point3 out = PolySurfaceDerivative(pieces[0], 0, 1, u, 0);
    const Point3 back = PolySurfaceDerivative(pieces[2], 0, 1, u, 1);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[c] / (v[1] - v[0]), back[c] / (v[3] - v[2]), 1e-9);
    // Curve 0's derivative uses curve 2 at v = 0 − (3 − 2.5) as its left neighbour.
    const Point3 c2 = EvaluateCurve(family[2], u);
    const Point3 c0 = EvaluateCurve(family[0], u);
    const Point3 c1 = EvaluateCurve(family[1], u);
    const double vp = -0.5;
    const double vq = 1;
    const Point3 expected{
        c2[0] * (0 - vq) / ((vp - 0) * (vp - vq)) + c0[0] * (-vp - vq) / ((0 - vp) * (0 - vq)) +
            c1[0] * (0 - vp) / ((vq - vp) * (vq - 0)),
        c2[1] * (0 - vq) / ((vp - 0) * (vp - vq)) + c0[1] * (-vp - vq) / ((0 - vp) * (0 - vq)) +
            c1[1] * (0 - vp) / ((vq - vp) * (vq - 0)),
        c2[2] * (0 - vq) / ((vp - 0) * (vp - vq)) + c0[2] * (-vp - vq) / ((0 - vp) * (0 - vq)) +
            c1[2] * (0 - vp) / ((vq - vp) * (vq - 0))};
    EXPECT_LT(Distance(EvaluatePoly(d[0], u), expected), 1e-12);
  }
  // Every curve is closed, so is every v-line of the surface: r(0,v) = r(1,v).
  for (const PolySurface& piece : pieces) {
    for (double t : {0.0, 0.3, 0.8}) {
      EXPECT_LT(Distance(EvaluatePolySurface(piece, 0, t), EvaluatePolySurface(piece, 1, t)),
                1e-12);
    }
  }
  EXPECT_THROW(EstimateFamilyDerivatives({curves[0], curves[1]}, {0, 1, 2}, true),
               ConstructionError);
  EXPECT_THROW(EstimateFamilyDerivatives(curves, {0, 1, 1, 3}, true), ConstructionError);
}

TEST(HermiteFamily, JsonNotesAndRefusals) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/hermite-family.json");
  bool cyclic = false;
  for (const std::string& note : set.notes) {
    cyclic = cyclic ||
             note.find("cyclic in u (every curve is closed), cyclic in v") != std::string::npos;
  }
  EXPECT_TRUE(cyclic);
  EXPECT_LE(WorstFixedError(set, 16, 16, Quantum::Parse("0.001")), 0.51);
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "hermite-curves", "v": [0, 2, 1], "curves": [
                {"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]},
                {"basis": "bezier", "points": [[0,1],[1,1],[2,1],[3,1]]},
                {"basis": "bezier", "points": [[0,2],[1,2],[2,2],[3,2]]}]}]})",
                        "h.json");
            }),
            "h.json: construct[0]: v[2] = 1 is not greater than v[1] = 2 (parameters must "
            "increase)");
}

// ---- Row 8: transition surface (seed 003, eq. 2.19) ------------------------

TEST(Transition, MatchesBothEdgesInPositionAndTangentDirection) {
  Patch a = FlatPatch(0, 1, 0.5, 0.2);
  Patch b = FlatPatch(0, 1.2, -0.3, 0.1);
  for (auto& row : b.g) {
    for (Point3& p : row) {
      p[1] += 5;  // b lies beyond a's edge t = 1 (y = 3)
      p[2] += 1;
    }
  }
  const Transition t = TransitionSurface(a, b);
  const Patch patch = AsSet(t.surface).patches[0];
  // The scale factors, computed again with a fine midpoint mean.
  const int n = 4000;
  double distance = 0;
  double length_a = 0;
  double length_b = 0;
  for (int k = 0; k < n; ++k) {
    const double u = (k + 0.5) / n;
    distance += Distance(EvaluateReference(a, u, 1), EvaluateReference(b, u, 0));
    length_a += Distance(EvaluateReference(a, u, 1), EvaluateReference(a, u, 1 - 1e-6)) / 1e-6;
    length_b += Distance(EvaluateReference(b, u, 1e-6), EvaluateReference(b, u, 0)) / 1e-6;
  }
  EXPECT_NEAR(t.k_a, distance / length_a, 1e-4 * t.k_a);
  EXPECT_NEAR(t.k_b, distance / length_b, 1e-4 * t.k_b);
  for (double u : {0.0, 0.25, 0.5, 1.0}) {
    EXPECT_LT(Distance(EvaluateReference(patch, u, 0), EvaluateReference(a, u, 1)), 1e-12);
    EXPECT_LT(Distance(EvaluateReference(patch, u, 1), EvaluateReference(b, u, 0)), 1e-12);
    // Tangent directions across the edges: r_w ∥ a_v, r_w ∥ b_v, same sense.
    const Point3 rw0 = Derivative(patch, u, 0, 1);
    const Point3 av = Derivative(a, u, 1, 1);
    const Point3 rw1 = Derivative(patch, u, 1, 1);
    const Point3 bv = Derivative(b, u, 0, 1);
    const auto cosine = [](const Point3& x, const Point3& y) {
      return (x[0] * y[0] + x[1] * y[1] + x[2] * y[2]) /
             (std::hypot(x[0], x[1], x[2]) * std::hypot(y[0], y[1], y[2]));
    };
    EXPECT_NEAR(cosine(rw0, av), 1, 1e-9);
    EXPECT_NEAR(cosine(rw1, bv), 1, 1e-9);
    EXPECT_NEAR(std::hypot(rw0[0], rw0[1], rw0[2]), t.k_a * std::hypot(av[0], av[1], av[2]), 1e-5);
  }
  PatchSet set;
  set.patches = {patch};
  EXPECT_LE(WorstFixedError(set, 33, 17, Quantum::Parse("0.001")), 0.51);
  // Edges that coincide give zero scale factors: refused unless given.
  Patch touching = a;
  for (auto& row : touching.g) {
    for (Point3& p : row) p[1] += 3;  // its edge t = 0 is a's edge t = 1
  }
  EXPECT_THROW(TransitionSurface(a, touching), ConstructionError);
  EXPECT_NO_THROW(TransitionSurface(a, touching, 1, 1));
}

// ---- Row 12: quadric Hermite interpolation on a triangulation (seed 000) ----

// The seed's functions for the two triangles, as reconstructed in
// examples/quadric-hermite.json.
double Phi(const Point3& p, double a) {
  const double x = p[0];
  const double y = p[1];
  const double z = p[2];
  return x * x + y * y - 2 + (z - 1) * (a * (z - 1) - y - 1);
}
double Psi(const Point3& p, double a3) {
  const double x = p[0];
  const double y = p[1];
  const double z = p[2];
  return 3 * (x * x + y * y - 2) + (z - 1) * (a3 * (z - 1) - 3 * x - 3);
}

const std::vector<Point3> kSeedVertices = {{1, 1, 1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}};
const std::vector<Point3> kSeedNormals = {{1, 1, -1}, {1, 1, 0}, {1, -1, 0}, {-3, 3, 0}};

TEST(QuadricHermite, ReproducesTheSeedsFunctionsWithTheFreeParameter) {
  const QuadricSolution first =
      SolveQuadricTriangle({kSeedVertices[0], kSeedVertices[1], kSeedVertices[2]},
                           {kSeedNormals[0], kSeedNormals[1], kSeedNormals[2]});
  const QuadricSolution second =
      SolveQuadricTriangle({kSeedVertices[3], kSeedVertices[0], kSeedVertices[1]},
                           {kSeedNormals[3], kSeedNormals[0], kSeedNormals[1]});
  // Condition (3) fails (the vertices share z): the system leaves a33 free.
  ASSERT_EQ(first.rank, 7);
  ASSERT_EQ(first.free_unknowns, std::vector<int>{2});
  EXPECT_STREQ(kQuadricUnknowns[first.free_unknowns[0]], "a33");
  ASSERT_EQ(second.free_unknowns, std::vector<int>{2});
  for (double a : {-0.125, 0.0, 1.0}) {
    const Quadric f = first.With({a});
    const Quadric g = second.With({3 * a});
    for (const Point3& x : {Point3{0.3, -0.2, 0.7}, Point3{2, 1, -3}, Point3{-1.5, 0.5, 2}}) {
      EXPECT_NEAR(f.Value(x), Phi(x, a), 1e-12);
      EXPECT_NEAR(g.Value(x), Psi(x, 3 * a), 1e-12);
    }
  }
}

TEST(QuadricHermite, SolutionsPassThroughTheVerticesWithTheNormals) {
  // Points and normals of an ellipsoid x²/4 + y² + z²/9 = 1 in general position.
  const auto point = [](double u, double v) {
    return Point3{2 * std::cos(u) * std::cos(v), std::sin(u) * std::cos(v), 3 * std::sin(v)};
  };
  const std::array<Point3, 3> p = {point(0.3, 0.2), point(1.1, -0.4), point(2.0, 0.7)};
  std::array<Point3, 3> n{};
  for (int i = 0; i < 3; ++i) n[i] = {p[i][0] / 4, p[i][1], p[i][2] / 9};
  n[1] = {n[1][0] * 5, n[1][1] * 5, n[1][2] * 5};  // lengths other than the first do not matter
  const QuadricSolution solution = SolveQuadricTriangle(p, n);
  // Never unique: with L the plane of the triangle, F + μ·L² has the same
  // values and normals at the vertices (L = 0 there), so one unknown stays
  // free and the family is exactly that.
  EXPECT_EQ(solution.rank, 7);
  ASSERT_EQ(solution.free_unknowns.size(), 1u);
  const Quadric f = solution.With({0.7});
  const Quadric f2 = solution.With({-1.3});
  const Point3 e1{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
  const Point3 e2{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
  const Point3 normal{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                      e1[0] * e2[1] - e1[1] * e2[0]};
  double ratio = 0;
  for (const Point3& x : {Point3{0.3, -0.2, 0.7}, Point3{2, 1, -3}, Point3{-1.5, 0.5, 2}}) {
    const double l =
        normal[0] * (x[0] - p[0][0]) + normal[1] * (x[1] - p[0][1]) + normal[2] * (x[2] - p[0][2]);
    const double r = (f.Value(x) - f2.Value(x)) / (l * l);
    if (ratio != 0) {
      EXPECT_NEAR(r, ratio, 1e-9 * std::fabs(ratio));
    }
    ratio = r;
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f.Value(p[i]), 0, 1e-12);
    const Point3 g = f.Gradient(p[i]);
    const double sine = std::hypot(g[1] * n[i][2] - g[2] * n[i][1], g[2] * n[i][0] - g[0] * n[i][2],
                                   g[0] * n[i][1] - g[1] * n[i][0]) /
                        (std::hypot(g[0], g[1], g[2]) * std::hypot(n[i][0], n[i][1], n[i][2]));
    EXPECT_LT(sine, 1e-10) << i;
  }
  // ∇F at the first vertex is 2·A1 (the seed's form).
  const Point3 g0 = f.Gradient(p[0]);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(g0[c], 2 * n[0][c], 1e-12);
}

TEST(QuadricHermite, GluesAlongThePlaneXEqualsYAndReportsAContinuousJoin) {
  for (double a : {-0.125, 0.0, 1.0}) {
    QuadricMesh mesh;
    mesh.vertices = kSeedVertices;
    mesh.normals = kSeedNormals;
    mesh.triangles = {{0, 1, 2}, {3, 0, 1}};
    mesh.free = {{a}, {3 * a}};
    const double tolerance = 0.02;
    const QuadricResult r = BuildQuadricMesh(mesh, tolerance, "q");
    ASSERT_EQ(r.glues.size(), 1u);
    const QuadricGlue& glue = r.glues[0];
    EXPECT_TRUE(glue.conics_coincide);
    // The plane through the shared vertices (1,1,1), (−1,−1,1) and the common
    // point on the z axis: x = y.
    EXPECT_NEAR(std::fabs(glue.plane_normal[0]), std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(glue.plane_normal[0], -glue.plane_normal[1], 1e-12);
    EXPECT_NEAR(glue.plane_normal[2], 0, 1e-12);
    // On x = y the two functions agree (φ − ψ/3 = (z − 1)(x − y)), so the
    // join is continuous, but the normals differ: only C0, as the seed finds.
    EXPECT_LT(glue.gap, 1e-12);
    EXPECT_GT(glue.worst_normal_angle_deg, 1);
    for (const Point3& x : {Point3{0.5, 0.5, -2}, Point3{-0.3, -0.3, 0.4}}) {
      EXPECT_NEAR(Phi(x, a), Psi(x, 3 * a) / 3, 1e-12);
    }
    // Every patch corner lies on its piece's quadric; every patch centre
    // within (to first order) the tolerance of it.
    EXPECT_LE(r.tessellation_error, tolerance);
    for (const Patch& patch : r.patches) {
      const bool second = patch.origin.find("triangle 1") != std::string::npos;
      const auto f = [&](const Point3& x) { return second ? Psi(x, 3 * a) / 3 : Phi(x, a); };
      const auto distance = [&](const Point3& x) {
        const double h = 1e-6;
        Point3 g{};
        for (int c = 0; c < 3; ++c) {
          Point3 xp = x;
          Point3 xm = x;
          xp[c] += h;
          xm[c] -= h;
          g[c] = (f(xp) - f(xm)) / (2 * h);
        }
        return std::fabs(f(x)) / std::hypot(g[0], g[1], g[2]);
      };
      EXPECT_LT(distance(EvaluateReference(patch, 0, 0)), 1e-9) << patch.origin;
      EXPECT_LT(distance(EvaluateReference(patch, 0.5, 0.5)), 1.5 * tolerance) << patch.origin;
    }
  }
}

TEST(QuadricHermite, RefusesBadTriangulations) {
  const auto error_of = [](QuadricMesh mesh) {
    try {
      BuildQuadricMesh(mesh, 0.02, "q");
    } catch (const ConstructionError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  QuadricMesh mesh;
  mesh.vertices = kSeedVertices;
  mesh.normals = kSeedNormals;
  mesh.triangles = {{0, 1, 2}, {3, 0, 1}};
  QuadricMesh zero = mesh;
  zero.normals[2] = {0, 0, 0};
  EXPECT_EQ(error_of(zero), "normals[2] has zero length");
  QuadricMesh flat = mesh;
  flat.vertices.push_back({0, 0, 1});  // on the segment from vertex 0 to vertex 1
  flat.normals.push_back({0, 0, 1});
  flat.triangles = {{0, 1, 4}};
  EXPECT_EQ(error_of(flat), "triangles[0]: the triangle is degenerate: its vertices are collinear");
  QuadricMesh missing = mesh;
  missing.triangles = {{0, 1, 7}};
  EXPECT_EQ(error_of(missing), "triangles[0]: vertex 7 does not exist");
  QuadricMesh wrong_free = mesh;
  wrong_free.free = {{1, 2}, {0}};
  EXPECT_EQ(error_of(wrong_free),
            "triangles[0]: the system leaves 1 free parameter(s), but \"free\" gives 2");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "quadric-hermite",
                "vertices": [[0,0,0],[1,0,0],[0,1,0]], "normals": [[0,0,1],[0,0,1],[0,0,0]],
                "triangles": [[0,1,2]]}]})",
                        "q.json");
            }),
            "q.json: construct[0]: normals[2] has zero length");
}

// ---- The command-line tool on the examples ----------------------------------

struct ToolRun {
  int exit_code = -1;
  std::string out;
};

ToolRun RunTool(const std::string& args) {
  ToolRun r;
  const std::string command = std::string(FDSURF_BINARY) + " " + args + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) r.out.append(buffer, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(ConstructionCli, SamplesCurvesWithTheFixedEngine) {
  const ToolRun r = RunTool("sample " FDSURF_EXAMPLES_DIR "/hermite-chain.json --grid 4");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out.substr(0, 14), "curve,i,x,y,z\n");
  // x(1/2) = 1 + 6/4 − 4/8 = 2, y(1/2) = 1 + 1/2 − 1/4 = 1.25.
  EXPECT_NE(r.out.find("\n0,2,2.000,1.250,0.000\n"), std::string::npos) << r.out;
  const ToolRun check = RunTool("check " FDSURF_EXAMPLES_DIR "/hermite-chain.json --grid 100");
  EXPECT_EQ(check.exit_code, 0);
  EXPECT_NE(check.out.find("join 1 at (3, 1, 0): parametrically smooth (C1)"), std::string::npos);
  EXPECT_NE(check.out.find("curves: max error"), std::string::npos);
}

TEST(ConstructionCli, JoinsOnTheTeapotAndRefusedInput) {
  const ToolRun r = RunTool("joins " FDSURF_EXAMPLES_DIR "/teapot.bpt");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("52 shared edges in 32 patches: 46 C1, 6 G1, 0 C0, 0 degenerate"),
            std::string::npos)
      << r.out;
  const char* bad = "/tmp/fdsurf_construction_test_bad.json";
  FILE* f = std::fopen(bad, "w");
  ASSERT_NE(f, nullptr);
  std::fputs(R"({"construct": [{"type": "lagrange-curves", "curves": []}]})", f);
  std::fclose(f);
  const ToolRun refused = RunTool(std::string("sample ") + bad + " --grid 4");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_TRUE(refused.out.empty());
  std::remove(bad);
}

}  // namespace
}  // namespace fdsurf::host
