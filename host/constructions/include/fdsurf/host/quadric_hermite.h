// SPDX-License-Identifier: MIT
// Piecewise quadric Hermite interpolation over a triangulation (seed 000):
// for each triangle a second-order surface F(x,y,z) = 0 through its three
// vertices whose normals there are parallel to the given vectors; neighbouring
// pieces glued along a plane through their two shared vertices. The pieces
// are implicit, so they are drawn through a double-precision tessellation
// into bilinear patches (docs/constructions.md, row 12).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
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

struct QuadricMesh {
  std::vector<Point3> vertices;
  std::vector<Point3> normals;
  std::vector<std::array<int, 3>> triangles;
  /// Free parameter values per triangle (empty: 0 for every free unknown).
  std::vector<std::vector<double>> free;
};

struct QuadricPiece {
  QuadricSolution solution;
  Quadric quadric;
  std::vector<double> parameters;
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

struct QuadricResult {
  std::vector<QuadricPiece> pieces;
  std::vector<QuadricGlue> glues;
  /// Bilinear patches of the tessellation, and how many cells had a corner
  /// where the surface does not meet the sampling line (left out).
  std::vector<Patch> patches;
  int cells_per_side = 0;
  int missing_cells = 0;
  /// The tessellation tolerance reached: the largest distance, at every
  /// cell's centre and edge midpoints, between the surface and the patch.
  double tessellation_error = 0;
  std::vector<std::string> notes;
};

/// Solves every triangle, glues neighbours and tessellates each piece into
/// bilinear patches until the sampled deviation is ≤ `tolerance` (file
/// units). Throws ConstructionError on bad input.
QuadricResult BuildQuadricMesh(const QuadricMesh& mesh, double tolerance,
                               const std::string& origin);

}  // namespace fdsurf::host
