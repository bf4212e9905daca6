// SPDX-License-Identifier: MIT
// Circular arcs and their affine images as standard circle cubics
// (CircleArcToCubics, docs/formats.md "Circular and elliptical arcs"). The
// references are independent of the code under test: the cubics are
// evaluated in long double from their control points and measured against
// the exact circle (|p| = 1) and, for an ellipse, against its own
// parametric form minimised by dense sampling and refinement.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "fdsurf/host/conic_arc.h"
#include "fdsurf/host/errors.h"

namespace fdsurf::host {
namespace {

using Real = long double;
constexpr Real kPi = std::numbers::pi_v<long double>;

struct RealPoint {
  Real x;
  Real y;
};

RealPoint CubicAt(const std::array<PlanePoint, 4>& b, Real t) {
  const Real u = 1 - t;
  const Real w[4] = {u * u * u, 3 * u * u * t, 3 * u * t * t, t * t * t};
  RealPoint p{0, 0};
  for (std::size_t i = 0; i < 4; ++i) {
    p.x += w[i] * b[i][0];
    p.y += w[i] * b[i][1];
  }
  return p;
}

// The angle of p measured from `from` in the direction of the sweep, in
// (−π, π]: 0 at the piece's start, |sweep| at its end when p is inside it.
Real AngleAlong(const RealPoint& p, Real from, Real sweep) {
  Real d = std::atan2(p.y, p.x) - from;
  while (d > kPi) d -= 2 * kPi;
  while (d <= -kPi) d += 2 * kPi;
  return sweep > 0 ? d : -d;
}

struct Sampled {
  Real worst_radial = 0;  // the largest | |c(t)| − 1 |
  bool in_sector = true;  // every sample's angle within the piece
  bool monotone = true;   // the angle never turns back
};

// 4001 samples of one cubic of the unit-circle arc from `from` over `sweep`.
Sampled SampleUnitPiece(const std::array<PlanePoint, 4>& b, Real from, Real sweep) {
  Sampled s;
  Real previous = 0;
  constexpr int kSamples = 4000;
  for (int i = 0; i <= kSamples; ++i) {
    const RealPoint p = CubicAt(b, static_cast<Real>(i) / kSamples);
    s.worst_radial = std::max(s.worst_radial, std::fabs(std::hypot(p.x, p.y) - 1));
    const Real angle = AngleAlong(p, from, sweep);
    // A few ulps of slack at the ends, where the cubic meets the circle.
    s.in_sector = s.in_sector && angle >= -1e-15L && angle <= std::fabs(sweep) + 1e-15L;
    s.monotone = s.monotone && angle >= previous - 1e-15L;
    previous = angle;
  }
  return s;
}

// The distance from x to the image under `map` of the unit-circle arc from
// `start` over `sweep`: dense samples of the angle, then a ternary search
// about the best one (the distance is unimodal that close to its minimum).
template <typename Map>
Real DistanceToArc(const RealPoint& x, const Map& map, Real start, Real sweep) {
  const auto distance = [&](Real theta) {
    const RealPoint e = map(std::cos(theta), std::sin(theta));
    return std::hypot(e.x - x.x, e.y - x.y);
  };
  constexpr int kSamples = 4000;
  Real best = start;
  for (int j = 0; j <= kSamples; ++j) {
    const Real theta = start + sweep * j / kSamples;
    if (distance(theta) < distance(best)) best = theta;
  }
  const Real step = std::fabs(sweep) / kSamples;
  Real lo = std::max(std::min(start, start + sweep), best - step);
  Real hi = std::min(std::max(start, start + sweep), best + step);
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Real m1 = lo + (hi - lo) / 3;
    const Real m2 = hi - (hi - lo) / 3;
    if (distance(m1) < distance(m2)) {
      hi = m2;
    } else {
      lo = m1;
    }
  }
  return distance((lo + hi) / 2);
}

TEST(CircleArc, TheBoundHoldsAndIsTightOnTheUnitCircle) {
  for (const double sweep : {kPi / 2, 1.0L, -0.7L, 0.3L, -kPi / 2}) {
    for (const double start : {0.0, 2.5, -1.0}) {
      const CircleArcCubics arc = CircleArcToCubics(start, sweep, 1, 1);
      ASSERT_EQ(arc.cubics.size(), 1u);
      const double bound = arc.unit_bound;
      const Sampled s = SampleUnitPiece(arc.cubics[0], start, sweep);
      // Rounding of the control points (a few ε) is the caller's margin.
      EXPECT_LE(s.worst_radial, bound + 1e-15) << "sweep " << sweep << " start " << start;
      // Tight: the sampled error is nearly the bound, so a bound half as
      // large would fail the line above.
      EXPECT_GE(s.worst_radial, 0.99 * bound) << "sweep " << sweep;
      // Inside the piece's sector, turning one way: each cubic point's
      // nearest circle point is on the piece, and every point of the piece
      // is reached (so the bound is the Hausdorff distance).
      EXPECT_TRUE(s.in_sector) << "sweep " << sweep << " start " << start;
      EXPECT_TRUE(s.monotone) << "sweep " << sweep << " start " << start;
    }
  }
  // The known figure: 2.7e-4 of the radius at 90°.
  EXPECT_NEAR(CircleCubicBound(kPi / 2), 2.725e-4, 1e-6);
}

TEST(CircleArc, FewestPiecesWithinTheTolerance) {
  // A 180° arc of radius 10 at 1e-6: 8 pieces (the Hermite cubic of a
  // rational quadratic took 64), and 7 would not do.
  const CircleArcCubics half = CircleArcToCubics(0, -kPi, 10, 1e-6);
  ASSERT_EQ(half.cubics.size(), 8u);
  EXPECT_LE(10 * half.unit_bound, 1e-6);
  EXPECT_GT(10 * CircleCubicBound(kPi / 7), 1e-6);
  // Pieces join bit for bit and run from the start to the end.
  for (std::size_t k = 1; k < half.cubics.size(); ++k) {
    EXPECT_EQ(half.cubics[k][0], half.cubics[k - 1][3]);
  }
  EXPECT_EQ(half.cubics.front()[0], (PlanePoint{1, 0}));
  EXPECT_NEAR(half.cubics.back()[3][0], -1, 1e-15);
  EXPECT_NEAR(half.cubics.back()[3][1], 0, 1e-15);
  // A coarse tolerance still keeps the pieces within 90°.
  EXPECT_EQ(CircleArcToCubics(0, 2 * kPi, 1, 1).cubics.size(), 4u);
  // Three turns, each piece checked against the circle.
  const double sweep = 6 * kPi;
  const CircleArcCubics turns = CircleArcToCubics(0.5, sweep, 3, 1e-7);
  const double n = static_cast<double>(turns.cubics.size());
  for (std::size_t k = 0; k < turns.cubics.size(); ++k) {
    // The piece's own end angles (the ones it was made from, up to the
    // rounding of cos and sin).
    const std::array<PlanePoint, 4>& b = turns.cubics[k];
    const Real from = std::atan2(static_cast<Real>(b[0][1]), static_cast<Real>(b[0][0]));
    const Real piece = AngleAlong(RealPoint{b[3][0], b[3][1]}, from, 1);
    EXPECT_NEAR(static_cast<double>(piece), sweep / n, 1e-12);
    const Sampled s = SampleUnitPiece(b, from, piece);
    EXPECT_LE(3 * s.worst_radial, 1e-7 + 1e-14) << "piece " << k;
    EXPECT_TRUE(s.in_sector && s.monotone) << "piece " << k;
  }
}

TEST(CircleArc, EllipsesWithinTheLargestStretch) {
  // An ellipse as an SVG reader makes it: a rotated, skewed, translated
  // image of the unit circle (x = a·u + c·v + 30, y = b·u + d·v − 5).
  const double a = 36.2;
  const double b = 17.0;
  const double c = 3.1;
  const double d = 7.5;
  const auto map = [&](Real u, Real v) { return RealPoint{a * u + c * v + 30, b * u + d * v - 5}; };
  // The largest singular value: sqrt of the largest eigenvalue of MᵀM.
  const Real p = a * a + b * b;
  const Real q = a * c + b * d;
  const Real r = c * c + d * d;
  const Real stretch = std::sqrt((p + r) / 2 + std::sqrt((p - r) * (p - r) / 4 + q * q));
  const double start = 0.4;
  const double sweep = 2.2;
  for (const double tolerance : {1e-2, 1e-4}) {
    const CircleArcCubics arc =
        CircleArcToCubics(start, sweep, static_cast<double>(stretch), tolerance);
    Real worst = 0;
    for (const std::array<PlanePoint, 4>& cubic : arc.cubics) {
      for (int i = 0; i <= 200; ++i) {
        const RealPoint u = CubicAt(cubic, i / 200.0L);
        worst = std::max(worst, DistanceToArc(map(u.x, u.y), map, start, sweep));
      }
    }
    EXPECT_LE(worst, tolerance) << "tolerance " << tolerance;
    EXPECT_GT(worst, tolerance / 50) << "the sampling does not see the error";
  }
}

TEST(CircleArc, RefusesWhatItCannotMeet) {
  EXPECT_THROW((void)CircleArcToCubics(0, 1, 1, 0), ConstructionError);
  EXPECT_THROW((void)CircleArcToCubics(0, 1, 0, 1), ConstructionError);
  EXPECT_THROW((void)CircleArcToCubics(0, 0, 1, 1), ConstructionError);
  EXPECT_THROW((void)CircleArcToCubics(0, 1, 1, 1e-300), ConstructionError);
}

}  // namespace
}  // namespace fdsurf::host
