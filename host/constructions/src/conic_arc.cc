// SPDX-License-Identifier: MIT
#include "fdsurf/host/conic_arc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/vec3.h"

namespace fdsurf::host {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

double Binomial(int n, int k) {
  static const double kTable[6][6] = {{1, 0, 0, 0, 0, 0}, {1, 1, 0, 0, 0, 0}, {1, 2, 1, 0, 0, 0},
                                      {1, 3, 3, 1, 0, 0}, {1, 4, 6, 4, 1, 0}, {1, 5, 10, 10, 5, 1}};
  return kTable[n][k];
}

double MaxAbs(const Point3& p) {
  return std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
}

// The standard cubic of the unit-circle arc from angle a to angle b:
// b1 = b0 + k·(−sin a, cos a), b2 = b3 − k·(−sin b, cos b), k = (4/3)·tan((b − a)/4)
// (negative for a clockwise arc, which turns the tangents round).
std::array<PlanePoint, 4> UnitCircleCubic(double a, double b) {
  const double k = 4.0 / 3 * std::tan((b - a) / 4);
  const double ca = std::cos(a);
  const double sa = std::sin(a);
  const double cb = std::cos(b);
  const double sb = std::sin(b);
  return {PlanePoint{ca, sa}, PlanePoint{ca - k * sa, sa + k * ca},
          PlanePoint{cb + k * sb, sb - k * cb}, PlanePoint{cb, sb}};
}

// The arc as `pieces` cubics of equal angle; each piece's bound is computed
// from its own end angles (rounding makes the pieces' angles differ a little).
CircleArcCubics CirclePieces(double start, double sweep, long pieces) {
  CircleArcCubics out;
  out.cubics.reserve(static_cast<std::size_t>(pieces));
  double from = start;
  for (long k = 1; k <= pieces; ++k) {
    const double to = k == pieces
                          ? start + sweep
                          : start + sweep * (static_cast<double>(k) / static_cast<double>(pieces));
    out.cubics.push_back(UnitCircleCubic(from, to));
    out.unit_bound = std::max(out.unit_bound, CircleCubicBound(to - from));
    from = to;
  }
  return out;
}

}  // namespace

double CircleCubicBound(double sweep) {
  // max over t of |c(t)|² − 1 = (4/27)·sin⁶(φ/4)/cos²(φ/4), and
  // |c| − 1 = sqrt(1 + ρ) − 1 ≤ ρ/2 (docs/formats.md). The factor covers the
  // relative rounding of these few operations (sin and cos within an ulp);
  // denorm_min keeps the value an upper bound where s⁶ underflows.
  const double s = std::sin(std::fabs(sweep) / 4);
  const double c = std::cos(std::fabs(sweep) / 4);
  const double s3 = s * s * s;
  return 2.0 / 27 * s3 * s3 / (c * c) * (1 + 64 * kEps) + std::numeric_limits<double>::denorm_min();
}

CircleArcCubics CircleArcToCubics(double start, double sweep, double scale, double tolerance) {
  if (!(tolerance > 0) || !std::isfinite(tolerance) || !(scale > 0) || !std::isfinite(scale) ||
      !std::isfinite(start) || !std::isfinite(sweep) || sweep == 0) {
    throw ConstructionError(
        "a circular arc needs a non-zero finite sweep and a tolerance and "
        "scale > 0 (tolerance " +
        FormatNumber(tolerance) + ", scale " + FormatNumber(scale) + ")");
  }
  constexpr long kMaxPieces = 1L << 24;
  const double angle = std::fabs(sweep);
  long pieces = std::max(1L, static_cast<long>(std::ceil(angle / (std::numbers::pi / 2))));
  for (;;) {
    // The bound grows as φ⁶, so n·(bound/tolerance)^(1/6) pieces nearly
    // meet it; the check with the pieces' own angles decides.
    const double excess = scale * CircleCubicBound(angle / static_cast<double>(pieces)) / tolerance;
    if (excess > 1) {
      const double estimate = std::ceil(static_cast<double>(pieces) * std::pow(excess, 1.0 / 6));
      pieces = std::max(pieces + 1, static_cast<long>(std::min(estimate, 2.0 * kMaxPieces)));
    } else {
      CircleArcCubics out = CirclePieces(start, sweep, pieces);
      if (scale * out.unit_bound <= tolerance) return out;
      ++pieces;
    }
    if (pieces > kMaxPieces) {
      throw ConstructionError("a circular arc cannot be bounded within tolerance " +
                              FormatNumber(tolerance) + " by 2^24 cubic pieces");
    }
  }
}

Point3 RationalQuadratic::At(double t) const {
  const double b0 = (1 - t) * (1 - t);
  const double b1 = 2 * t * (1 - t) * w;
  const double b2 = t * t;
  const double denominator = b0 + b1 + b2;
  return Scale(Add(Add(Scale(p0, b0), Scale(p1, b1)), Scale(p2, b2)), 1 / denominator);
}

