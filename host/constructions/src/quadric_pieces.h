// SPDX-License-Identifier: MIT
// Drawing one piece of the quadric Hermite construction (docs/constructions.md,
// row 12): its quadric trimmed by the planes of its three edges, as its
// outline (the trimmed glue conics) and plane sections parallel to its
// triangle, each conic arc cut exactly and approximated by cubic curves with a
// proven bound. Internal to the constructions box.
#pragma once

#include <array>
#include <vector>

#include "fdsurf/host/plane_section.h"
#include "fdsurf/host/quadric_hermite.h"

namespace fdsurf::host::internal {

struct PieceInput {
  const Quadric* f = nullptr;
  int triangle = 0;
  /// The mesh's numbers of the triangle's vertices, for messages.
  std::array<int, 3> vertex_ids{};
  /// The triangle's vertices; edge k runs from p[k] to p[(k + 1) % 3].
  std::array<Point3, 3> p{};
  /// The trimming plane of each edge, Side > 0 towards the third vertex.
  std::array<Plane, 3> planes{};
  /// The triangle's unit normal (sections are the planes n·(X − p[0]) = h).
  Point3 n{};
  int sections = 8;
  /// Each cubic within this of the quadric (file units).
  double tolerance = 1e-3;
};

/// The piece's arcs: the three outline arcs (edge order) and then the
/// sections, lowest first. Throws ConstructionError when an outline arc
/// cannot be found inside the other two planes, runs through infinity, or the
/// bound cannot be met, naming the triangle and edge.
std::vector<QuadricArc> DrawPiece(const PieceInput& in);

/// A proven bound on the distance of every point of a rational quadratic arc
/// from the quadric's surface (first order made rigorous: 2·ε/γ where
/// |F| ≤ ε on the arc by Bernstein bounds and |∇F| ≥ γ > 0 by a Lipschitz
/// bound, valid when 4·ε·‖M‖ ≤ γ²); infinity where that does not hold.
double ArcDistanceBound(const RationalQuadratic& arc, const Quadric& f);

}  // namespace fdsurf::host::internal
