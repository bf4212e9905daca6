// SPDX-License-Identifier: MIT
// The curve in which a quadric surface meets a plane (a conic, or one or two
// lines when it degenerates), parametrised so that arcs of it can be cut out
// exactly and written as rational quadratic Bézier curves
// (docs/constructions.md, row 12).
#pragma once

#include <optional>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/conic_arc.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quadric_hermite.h"

namespace fdsurf::host {

/// One connected curve of a plane section, with a parameter.
///
/// A proper conic is parametrised by the pencil of lines through a point K on
/// it: the direction θ ∈ [0, π) of a line through K picks the line's second
/// crossing with the conic (the tangent's direction picks K). The map is one
/// to one onto the conic (K included) except at the directions of its points
/// at infinity (none for an ellipse, one for a parabola, two for a
/// hyperbola), and θ is cyclic: an arc may run through π back to 0.
/// A line is parametrised by arc length from a point on it.
class SectionBranch {
 public:
  enum class Kind { kConic, kLine };

  /// The conic q(u,v) = a·u² + 2b·uv + c·v² + 2d·u + 2e·v + g = 0 of the
  /// plane with origin O and orthonormal directions e1, e2 (u along e1,
  /// v along e2), through the point k (frame coordinates) of it.
  static SectionBranch Conic(const Point3& origin, const Point3& e1, const Point3& e2,
                             const double (&coefficients)[6], const double (&k)[2]);
  /// The line of that plane through frame point p with unit direction dir.
  static SectionBranch Line(const Point3& origin, const Point3& e1, const Point3& e2,
                            const double (&p)[2], const double (&dir)[2]);

  FDSURF_NODISCARD Kind kind() const { return kind_; }
  /// For a conic: the parameter period π; a line's parameter is not cyclic.
  FDSURF_NODISCARD bool Cyclic() const { return kind_ == Kind::kConic; }

  /// The point at parameter p (a conic's p is taken mod π).
  FDSURF_NODISCARD Point3 At(double p) const;
  /// The parameter of a point on the branch (of the nearest point for a
  /// line; for a conic the direction of x − K, or K's own at K).
  FDSURF_NODISCARD double ParameterOf(const Point3& x) const;
  /// The parameters where the branch crosses the plane `cut` (at most two),
  /// unsorted; none when the branch lies in the cut or parallel to it.
  FDSURF_NODISCARD std::vector<double> Crossings(const Plane& cut) const;
  /// A conic's parameters at infinity (0, 1 or 2 of them).
  FDSURF_NODISCARD std::vector<double> AtInfinity() const;
  /// The arc from p0 forward to p1 (for a conic: increasing θ, through π
  /// back to 0 when p1 < p0) as rational quadratic arcs in order. The arc
  /// must not contain a point at infinity.
  FDSURF_NODISCARD std::vector<RationalQuadratic> Arc(double p0, double p1) const;

 private:
  FDSURF_NODISCARD Point3 ToSpace(double u, double v) const;
  void ArcSpan(double t0, double t1, int depth, std::vector<RationalQuadratic>* out) const;

  Kind kind_ = Kind::kConic;
  Point3 origin_{};
  Point3 e1_{};
  Point3 e2_{};
  double quad_[3] = {};  // a, b, c
  double k_[2] = {};     // K (conic) or the line's point
  double grad_[2] = {};  // half the gradient of q at K: A·K + (d, e)
  double dir_[2] = {};   // the line's direction
};

/// The section of quadric f by the plane through `origin` spanned by the
/// orthonormal e1, e2: its branches (a proper conic: one; a pair of lines:
/// two; one line: one; nothing real: none). `known` is a point of the section
/// to parametrise a conic from (e.g. a vertex on a glue plane); without it
/// one is searched for near `origin`. A conic whose real points all lie
/// farther than `reach` from `origin` counts as none.
std::vector<SectionBranch> SectionOf(const Quadric& f, const Point3& origin, const Point3& e1,
                                     const Point3& e2, const std::optional<Point3>& known,
                                     double reach);

}  // namespace fdsurf::host
