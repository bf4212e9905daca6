// SPDX-License-Identifier: MIT
// Rows 5-9 of docs/constructions.md: Lagrange interpolation, surfaces over
// families of curves (Lagrange, Bézier, Hermite) and the transition surface
// (seeds 001, 003).
#include <gtest/gtest.h>

#include "construction_test_support.h"

namespace fdsurf::host {
namespace {

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

}  // namespace
}  // namespace fdsurf::host
