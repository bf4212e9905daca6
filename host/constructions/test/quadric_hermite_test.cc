// SPDX-License-Identifier: MIT
// Row 12 of docs/constructions.md: quadric Hermite interpolation on a
// triangulation (seed 000).
#include <gtest/gtest.h>

#include "construction_test_support.h"
#include "fdsurf/host/quadric_hermite.h"

namespace fdsurf::host {
namespace {

// ---- Row 12: quadric Hermite interpolation on a triangulation (seed 000) ----

// The seed's functions for the two triangles, as reconstructed in
// examples/quadric-hermite.json.
double Phi(const Point3& p, double a) {
  const double x = p[0];
  const double y = p[1];
  const double z = p[2];
  return x * x + y * y - 2 + (z - 1) * (a * (z - 1) - y - 1);
}
double Psi(const Point3& p, double a3) {
  const double x = p[0];
  const double y = p[1];
  const double z = p[2];
  return 3 * (x * x + y * y - 2) + (z - 1) * (a3 * (z - 1) - 3 * x - 3);
}

const std::vector<Point3> kSeedVertices = {{1, 1, 1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}};
const std::vector<Point3> kSeedNormals = {{1, 1, -1}, {1, 1, 0}, {1, -1, 0}, {-3, 3, 0}};

TEST(QuadricHermite, ReproducesTheSeedsFunctionsWithTheFreeParameter) {
  const QuadricSolution first =
      SolveQuadricTriangle({kSeedVertices[0], kSeedVertices[1], kSeedVertices[2]},
                           {kSeedNormals[0], kSeedNormals[1], kSeedNormals[2]});
  const QuadricSolution second =
      SolveQuadricTriangle({kSeedVertices[3], kSeedVertices[0], kSeedVertices[1]},
                           {kSeedNormals[3], kSeedNormals[0], kSeedNormals[1]});
  // Condition (3) fails (the vertices share z): the system leaves a33 free.
  ASSERT_EQ(first.rank, 7);
  ASSERT_EQ(first.free_unknowns, std::vector<int>{2});
  EXPECT_STREQ(kQuadricUnknowns[first.free_unknowns[0]], "a33");
  ASSERT_EQ(second.free_unknowns, std::vector<int>{2});
  for (double a : {-0.125, 0.0, 1.0}) {
    const Quadric f = first.With({a});
    const Quadric g = second.With({3 * a});
    for (const Point3& x : {Point3{0.3, -0.2, 0.7}, Point3{2, 1, -3}, Point3{-1.5, 0.5, 2}}) {
      EXPECT_NEAR(f.Value(x), Phi(x, a), 1e-12);
      EXPECT_NEAR(g.Value(x), Psi(x, 3 * a), 1e-12);
    }
  }
}

TEST(QuadricHermite, SolutionsPassThroughTheVerticesWithTheNormals) {
  // Points and normals of an ellipsoid x²/4 + y² + z²/9 = 1 in general position.
  const auto point = [](double u, double v) {
    return Point3{2 * std::cos(u) * std::cos(v), std::sin(u) * std::cos(v), 3 * std::sin(v)};
  };
  const std::array<Point3, 3> p = {point(0.3, 0.2), point(1.1, -0.4), point(2.0, 0.7)};
  std::array<Point3, 3> n{};
  for (int i = 0; i < 3; ++i) n[i] = {p[i][0] / 4, p[i][1], p[i][2] / 9};
  n[1] = {n[1][0] * 5, n[1][1] * 5, n[1][2] * 5};  // lengths other than the first do not matter
  const QuadricSolution solution = SolveQuadricTriangle(p, n);
  // Never unique: with L the plane of the triangle, F + μ·L² has the same
  // values and normals at the vertices (L = 0 there), so one unknown stays
  // free and the family is exactly that.
  EXPECT_EQ(solution.rank, 7);
  ASSERT_EQ(solution.free_unknowns.size(), 1u);
  const Quadric f = solution.With({0.7});
  const Quadric f2 = solution.With({-1.3});
  const Point3 e1{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
  const Point3 e2{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
  const Point3 normal{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                      e1[0] * e2[1] - e1[1] * e2[0]};
  double ratio = 0;
  for (const Point3& x : {Point3{0.3, -0.2, 0.7}, Point3{2, 1, -3}, Point3{-1.5, 0.5, 2}}) {
    const double l =
        normal[0] * (x[0] - p[0][0]) + normal[1] * (x[1] - p[0][1]) + normal[2] * (x[2] - p[0][2]);
    const double r = (f.Value(x) - f2.Value(x)) / (l * l);
    if (ratio != 0) {
      EXPECT_NEAR(r, ratio, 1e-9 * std::fabs(ratio));
    }
    ratio = r;
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f.Value(p[i]), 0, 1e-12);
    const Point3 g = f.Gradient(p[i]);
    const double sine = std::hypot(g[1] * n[i][2] - g[2] * n[i][1], g[2] * n[i][0] - g[0] * n[i][2],
                                   g[0] * n[i][1] - g[1] * n[i][0]) /
                        (std::hypot(g[0], g[1], g[2]) * std::hypot(n[i][0], n[i][1], n[i][2]));
    EXPECT_LT(sine, 1e-10) << i;
  }
  // ∇F at the first vertex is 2·A1 (the seed's form).
  const Point3 g0 = f.Gradient(p[0]);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(g0[c], 2 * n[0][c], 1e-12);
}

TEST(QuadricHermite, GluesAlongThePlaneXEqualsYAndReportsAContinuousJoin) {
  // a ≤ 1/8 leaves the pieces unbounded (refused below); the example draws
  // these three.
  for (double a : {0.25, 0.5, 1.0}) {
    QuadricMesh mesh;
    mesh.vertices = kSeedVertices;
    mesh.normals = kSeedNormals;
    mesh.triangles = {{0, 1, 2}, {3, 1, 0}};
    mesh.free = {{a}, {3 * a}};
    const double tolerance = 0.02;
    const QuadricResult r = BuildQuadricMesh(mesh, tolerance, "q");
    ASSERT_EQ(r.glues.size(), 1u);
    const QuadricGlue& glue = r.glues[0];
    EXPECT_TRUE(glue.conics_coincide);
    // The plane through the shared vertices (1,1,1), (−1,−1,1) and the common
    // point on the z axis: x = y.
    EXPECT_NEAR(std::fabs(glue.plane_normal[0]), std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(glue.plane_normal[0], -glue.plane_normal[1], 1e-12);
    EXPECT_NEAR(glue.plane_normal[2], 0, 1e-12);
    // On x = y the two functions agree (φ − ψ/3 = (z − 1)(x − y)), so the
    // join is continuous, but the normals differ: only C0, as the seed finds.
    EXPECT_LT(glue.gap, 1e-12);
    EXPECT_GT(glue.worst_normal_angle_deg, 1);
    for (const Point3& x : {Point3{0.5, 0.5, -2}, Point3{-0.3, -0.3, 0.4}}) {
      EXPECT_NEAR(Phi(x, a), Psi(x, 3 * a) / 3, 1e-12);
    }
    // Every drawn point lies on its piece's function (the seed's φ and ψ,
    // written out here), to first order within the proven bound.
    EXPECT_LE(r.bound, tolerance);
    ASSERT_FALSE(r.arcs.empty());
    for (const QuadricArc& arc : r.arcs) {
      const auto f = [&](const Point3& x) {
        return arc.triangle == 1 ? Psi(x, 3 * a) / 3 : Phi(x, a);
      };
      const auto distance = [&](const Point3& x) {
        const double h = 1e-6;
        Point3 g{};
        for (int c = 0; c < 3; ++c) {
          Point3 xp = x;
          Point3 xm = x;
          xp[c] += h;
          xm[c] -= h;
          g[c] = (f(xp) - f(xm)) / (2 * h);
        }
        return std::fabs(f(x)) / std::hypot(g[0], g[1], g[2]);
      };
      for (const CubicArc& cubic : arc.cubics) {
        for (int i = 0; i <= 8; ++i) {
          const double t = i / 8.0;
          const double u = 1 - t;
          Point3 x{};
          for (int c = 0; c < 3; ++c) {
            x[c] = u * u * u * cubic.b[0][c] + 3 * u * u * t * cubic.b[1][c] +
                   3 * u * t * t * cubic.b[2][c] + t * t * t * cubic.b[3][c];
          }
          EXPECT_LE(distance(x), arc.bound * 1.01 + 1e-12) << arc.triangle << " " << arc.index;
        }
      }
    }
  }
}

TEST(QuadricHermite, RefusesBadTriangulations) {
  const auto error_of = [](QuadricMesh mesh) {
    try {
      BuildQuadricMesh(mesh, 0.02, "q");
    } catch (const ConstructionError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  QuadricMesh mesh;
  mesh.vertices = kSeedVertices;
  mesh.normals = kSeedNormals;
  mesh.triangles = {{0, 1, 2}, {3, 1, 0}};
  QuadricMesh zero = mesh;
  zero.normals[2] = {0, 0, 0};
  EXPECT_EQ(error_of(zero), "normals[2] has zero length");
  QuadricMesh flat = mesh;
  flat.vertices.push_back({0, 0, 1});  // on the segment from vertex 0 to vertex 1
  flat.normals.push_back({0, 0, 1});
  flat.triangles = {{0, 1, 4}};
  EXPECT_EQ(error_of(flat), "triangles[0]: the triangle is degenerate: its vertices are collinear");
  QuadricMesh missing = mesh;
  missing.triangles = {{0, 1, 7}};
  EXPECT_EQ(error_of(missing), "triangles[0]: vertex 7 does not exist");
  QuadricMesh wrong_free = mesh;
  wrong_free.free = {{1, 2}, {0}};
  EXPECT_EQ(error_of(wrong_free),
            "triangles[0]: the system leaves 1 free parameter(s), but \"free\" gives 2");
  EXPECT_EQ(InputErrorOf([] {
              ParseJson(R"({"construct": [{"type": "quadric-hermite",
                "vertices": [[0,0,0],[1,0,0],[0,1,0]], "normals": [[0,0,1],[0,0,1],[0,0,0]],
                "triangles": [[0,1,2]]}]})",
                        "q.json");
            }),
            "q.json: construct[0]: normals[2] has zero length");
}

}  // namespace
}  // namespace fdsurf::host
