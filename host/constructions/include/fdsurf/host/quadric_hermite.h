// SPDX-License-Identifier: MIT
// Piecewise quadric Hermite interpolation over a triangulation (seed 000):
// for each triangle a second-order surface F(x,y,z) = 0 through its three
// vertices whose normals there are parallel to the given vectors; neighbouring
// pieces glued along a plane through their two shared vertices. Each piece is
// its quadric trimmed by the planes of its three edges, drawn by plane
// sections (conic arcs, exactly rational quadratic curves) approximated by
// cubic Bézier curves within a proven bound (docs/constructions.md, row 12).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/conic_arc.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// F(X) = Σ_jk M_jk·D_j·D_k + 2·A·D, D = X − P, with M symmetric: the seed's
/// form around the triangle's first vertex P with its normal A
/// (a_jj = M_jj, a_jk = 2·M_jk for j ≠ k).
struct Quadric {
  Point3 p{};
  Point3 a{};
  std::array<std::array<double, 3>, 3> m{};
  FDSURF_NODISCARD double Value(const Point3& x) const;
  FDSURF_NODISCARD Point3 Gradient(const Point3& x) const;
  /// Q(d) = dᵀ·M·d, the quadratic part along a direction.
  FDSURF_NODISCARD double Form(const Point3& d, const Point3& e) const;
};

/// The points X with Dot(normal, X) = offset; `normal` has unit length.
/// Side(X) > 0 on the side the normal points to.
struct Plane {
  Point3 normal{};
  double offset = 0;
  FDSURF_NODISCARD double Side(const Point3& x) const;
  /// The plane through `point` with the given unit normal.
  static Plane Through(const Point3& point, const Point3& unit_normal);
};

/// The names of the unknowns of the linear system, in order:
/// a11 a22 a33 a12 a13 a23 lambda2 lambda3 (∇F(P_i) = λ_i·A_i).
extern const char* const kQuadricUnknowns[8];

/// The solution set of one triangle's conditions F(P_i) = 0 (i = 2, 3) and
/// ∇F(P_i) = λ_i·A_i (i = 2, 3); F(P_1) = 0 and ∇F(P_1) = 2·A_1 hold by
/// the form. x = particular + Σ t_k·null[k], t_k the free parameters.
struct QuadricSolution {
  int rank = 0;
  /// Indices (into kQuadricUnknowns) of the unknowns left free, like the
  /// seed's a33.
  std::vector<int> free_unknowns;
  std::array<double, 8> particular{};
  std::vector<std::array<double, 8>> null;
  /// The quadric for the given free parameter values (as many as
  /// free_unknowns; each is the value of that unknown).
  FDSURF_NODISCARD Quadric With(const std::vector<double>& parameters) const;
  Point3 p1{};
  Point3 a1{};
};

/// Sets up and solves the linear conditions for triangle (p[0], p[1], p[2])
/// with vertex normals n. Throws ConstructionError for a degenerate triangle
/// (coincident or collinear vertices), a zero-length normal, or an
/// inconsistent system (no quadric has these normals), naming the cause.
QuadricSolution SolveQuadricTriangle(const std::array<Point3, 3>& p,
                                     const std::array<Point3, 3>& n);

