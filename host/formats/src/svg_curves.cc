// SPDX-License-Identifier: MIT
// Path segments as the drawing's cubic curves (docs/formats.md, "SVG"):
// lines and cubics exactly, elliptical arcs as the standard cubics of the unit
// circle mapped to the page, with their proven bound (CircleArcToCubics).
#include <cmath>
#include <limits>

#include "fdsurf/host/conic_arc.h"
#include "fdsurf/host/text.h"
#include "svg_internal.h"

namespace fdsurf::host::svg {
namespace {

Point3 Lift(const Vec2& p) { return {p[0], p[1], 0}; }

double Distance(const Vec2& p, const Vec2& q) { return std::hypot(p[0] - q[0], p[1] - q[1]); }

}  // namespace

void CurveSink::Add(const std::array<Vec2, 4>& out_points, bool straight) {
  Curve curve;
  curve.basis = Basis::kBezier;
  for (std::size_t i = 0; i < 4; ++i) curve.g[i] = Lift(out_points[i]);
  curve.origin = origin_;
  curve.straight = straight;
  out_->push_back(std::move(curve));
}

void CurveSink::Line(const Vec2& from, const Vec2& to) {
  const Vec2 a = to_out_.Apply(from);
  const Vec2 b = to_out_.Apply(to);
  // A line as a cubic: control points at 1/3 and 2/3 (uniform speed).
  Add({a, Vec2{a[0] + (b[0] - a[0]) / 3, a[1] + (b[1] - a[1]) / 3},
       Vec2{a[0] + 2 * (b[0] - a[0]) / 3, a[1] + 2 * (b[1] - a[1]) / 3}, b},
      true);
}

void CurveSink::Cubic(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3) {
  // Affine maps commute with Bézier curves: map the control points.
  Add({to_out_.Apply(p0), to_out_.Apply(p1), to_out_.Apply(p2), to_out_.Apply(p3)}, false);
}

void CurveSink::Arc(const Vec2& from, double rx, double ry, double rotation_deg, bool large_arc,
                    bool sweep, const Vec2& to) {
  // SVG 2 B.2.5: identical ends draw nothing, a zero radius a straight line.
  if (from == to) return;
  if (rx == 0 || ry == 0) {
    Line(from, to);
    return;
  }
  const CentreArc arc = EndpointToCentre(from, rx, ry, rotation_deg, large_arc, sweep, to);
  // The ellipse as an affine image of the unit circle, then mapped to the
  // page: T(u, v) = to_out(centre + R(rotation)·(rx·u, ry·v)).
  const double cs = std::cos(arc.rotation);
  const double sn = std::sin(arc.rotation);
  const Affine ellipse{cs * arc.rx, sn * arc.rx,   -sn * arc.ry,
                       cs * arc.ry, arc.centre[0], arc.centre[1]};
  const Affine t = to_out_.After(ellipse);
  // What rounding may have moved: the computed ends from the file's ends
  // (measured) and every control point by a few units in the last place of
  // the page's coordinates (32 ε is generous for the handful of operations).
  const Vec2 start = to_out_.Apply(from);
  const Vec2 end = to_out_.Apply(to);
  const double magnitude = std::abs(t.e) + std::abs(t.f) + t.MaxStretch() * 2;
  const double margin =
      32 * std::numeric_limits<double>::epsilon() * magnitude +
      std::max(
          Distance(t.Apply({std::cos(arc.theta1), std::sin(arc.theta1)}), start),
          Distance(t.Apply({std::cos(arc.theta1 + arc.delta), std::sin(arc.theta1 + arc.delta)}),
                   end));
  if (!(margin < arc_tolerance_ / 2)) {
    throw SyntaxError("the arc cannot be drawn within the arc tolerance (--arc-tolerance) " +
                      FormatNumber(arc_tolerance_) + " mm: rounding alone moves it by " +
                      FormatNumber(margin) + " mm");
  }
  // The unit circle's standard cubics, mapped: T stretches no distance by
  // more than its largest singular value, so the mapped cubics lie within
  // MaxStretch()·unit_bound of the mapped arc (and it of them), and moving
  // control points by ≤ margin moves every point of a cubic by ≤ margin.
  const CircleArcCubics pieces =
      CircleArcToCubics(arc.theta1, arc.delta, t.MaxStretch(), arc_tolerance_ - margin);
  for (std::size_t k = 0; k < pieces.cubics.size(); ++k) {
    const std::array<PlanePoint, 4>& u = pieces.cubics[k];
    Add({k == 0 ? start : t.Apply(u[0]), t.Apply(u[1]), t.Apply(u[2]),
         k + 1 == pieces.cubics.size() ? end : t.Apply(u[3])},
        false);
  }
}

}  // namespace fdsurf::host::svg
