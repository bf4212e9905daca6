// SPDX-License-Identifier: MIT
// The parts of the SVG reader (svg_io.cc): the path grammar (svg_path.cc),
// transforms and lengths (svg_transform.cc). Not installed.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host::svg {

using Vec2 = std::array<double, 2>;

/// A syntax error inside one attribute's value; the element walker adds the
/// file, line, element and attribute ("a.svg:12: <path id="p3"> d: ...").
class SyntaxError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// x' = a·x + c·y + e, y' = b·x + d·y + f: SVG's matrix(a b c d e f).
struct Affine {
  double a = 1, b = 0, c = 0, d = 1, e = 0, f = 0;
  FDSURF_NODISCARD Vec2 Apply(const Vec2& p) const {
    return {a * p[0] + c * p[1] + e, b * p[0] + d * p[1] + f};
  }
  /// This map after `inner`: (this ∘ inner)(p) = this(inner(p)).
  FDSURF_NODISCARD Affine After(const Affine& inner) const;
  /// The largest singular value of the linear part: the most any distance
  /// is stretched (|A(p) − A(q)| ≤ MaxStretch()·|p − q|).
  FDSURF_NODISCARD double MaxStretch() const;
};

/// A transform list ("translate(10) rotate(30, 5, 5) matrix(...)"); throws
/// SyntaxError naming the column.
Affine ParseTransform(std::string_view text);

/// Numbers separated by white space and/or commas (points="", viewBox="").
std::vector<double> ParseNumberList(std::string_view text);

/// A length in user units (px): a number with an optional unit mm, cm, in,
/// pt, pc, px (96 px per inch). Throws SyntaxError for percentages (not
/// supported), other units or a malformed number.
double ParseLength(std::string_view text);

/// Millimetres per user unit of a unit suffix ("" and "px": 25.4 / 96);
/// 0 for an unknown unit.
double MillimetresPerUnit(std::string_view unit);

/// What the path grammar produces, in absolute user coordinates, segment by
/// segment. Quadratics are already degree-elevated (exact).
class PathSink {
 public:
  virtual ~PathSink() = default;
  PathSink() = default;
  PathSink(const PathSink&) = delete;
  PathSink& operator=(const PathSink&) = delete;
  PathSink(PathSink&&) = delete;
  PathSink& operator=(PathSink&&) = delete;
  virtual void Line(const Vec2& from, const Vec2& to) = 0;
  virtual void Cubic(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3) = 0;
  /// An elliptical arc in endpoint form (SVG 2 appendix B.2.3); radii as
  /// written (sign and size not yet corrected), rotation in degrees.
  virtual void Arc(const Vec2& from, double rx, double ry, double rotation_deg, bool large_arc,
                   bool sweep, const Vec2& to) = 0;
};

/// Parses path data (the d attribute, SVG 2 §9.3.9) into `sink`. Throws
/// SyntaxError ("expected a number after 'C' at column 18"). Like SVG 2's
/// error handling it does not draw a prefix of a broken path: the caller
/// drops what the sink collected when this throws.
void ParsePathData(std::string_view d, PathSink* sink);

/// An arc in centre form (SVG 2 appendix B.2.4): centre, radii (scaled up
/// when too small), rotation, start angle and signed sweep, radians.
struct CentreArc {
  Vec2 centre{};
  double rx = 0, ry = 0;
  double rotation = 0;
  double theta1 = 0;
  double delta = 0;
  /// The point at angle theta on the ellipse: centre + R(rotation)·(rx cos θ, ry sin θ).
  FDSURF_NODISCARD Vec2 At(double theta) const;
};

/// The centre form of an endpoint arc whose radii are both non-zero and whose
/// ends differ (the caller draws the other cases as a line or nothing).
CentreArc EndpointToCentre(const Vec2& from, double rx, double ry, double rotation_deg,
                           bool large_arc, bool sweep, const Vec2& to);

/// Turns path segments into the drawing's curves: each control point mapped
/// by `to_out` (user space to the output page, mm, y up), lines and cubics
/// exactly, arcs as cubic pieces within `arc_tolerance` mm of the exact
/// (mapped) arc. Throws SyntaxError for an arc the arithmetic cannot draw
/// within the tolerance (coordinates so large that rounding alone exceeds
/// half of it); ConstructionError passes through from CircleArcToCubics.
class CurveSink : public PathSink {
 public:
  CurveSink(const Affine& to_out, double arc_tolerance, std::string origin, std::vector<Curve>* out)
      : to_out_(to_out), arc_tolerance_(arc_tolerance), origin_(std::move(origin)), out_(out) {}
  void Line(const Vec2& from, const Vec2& to) override;
  void Cubic(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3) override;
  void Arc(const Vec2& from, double rx, double ry, double rotation_deg, bool large_arc, bool sweep,
           const Vec2& to) override;

 private:
  void Add(const std::array<Vec2, 4>& out_points, bool straight);
  Affine to_out_;
  double arc_tolerance_;
  std::string origin_;
  std::vector<Curve>* out_;
};

}  // namespace fdsurf::host::svg