/// A triangulation with a normal vector per vertex. Triangles list vertex
/// indices; a triangle's first vertex is the seed's P₁ (F is written around
/// it and ∇F(P₁) = 2·A₁, so the length of that normal scales F).
struct QuadricMesh {
  std::vector<Point3> vertices;
  std::vector<Point3> normals;
  std::vector<std::array<int, 3>> triangles;
  /// Free parameter values per triangle (empty: 0 for every free unknown).
  std::vector<std::vector<double>> free;
  /// μ, the coefficient of L² in F = F* + μ·L² (L(X) = n·(X − P₁), n the
  /// triangle's unit normal, F* the member of the family with no L² part:
  /// nᵀ·M*·n = 0): empty to let `free` decide, one value for every
  /// triangle, or one per triangle. In units of F per length².
  std::vector<double> mu;
  /// μ from the normals instead: per triangle |A₁| times the mean over its
  /// edges of (g_i − g_j)·(P_i − P_j) / |P_i − P_j|² (g the unit normals),
  /// the normal curvature the normals turn by. Exact on a sphere.
  bool mu_from_normals = false;
  /// Plane sections drawn across each piece, parallel to its triangle.
  int sections = 8;
  /// Turn the normals (by as little as it takes) until every triangle's
  /// conditions have a solution: they do only when
  /// (A_i·e_ij)(A_j·e_jk)(A_k·e_ki) = −(A_j·e_ij)(A_k·e_jk)(A_i·e_ki)
  /// (e_ij = P_j − P_i), which normals from a file rarely meet exactly.
  /// The normals are replaced by the nearest field of compatible ones
  /// (docs/constructions.md, row 12). Off: such a triangle is refused.
  bool adjust_normals = false;
  /// The largest turn (degrees) adjust_normals may make; a mesh that needs
  /// more is refused.
  double max_normal_turn_deg = 30;
};

struct QuadricPiece {
  QuadricSolution solution;
  Quadric quadric;
  std::vector<double> parameters;
  /// nᵀ·M·n of the chosen quadric: its μ.
  double mu = 0;
  /// The triangle's unit normal n (the direction of L).
  Point3 plane_normal{};
};

struct QuadricGlue {
  int triangle_a = 0;
  int triangle_b = 0;
  int vertex_a = 0;  // the shared vertices (mesh indices)
  int vertex_b = 0;
  /// The glue plane: unit normal and a point on it (the shared vertex a).
  Point3 plane_normal{};
  /// Whether a plane was found where both pieces cut the same conic.
  bool conics_coincide = false;
  /// Largest angle (degrees) between the two pieces' normals along the
  /// glue curve: 0 for a tangent-continuous join.
  double worst_normal_angle_deg = 0;
  /// Largest distance (to first order, |F_b|/|∇F_b|) of piece a's glue
  /// curve from piece b: 0 up to rounding when the conics coincide.
  double gap = 0;
};

/// One drawn conic arc of a piece and its cubic approximation.
struct QuadricArc {
  enum class Role { kOutline, kSection };
  int triangle = 0;
  Role role = Role::kSection;
  /// Outline: the triangle's edge (k: from its vertex k to vertex k+1 mod 3);
  /// section: its index (0 .. sections − 1).
  int index = 0;
  /// Whether the curves went to the drawing (a shared edge's outline is
  /// drawn once, from the lower-numbered triangle).
  bool drawn = true;
  RationalQuadratic arc;
  std::vector<CubicArc> cubics;
  /// Proven: every point of the cubics lies within `bound` of the quadric
  /// (the cubic's bound plus the arc's own distance from the quadric, which
  /// is double rounding).
  double bound = 0;
};

struct QuadricResult {
  std::vector<QuadricPiece> pieces;
  std::vector<QuadricGlue> glues;
  /// The trimming planes of each piece, oriented so that Side > 0 inside
  /// (towards the third vertex): planes[t][k] holds edge k of triangle t.
  std::vector<std::array<Plane, 3>> planes;
  std::vector<QuadricArc> arcs;
  /// The cubic Bézier curves of every drawn arc, in order.
  std::vector<Curve> curves;
  /// The largest QuadricArc::bound.
  double bound = 0;
  /// With adjust_normals: the normals used, and the largest turn (degrees).
  std::vector<Point3> normals;
  double largest_normal_turn_deg = 0;
  std::vector<std::string> notes;
};

/// Solves every triangle, glues neighbours and draws each piece as cubic
/// curves within `tolerance` (file units) of it. Throws ConstructionError on
/// bad input: an edge of more than two triangles or two triangles that run
/// along an edge the same way (naming the edge), and the cases of
/// SolveQuadricTriangle (naming the triangle).
QuadricResult BuildQuadricMesh(const QuadricMesh& mesh_in, double tolerance,
                               const std::string& origin);

}  // namespace fdsurf::host
