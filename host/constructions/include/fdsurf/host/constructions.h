// SPDX-License-Identifier: MIT
// Curve and surface constructions from the source documents (seeds 001-004),
// each turned into cubic curves or bicubic patches that the fixed-point engine
// evaluates. Formulas, sources and bounds: docs/constructions.md.
//
// Conventions: a surface r(u, v) becomes patches with s = u and t = v (after
// mapping each parameter interval onto [0, 1]). Every function throws
// ConstructionError with a message that says what is wrong and by how much;
// the JSON reader prefixes it with the file and the JSON path.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

// ---- Polynomials ------------------------------------------------------------

/// A curve polynomial with vector coefficients: c[k] multiplies u^k.
using VecPoly = std::vector<Point3>;
/// A scalar polynomial: c[k] multiplies x^k.
using Poly = std::vector<double>;

/// A polynomial surface on [0,1]²: c[i][j] multiplies s^i·t^j (i < rows,
/// j < columns; every row has the same length).
struct PolySurface {
  std::vector<std::vector<Point3>> c;
};

/// The power coefficients of a cubic curve, ascending (c[k] multiplies u^k).
VecPoly CurvePolynomial(const Curve& curve);
/// The point of a cubic curve at u, from its basis directly (U·M·g).
Point3 EvaluateCurve(const Curve& curve, double u);
Point3 EvaluatePoly(const VecPoly& p, double u);
double EvaluatePoly(const Poly& p, double x);
Point3 EvaluatePolySurface(const PolySurface& surface, double s, double t);
/// ∂^a/∂s^a ∂^b/∂t^b of the surface at (s, t).
Point3 PolySurfaceDerivative(const PolySurface& surface, int a, int b, double s, double t);

/// The exact Bézier patch of a surface of degree ≤ 3 in s and in t.
/// Throws ConstructionError if a degree exceeds 3.
Patch BezierPatchOf(const PolySurface& surface);
/// The Bézier control points of any patch (exact up to double rounding).
Patch ToBezier(const Patch& patch);

/// Appends `surface` to `out` as patches. Degree ≤ 3 in both parameters: one
/// exact Bézier patch, returns 0. Otherwise K_s × K_t bicubic Hermite pieces
/// interpolating position, first derivatives and twist at the piece corners,
/// with K_s, K_t doubled until the proven bound (docs/constructions.md)
///   max over pieces of (M₄₀ + M₀₄ + M₁₄/4)/384
/// (M: derivative bounds in each piece's own parameters) is ≤ `tolerance`;
/// returns that bound (file units, per coordinate). Throws
/// ConstructionError if 256 pieces per direction do not reach it.
double AppendPatches(const PolySurface& surface, double tolerance, const std::string& origin,
                     std::vector<Patch>* out);

// ---- Row 1: Hermite curves and chains (seed 002) -----------------------------

/// A Hermite segment from P0 to P1 with end vectors T0, T1.
Curve HermiteSegment(const Point3& p0, const Point3& p1, const Point3& t0, const Point3& t1);

enum class JoinClass { kNotSmooth, kGeometric, kParametric };
const char* JoinClassName(JoinClass join);
/// Classifies the join of a segment ending with vector `end` and one starting
/// with `start`: parametric (C¹) if equal within `tolerance`·max(|end|,|start|),
/// geometric (G¹) if parallel with the same direction within that tolerance,
/// not smooth otherwise (also when either vector is zero).
JoinClass ClassifyJoin(const Point3& end, const Point3& start, double tolerance = 1e-9);

struct HermiteChain {
  std::vector<Curve> segments;
  /// joins[k] is the join of segments k and k+1.
  std::vector<JoinClass> joins;
};
/// A chain through points[0..n] (n ≥ 1). Segment k runs from points[k] to
/// points[k+1], leaving with out_vectors[k] and arriving with in_vectors[k+1]
/// (in_vectors[0] and out_vectors[n] are unused). Equal in and out vectors
/// give C¹ joins.
HermiteChain MakeHermiteChain(const std::vector<Point3>& points,
                              const std::vector<Point3>& in_vectors,
                              const std::vector<Point3>& out_vectors);

// ---- Rows 2-4: ruled, bilinear and Coons surfaces (seed 001) ----------------

/// r(u,v) = (1−v)·r1(u) + v·r2(u).
PolySurface RuledSurface(const Curve& r1, const Curve& r2);
/// r(u,v) = (1−u)(1−v)P00 + u(1−v)P10 + (1−u)v·P01 + uv·P11.
PolySurface BilinearSurface(const Point3& p00, const Point3& p10, const Point3& p01,
                            const Point3& p11);

enum class CoonsBlend { kLinear, kCubic };
/// The Coons patch on boundaries r1(u) = r(u,0), r2(u) = r(u,1),
/// r3(v) = r(0,v), r4(v) = r(1,v) (seed 001, eq. 6; kCubic: eq. 7 with
/// f(x) = 3x² − 2x³ in place of x). Throws ConstructionError naming the
/// corner and the gap when two boundaries' corners are farther apart than
/// `tolerance`.
PolySurface CoonsPatch(const Curve& r1, const Curve& r2, const Curve& r3, const Curve& r4,
                       CoonsBlend blend, double tolerance);

