// SPDX-License-Identifier: MIT
// Conic arcs as rational quadratic Bézier curves, and their approximation by
// cubic Bézier curves with a proven bound (docs/constructions.md, row 12,
// "The cubic approximation of a conic arc"); circular arcs and their affine
// images (ellipses) with the standard circle cubic and a proven geometric
// bound (docs/formats.md, "Circular and elliptical arcs").
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// r(t) = (B0·p0 + w·B1·p1 + B2·p2) / (B0 + w·B1 + B2), t ∈ [0, 1], B_i the
/// quadratic Bernstein polynomials. Every bounded arc of a conic is one for
/// some w > 0 (w < 1 ellipse, w = 1 parabola, w > 1 hyperbola); p1 is where
/// the tangents at the ends meet. Coordinates in any unit (the file's).
struct RationalQuadratic {
  Point3 p0{};
  Point3 p1{};
  Point3 p2{};
  double w = 1;
  /// The point at t (exact up to double rounding).
  FDSURF_NODISCARD Point3 At(double t) const;
};

/// A cubic Bézier curve b and a proven bound: |c(t) − r(t)| ≤ bound for every
/// t ∈ [0, 1], r the arc it approximates (same t), c the cubic.
struct CubicArc {
  std::array<Point3, 4> b{};
  double bound = 0;
  /// The (sub-)arc it approximates.
  RationalQuadratic arc;
};

/// The two halves of an arc at t = 1/2, each again a rational quadratic
/// (its weight is sqrt((1 + w) / 2)).
void SplitArc(const RationalQuadratic& arc, RationalQuadratic* first, RationalQuadratic* second);

/// The cubic Hermite interpolant of the arc: the same end points and end
/// derivatives in t (r′(0) = 2w·(p1 − p0)), so b1 = p0 + (2w/3)·(p1 − p0),
/// b2 = p2 + (2w/3)·(p1 − p2); its error falls as the fourth power of the
/// arc's length. The bound: the largest Bernstein coefficient of c·W − N
/// (degree 5, N and W the arc's numerator and denominator) over the least
/// value of W, plus a margin for double rounding.
FDSURF_NODISCARD CubicArc ApproximateArc(const RationalQuadratic& arc);

/// Cubics covering the arc in order, each with bound ≤ tolerance: the arc is
/// halved until each piece's bound is met. `extra`, when given, is a further
/// bound for a piece (e.g. the piece's own distance from a surface) that is
/// added to its cubic's bound, which then includes it. Throws
/// ConstructionError when that takes more than 2^24 pieces (a tolerance below
/// the arithmetic's rounding, or an extra bound that does not shrink).
std::vector<CubicArc> ArcToCubics(
    const RationalQuadratic& arc, double tolerance,
    const std::function<double(const RationalQuadratic&)>& extra = nullptr);

/// A point in a plane, (x, y).
using PlanePoint = std::array<double, 2>;

/// A circular arc as cubic Bézier curves: the control points on the unit
/// circle about the origin, to be mapped by the caller (a circle: centre +
/// r·p; an ellipse: any affine map).
struct CircleArcCubics {
  /// The arc's pieces in order, all of the same angle; consecutive pieces
  /// share their end point bit for bit.
  std::vector<std::array<PlanePoint, 4>> cubics;
  /// Every point of each cubic is within this distance of its piece of the
  /// unit circle and every point of the piece within it of the cubic (the
  /// Hausdorff distance), before the caller's map and without the rounding
  /// of the control points (the caller's margin).
  double unit_bound = 0;
};

/// The Hausdorff distance bound of the standard cubic of a unit-circle arc of
/// angle `sweep` radians (|sweep| ≤ π/2): (2/27)·sin⁶(φ/4)/cos²(φ/4), φ =
/// |sweep|, rounded up (docs/formats.md). The standard cubic has b1 = b0 +
/// k·(tangent at b0), b2 = b3 − k·(tangent at b3), k = (4/3)·tan(φ/4).
FDSURF_NODISCARD double CircleCubicBound(double sweep);

/// The unit-circle arc from angle `start` over `sweep` (radians, signed:
/// positive counter-clockwise, non-zero) as the fewest equal pieces of at
/// most 90° whose standard cubics have scale·unit_bound ≤ tolerance. `scale`
/// is the largest singular value of the map the caller applies afterwards
/// (the radius for a circle), which stretches no distance by more than that.
/// Throws ConstructionError when tolerance or scale is not > 0 and finite or
/// when that takes more than 2^24 pieces.
FDSURF_NODISCARD CircleArcCubics CircleArcToCubics(double start, double sweep, double scale,
                                                   double tolerance);

}  // namespace fdsurf::host
