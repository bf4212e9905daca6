// SPDX-License-Identifier: MIT
// The double-precision reference: against exact rational values, and the
// defining properties of each basis.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "exact_reference.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {
namespace {

const Basis kAllBases[] = {Basis::kPower, Basis::kHermite, Basis::kBezier, Basis::kBSpline,
                           Basis::kCatmullRom};

Patch RandomIntegerPatch(std::mt19937_64& rng, Basis basis, std::int64_t range,
                         std::int64_t (&g)[3][4][4]) {
  std::uniform_int_distribution<std::int64_t> dist(-range, range);
  Patch patch;
  patch.basis = basis;
  patch.origin = "random";
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        g[c][i][j] = dist(rng);
        patch.g[i][j][c] = static_cast<double>(g[c][i][j]);
      }
    }
  }
  return patch;
}

TEST(Reference, WithinOneBillionthOfTheExactValue) {
  std::mt19937_64 rng(23);
  for (Basis basis : kAllBases) {
    for (int trial = 0; trial < 20; ++trial) {
      std::int64_t g[3][4][4];
      const std::int64_t range = std::int64_t{1} << 30;
      const Patch patch = RandomIntegerPatch(rng, basis, range, g);
      const int n = 1 + static_cast<int>(rng() % 300);
      const int m = 1 + static_cast<int>(rng() % 300);
      for (int i = 0; i <= n; i += 1 + n / 17) {
        for (int j = 0; j <= m; j += 1 + m / 13) {
          const Point3 p =
              EvaluateReference(patch, static_cast<double>(i) / n, static_cast<double>(j) / m);
          for (int c = 0; c < 3; ++c) {
            const double exact = testing::ToDouble(
                testing::ExactPatchPoint(static_cast<int>(basis), g[c], i, n, j, m));
            // Relative to the size of the geometry: what 1e-9 relative means
            // for a point that may itself be near zero.
            ASSERT_LE(std::fabs(p[c] - exact), 1e-9 * static_cast<double>(range))
                << BasisName(basis) << " (" << i << "/" << n << "," << j << "/" << m << ")";
          }
        }
      }
    }
  }
}

TEST(Reference, HornerAndDeCasteljauAgreeWithTheDirectForm) {
  std::mt19937_64 rng(29);
  std::int64_t g[3][4][4];
  const Patch patch = RandomIntegerPatch(rng, Basis::kBezier, 1000, g);
  const PowerCoefficients coefficients = CoefficientsOf(patch);
  for (double s : {0.0, 0.1, 0.5, 0.77, 1.0}) {
    for (double t : {0.0, 0.3, 0.9, 1.0}) {
      const Point3 a = EvaluateDeCasteljau(patch, s, t);
      const Point3 b = EvaluateHorner(coefficients, s, t);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-9);
    }
  }
}

TEST(Bases, BlendingFunctionsSumToOne) {
  // Every point of the geometry at (1,1,1) (Hermite: tangents and twists 0)
  // gives the surface (1,1,1) everywhere exactly when Σ b_i(u) = 1.
  for (Basis basis : {Basis::kHermite, Basis::kBezier, Basis::kBSpline, Basis::kCatmullRom}) {
    Patch patch;
    patch.basis = basis;
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        const bool tangent = basis == Basis::kHermite && (i >= 2 || j >= 2);
        patch.g[i][j] = tangent ? Point3{0, 0, 0} : Point3{1, 1, 1};
      }
    }
    for (double s = 0; s <= 1.0; s += 0.125) {
      for (double t = 0; t <= 1.0; t += 0.125) {
        const Point3 p = EvaluateReference(patch, s, t);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], 1.0, 1e-14) << BasisName(basis);
      }
    }
  }
  // And in the engine's integer tables: d·M has row sums (0, 0, 0, d).
  for (Basis basis : kAllBases) {
    if (basis == Basis::kPower || basis == Basis::kHermite) continue;
    const BasisMatrix* m = GetBasisMatrix(basis);
    for (int r = 0; r < 4; ++r) {
      int sum = 0;
      for (int c = 0; c < 4; ++c) sum += m->matrix[r][c];
      EXPECT_EQ(sum, r == 3 ? m->denominator : 0) << BasisName(basis) << " row " << r;
    }
  }
}

Patch RandomDoublePatch(std::mt19937_64& rng, Basis basis) {
  std::uniform_real_distribution<double> dist(-100, 100);
  Patch patch;
  patch.basis = basis;
  patch.origin = "random";
  for (auto& row : patch.g) {
    for (auto& p : row) p = {dist(rng), dist(rng), dist(rng)};
  }
  return patch;
}