void SplitArc(const RationalQuadratic& arc, RationalQuadratic* first, RationalQuadratic* second) {
  // De Casteljau on the homogeneous points (p0, 1), (w·p1, w), (p2, 1); each
  // half is brought back to end weights 1, which leaves the middle weight
  // ((1 + w) / 2) / sqrt((1 + w) / 2).
  const double w = arc.w;
  const Point3 left = Scale(Add(arc.p0, Scale(arc.p1, w)), 1 / (1 + w));
  const Point3 right = Scale(Add(arc.p2, Scale(arc.p1, w)), 1 / (1 + w));
  const Point3 middle = Scale(Add(Add(arc.p0, Scale(arc.p1, 2 * w)), arc.p2), 1 / (2 + 2 * w));
  const double half_weight = std::sqrt((1 + w) / 2);
  *first = RationalQuadratic{arc.p0, left, middle, half_weight};
  *second = RationalQuadratic{middle, right, arc.p2, half_weight};
}

CubicArc ApproximateArc(const RationalQuadratic& arc) {
  const double w = arc.w;
  const double alpha = 2 * w / 3;
  CubicArc cubic;
  cubic.arc = arc;
  cubic.b[0] = arc.p0;
  cubic.b[1] = Add(arc.p0, Scale(Sub(arc.p1, arc.p0), alpha));
  cubic.b[2] = Add(arc.p2, Scale(Sub(arc.p1, arc.p2), alpha));
  cubic.b[3] = arc.p2;
  // e(t)·W(t) = c(t)·W(t) − N(t) in the degree-5 Bernstein basis, with
  // everything relative to p0 (so that the coefficients are small where the
  // arc is). Coefficient k: Σ_j C(2,j)·C(3,k−j)/C(5,k)·(W_j·c_{k−j} − N_j).
  const Point3 q1 = Sub(arc.p1, arc.p0);
  const Point3 q2 = Sub(arc.p2, arc.p0);
  const Point3 c[4] = {{0, 0, 0}, Scale(q1, alpha), Add(q2, Scale(Sub(q1, q2), alpha)), q2};
  const double weight[3] = {1, w, 1};
  const Point3 numerator[3] = {{0, 0, 0}, Scale(q1, w), q2};
  double largest = 0;
  for (int k = 0; k <= 5; ++k) {
    Point3 d{0, 0, 0};
    for (int j = std::max(0, k - 3); j <= std::min(2, k); ++j) {
      const double factor = Binomial(2, j) * Binomial(3, k - j) / Binomial(5, k);
      d = Add(d, Scale(Sub(Scale(c[k - j], weight[j]), numerator[j]), factor));
    }
    largest = std::max(largest, Norm(d));
  }
  // W(t) = 1 − 2t(1 − t)(1 − w): least at t = 1/2 when w < 1, else at the ends.
  const double least_weight = std::min(1.0, (1 + w) / 2);
  // The margin covers the rounding of the sums above (a few operations on
  // values of size |q|·max(1, w)) and of the stored control points.
  const double size = std::max(MaxAbs(q1), MaxAbs(q2));
  const double absolute = std::max({MaxAbs(arc.p0), MaxAbs(arc.p1), MaxAbs(arc.p2)});
  const double margin = 64 * kEps * (size * std::max(1.0, w) / least_weight + absolute);
  cubic.bound = largest / least_weight + margin;
  return cubic;
}

std::vector<CubicArc> ArcToCubics(const RationalQuadratic& arc, double tolerance,
                                  const std::function<double(const RationalQuadratic&)>& extra) {
  constexpr int kMaxDepth = 24;
  std::vector<CubicArc> out;
  // Depth-first, first half first, so that the cubics come out in order.
  std::vector<std::pair<RationalQuadratic, int>> stack = {{arc, 0}};
  while (!stack.empty()) {
    const auto [piece, depth] = stack.back();
    stack.pop_back();
    CubicArc cubic = ApproximateArc(piece);
    if (extra) cubic.bound += extra(piece);
    if (cubic.bound <= tolerance) {
      out.push_back(cubic);
      continue;
    }
    if (depth >= kMaxDepth) {
      throw ConstructionError("a conic arc cannot be bounded within tolerance " +
                              FormatNumber(tolerance) +
                              " by 2^24 cubic pieces (below the arithmetic's rounding, or the "
                              "surface is nearly singular there)");
    }
    RationalQuadratic first;
    RationalQuadratic second;
    SplitArc(piece, &first, &second);
    stack.emplace_back(second, depth + 1);
    stack.emplace_back(first, depth + 1);
  }
  return out;
}

}  // namespace fdsurf::host