// ---- Rows 5, 6, 9: interpolation and families of curves (seeds 001, 003) ---

/// The Lagrange cardinal polynomials on `nodes` (strictly increasing, ≥ 2),
/// in the normalised parameter x = (v − nodes.front()) / (nodes.back() − nodes.front()).
std::vector<Poly> LagrangeBasis(const std::vector<double>& nodes);
/// Bernstein polynomials of degree n.
std::vector<Poly> BernsteinBasis(int n);

/// Tensor-product Lagrange interpolation r(u,v) = Σ_k Σ_l L_k(u)·M_l(v)·r_kl
/// on u_nodes × v_nodes (points[k][l] at (u_k, v_l)).
PolySurface LagrangeGrid(const std::vector<double>& u_nodes, const std::vector<double>& v_nodes,
                         const std::vector<std::vector<Point3>>& points);

/// r(u,v) = Σ_i b_i(v)·c_i(u) for the family `curves` (as polynomials in u)
/// and scalar blending polynomials b_i in t ∈ [0,1].
PolySurface BlendCurves(const std::vector<VecPoly>& curves, const std::vector<Poly>& blend);

// ---- Row 7: Hermite surface over a family of curves (seed 003, eq. 2.18) ---

/// The derivative curves r_v(u, v_i) estimated from the family: the
/// three-point formula for inner curves and the end formulas that make r_vv
/// zero on the edge curves; with `closed`, the family is cyclic with period
/// end v.back() (v has one more value than curves).
std::vector<VecPoly> EstimateFamilyDerivatives(const std::vector<VecPoly>& curves,
                                               const std::vector<double>& v, bool closed);
/// The pieces of r(u,v) = c_i(u)·H0(w) + c_{i+1}(u)·H1(w) + r_v(u,v_i)·Δ·H2(w)
/// + r_v(u,v_{i+1})·Δ·H3(w), w = (v − v_i)/Δ, Δ = v_{i+1} − v_i, one per
/// interval (closed: the last returns to curve 0).
std::vector<PolySurface> HermiteFamily(const std::vector<VecPoly>& curves,
                                       const std::vector<VecPoly>& derivatives,
                                       const std::vector<double>& v, bool closed);

// ---- Row 8: transition surface (seed 003, eq. 2.19) -------------------------

struct Transition {
  PolySurface surface;
  double k_a = 0;
  double k_b = 0;
};
/// Joins the edge t = 1 of patch `a` to the edge t = 0 of patch `b`:
/// r(u,w) = a(u,1)·H0(w) + b(u,0)·H1(w) + k_a·a_v(u,1)·H2(w) + k_b·b_v(u,0)·H3(w).
/// k_a, k_b are the mean distance between the edges over the mean length of
/// a_v(u,1), b_v(u,0) (means over 257 evenly spaced u, trapezoidal), unless
/// given (> 0).
Transition TransitionSurface(const Patch& a, const Patch& b, double k_a = 0, double k_b = 0);

// ---- Row 10: Bézier patch joins (seed 004) ---------------------------------

struct EdgeJoin {
  std::size_t patch_a = 0;
  std::size_t patch_b = 0;
  /// Edge names: "s=0", "s=1", "t=0", "t=1".
  std::string edge_a;
  std::string edge_b;
  /// "C0", "G1", "C1" or "degenerate" (a cross row with a zero-length leg).
  std::string join;
  /// Largest angle (degrees) between P3−P2 and Q1−Q0 over the 4 cross rows.
  double worst_angle_deg = 0;
  /// Largest | |Q1−Q0| / |P3−P2| − 1 |.
  double worst_ratio_error = 0;
  /// Cross rows skipped because a leg is shorter than the tolerance.
  int degenerate_rows = 0;
};
/// Every pair of patch edges whose four Bézier control points coincide (in
/// the same or reverse order, within `tolerance`), classified by the cross
/// rows: C¹ if points 3, 4, 5 of each row are collinear, in order and equally
/// spaced; G¹ if collinear and in order; C⁰ otherwise. Angles up to
/// `angle_deg` and ratio errors up to `ratio` count as equal.
std::vector<EdgeJoin> CheckBezierJoins(const std::vector<Patch>& patches, double tolerance = 1e-9,
                                       double angle_deg = 1e-6, double ratio = 1e-6);

// ---- Row 11: closed spline nets (seed 004) -------------------------------

/// Cuts a uniform B-spline or Catmull-Rom net into patches, wrapping the rows
/// (closed_s) and/or the columns (closed_t) so the surface closes on itself.
/// A closed direction needs ≥ 3 points, an open one ≥ 4.
std::vector<Patch> PeriodicNetPatches(const std::vector<std::vector<Point3>>& net, Basis basis,
                                      bool closed_s, bool closed_t, const std::string& origin);

}  // namespace fdsurf::host