// Evaluates the fixed engine at (i/n, j/m) in file units.
Point3 FixedAt(const PreparedPatch<3>& prepared, const Quantum& q, std::uint32_t i,
               std::uint32_t j) {
  Point3 result{};
  ForEachGridPoint(prepared, [&](std::uint32_t a, std::uint32_t b, const std::int32_t(&k)[3]) {
    if (a == i && b == j) {
      for (int c = 0; c < 3; ++c) result[c] = k[c] * q.value();
    }
  });
  return result;
}

TEST(Bases, CatmullRomAndHermiteInterpolateTheirPoints) {
  std::mt19937_64 rng(31);
  const Quantum q = Quantum::Parse("0.001");
  const double tolerance = 0.51 * q.value() + 1e-12;
  for (int trial = 0; trial < 10; ++trial) {
    const Patch cr = RandomDoublePatch(rng, Basis::kCatmullRom);
    const Patch hermite = RandomDoublePatch(rng, Basis::kHermite);
    const PreparedPatch<3> cr_fixed = PrepareFixedPatch(cr, q, 5, 7);
    const PreparedPatch<3> hermite_fixed = PrepareFixedPatch(hermite, q, 5, 7);
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        // Catmull-Rom passes through the inner points net[1..2][1..2].
        const Point3 want_cr = cr.g[1 + a][1 + b];
        const Point3 got_cr = EvaluateReference(cr, a, b);
        const Point3 fixed_cr = FixedAt(cr_fixed, q, 5 * a, 7 * b);
        // Hermite passes through P00, P01, P10, P11 = g[0..1][0..1].
        const Point3 want_h = hermite.g[a][b];
        const Point3 got_h = EvaluateReference(hermite, a, b);
        const Point3 fixed_h = FixedAt(hermite_fixed, q, 5 * a, 7 * b);
        for (int c = 0; c < 3; ++c) {
          EXPECT_NEAR(got_cr[c], want_cr[c], 1e-12);
          EXPECT_NEAR(fixed_cr[c], want_cr[c], tolerance);
          EXPECT_NEAR(got_h[c], want_h[c], 1e-12);
          EXPECT_NEAR(fixed_h[c], want_h[c], tolerance);
        }
      }
    }
    // Hermite's s-derivative at the corner (0,0) is Ps00 = g[2][0], its
    // t-derivative Pt00 = g[0][2] (central differences on the reference).
    const double h = 1e-5;
    const Point3 ps1 = EvaluateReference(hermite, h, 0);
    const Point3 ps0 = EvaluateReference(hermite, -h, 0);
    const Point3 pt1 = EvaluateReference(hermite, 0, h);
    const Point3 pt0 = EvaluateReference(hermite, 0, -h);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR((ps1[c] - ps0[c]) / (2 * h), hermite.g[2][0][c], 1e-5);
      EXPECT_NEAR((pt1[c] - pt0[c]) / (2 * h), hermite.g[0][2][c], 1e-5);
    }
  }
}

TEST(Bases, BezierAndBSplineReproducePlanes) {
  // A net on a plane with uniform spacing, P_ij = O + i·U + j·V: both bases
  // have linear precision, so the surface is O + (i0 + 3s)·U + (j0 + 3t)·V
  // (Bézier, knots at thirds) or O + (1 + s)·U + (1 + t)·V (B-spline).
  const Point3 o{3, -2, 5};
  const Point3 u{1.5, 0.25, -0.75};
  const Point3 v{-0.5, 2, 0.125};
  const Quantum q = Quantum::Parse("0.0001");
  for (Basis basis : {Basis::kBezier, Basis::kBSpline}) {
    Patch patch;
    patch.basis = basis;
    patch.origin = "plane";
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        for (int c = 0; c < 3; ++c) patch.g[i][j][c] = o[c] + i * u[c] + j * v[c];
      }
    }
    const int n = 9;
    const int m = 10;
    const PreparedPatch<3> prepared = PrepareFixedPatch(patch, q, n, m);
    ForEachGridPoint(prepared, [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      const double s = static_cast<double>(i) / n;
      const double t = static_cast<double>(j) / m;
      const double a = basis == Basis::kBezier ? 3 * s : 1 + s;
      const double b = basis == Basis::kBezier ? 3 * t : 1 + t;
      const Point3 ref = EvaluateReference(patch, s, t);
      for (int c = 0; c < 3; ++c) {
        const double plane = o[c] + a * u[c] + b * v[c];
        EXPECT_NEAR(ref[c], plane, 1e-12);
        EXPECT_NEAR(k[c] * q.value(), plane, 0.51 * q.value() + 1e-12);
      }
    });
  }
}

}  // namespace
}  // namespace fdsurf::host
