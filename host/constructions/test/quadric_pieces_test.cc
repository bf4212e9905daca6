// SPDX-License-Identifier: MIT
// Row 12 of docs/constructions.md drawn with a proof: conic arcs as rational
// quadratics, their cubic approximations and bounds, plane sections of
// quadrics, and whole meshes (a sphere reproduced exactly, random meshes, the
// glue curves of neighbours). The references here are independent of the
// code under test: the sphere's own equation, dense sampling of the exact
// arcs, and a Newton projection onto each quadric.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>

#include "fdsurf/host/conic_arc.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/mesh_io.h"
#include "fdsurf/host/plane_section.h"
#include "fdsurf/host/quadric_hermite.h"
#include "fdsurf/host/vec3.h"

namespace fdsurf::host {
namespace {

constexpr double kPi = std::numbers::pi;

Point3 CubicAt(const std::array<Point3, 4>& b, double t) {
  const double u = 1 - t;
  Point3 x{};
  for (int c = 0; c < 3; ++c) {
    x[c] = u * u * u * b[0][c] + 3 * u * u * t * b[1][c] + 3 * u * t * t * b[2][c] +
           t * t * t * b[3][c];
  }
  return x;
}

// The largest |c(t) − r(t)| over 2001 samples.
double SampledError(const CubicArc& cubic, const RationalQuadratic& arc) {
  double worst = 0;
  for (int i = 0; i <= 2000; ++i) {
    const double t = i / 2000.0;
    worst = std::max(worst, Norm(Sub(CubicAt(cubic.b, t), arc.At(t))));
  }
  return worst;
}

// ---- Conic arcs and their cubics ----

TEST(ConicArc, TheBoundHoldsAndIsTightOnCirclesAndHyperbolas) {
  // A circle arc of angle φ: p1 at radius 1/cos(φ/2) on the bisector,
  // w = cos(φ/2). A hyperbola x² − y² = 1 over (−d, d): w = cosh(d).
  std::vector<RationalQuadratic> arcs;
  for (double phi : {kPi / 2, kPi / 4, 1.0, 0.3}) {
    const double r = 50;
    arcs.push_back({{r, 0, 0},
                    {r, r * std::tan(phi / 2), 0},
                    {r * std::cos(phi), r * std::sin(phi), 0},
                    std::cos(phi / 2)});
  }
  for (double d : {1.0, 0.5, 0.2}) {
    arcs.push_back({{std::cosh(d), -std::sinh(d), 3},
                    {1 / std::cosh(d), 0, 3},
                    {std::cosh(d), std::sinh(d), 3},
                    std::cosh(d)});
  }
  for (const RationalQuadratic& arc : arcs) {
    const CubicArc cubic = ApproximateArc(arc);
    const double sampled = SampledError(cubic, arc);
    EXPECT_GE(cubic.bound, sampled) << "w " << arc.w;
    // Not vacuous: within a small factor of the truth, so a bound computed a
    // few times too small (or an approximation a few times worse) fails the
    // line above.
    EXPECT_LE(cubic.bound, 3 * sampled + 1e-12) << "w " << arc.w;
  }
}

TEST(ConicArc, HalvesStayOnTheConicAndTheBoundFallsWithTheFourthPower) {
  RationalQuadratic arc{{50, 0, 0}, {50, 50, 0}, {0, 50, 0}, std::sqrt(0.5)};
  double previous = ApproximateArc(arc).bound;
  for (int level = 1; level <= 5; ++level) {
    RationalQuadratic first;
    RationalQuadratic second;
    SplitArc(arc, &first, &second);
    for (int i = 0; i <= 16; ++i) {
      for (const RationalQuadratic* half : {&first, &second}) {
        EXPECT_NEAR(Norm(half->At(i / 16.0)), 50, 1e-12);
      }
    }
    EXPECT_NEAR(Norm(first.At(1)), 50, 1e-12);
    const double bound = ApproximateArc(first).bound;
    EXPECT_LT(bound, previous / 10) << level;  // ≈ 1/16 per halving
    previous = bound;
    arc = first;
  }
}

TEST(ConicArc, ArcToCubicsCoversTheArcInOrderWithinTheTolerance) {
  const RationalQuadratic arc{{50, 0, 0}, {50, 50, 0}, {0, 50, 0}, std::sqrt(0.5)};
  const std::vector<CubicArc> cubics = ArcToCubics(arc, 1e-3);
  ASSERT_GT(cubics.size(), 1u);
  EXPECT_NEAR(Norm(Sub(cubics.front().b[0], arc.p0)), 0, 1e-12);
  EXPECT_NEAR(Norm(Sub(cubics.back().b[3], arc.p2)), 0, 1e-12);
  for (std::size_t i = 0; i < cubics.size(); ++i) {
    EXPECT_LE(cubics[i].bound, 1e-3);
    EXPECT_GE(cubics[i].bound, SampledError(cubics[i], cubics[i].arc));
    for (int k = 0; k <= 100; ++k) EXPECT_NEAR(Norm(CubicAt(cubics[i].b, k / 100.0)), 50, 1e-3);
    if (i > 0) {
      EXPECT_EQ(cubics[i].b[0], cubics[i - 1].b[3]);
    }
  }
}

// ---- Plane sections ----

// The unit sphere about c as a Quadric in the seed's form around the point p
// of it: F = (|X − c|² − r²)/r, ∇F(p) = 2(p − c)/r.
Quadric Sphere(const Point3& c, double r, const Point3& p) {
  Quadric f;
  f.p = p;
  f.a = Scale(Sub(p, c), 1 / r);
  for (int j = 0; j < 3; ++j) f.m[j][j] = 1 / r;
  return f;
}

TEST(PlaneSection, ASphereCutsACircleWhoseArcsAndCrossingsLieOnIt) {
  const Point3 centre{1, 2, 3};
  const Quadric f = Sphere(centre, 10, {11, 2, 3});
  // The plane z = 9 cuts the circle of radius 8 about (1, 2, 9).
  const std::vector<SectionBranch> branches =
      SectionOf(f, {0, 0, 9}, {1, 0, 0}, {0, 1, 0}, std::nullopt, 10);
  ASSERT_EQ(branches.size(), 1u);
  const SectionBranch& circle = branches[0];
  EXPECT_TRUE(circle.AtInfinity().empty());
  for (int i = 0; i < 32; ++i) {
    const Point3 x = circle.At(kPi * i / 32);
    EXPECT_NEAR(Norm(Sub(x, {1, 2, 9})), 8, 1e-12);
    EXPECT_NEAR(x[2], 9, 1e-12);
  }
  // x = 5 crosses it at y = 2 ± sqrt(48).
  const Plane cut = Plane::Through({5, 0, 0}, {1, 0, 0});
  std::vector<double> at = circle.Crossings(cut);
  ASSERT_EQ(at.size(), 2u);
  std::vector<double> ys = {circle.At(at[0])[1], circle.At(at[1])[1]};
  std::sort(ys.begin(), ys.end());
  EXPECT_NEAR(ys[0], 2 - std::sqrt(48.0), 1e-12);
  EXPECT_NEAR(ys[1], 2 + std::sqrt(48.0), 1e-12);
  // The arc between them, either way round, lies on the circle; the two
  // ways make up the whole circle (2π·8).
  double length = 0;
  for (const auto& [from, to] : {std::pair{at[0], at[1]}, std::pair{at[1], at[0]}}) {
    for (const RationalQuadratic& piece : circle.Arc(from, to)) {
      EXPECT_GT(piece.w, 0);
      for (int i = 0; i <= 16; ++i) {
        EXPECT_NEAR(Norm(Sub(piece.At(i / 16.0), {1, 2, 9})), 8, 1e-12);
        if (i > 0) length += Norm(Sub(piece.At(i / 16.0), piece.At((i - 1) / 16.0)));
      }
    }
  }
  EXPECT_NEAR(length, 2 * kPi * 8, 0.01);
}

TEST(PlaneSection, HyperbolasHaveTwoPointsAtInfinityAndConesSplitIntoLines) {
  // The cylinder x² − y² = 1 (F = x² − y² − 1 written around (1, 0, 0):
  // F = dx² − dy² + 2·dx) cut by z = 0: a hyperbola.
  Quadric cylinder;
  cylinder.p = {1, 0, 0};
  cylinder.a = {1, 0, 0};
  cylinder.m[0][0] = 1;
  cylinder.m[1][1] = -1;
  const auto hyperbola = SectionOf(cylinder, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, std::nullopt, 2);
  ASSERT_EQ(hyperbola.size(), 1u);
  EXPECT_EQ(hyperbola[0].AtInfinity().size(), 2u);
  for (int i = 1; i < 31; ++i) {
    const Point3 x = hyperbola[0].At(kPi * i / 31 + 0.01);
    if (Norm(x) > 1e6) continue;
    EXPECT_NEAR(x[0] * x[0] - x[1] * x[1], 1, 1e-9 * (1 + Dot(x, x)));
  }
  // The cone x² + y² = z² around (0, 1, 1) cut by x = 0: the lines y = ±z.
  Quadric cone;
  cone.p = {0, 1, 1};
  cone.a = {0, 1, -1};
  cone.m[0][0] = 1;
  cone.m[1][1] = 1;
  cone.m[2][2] = -1;
  const auto lines = SectionOf(cone, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}, std::nullopt, 2);
  ASSERT_EQ(lines.size(), 2u);
  for (const SectionBranch& line : lines) {
    EXPECT_EQ(line.kind(), SectionBranch::Kind::kLine);
    for (double t : {-3.0, 0.5, 2.0}) {
      const Point3 x = line.At(t);
      EXPECT_NEAR(x[0], 0, 1e-12);
      EXPECT_NEAR(std::fabs(x[1]), std::fabs(x[2]), 1e-12);
    }
  }
}

// ---- Whole meshes ----

struct Mesh {
  std::vector<Point3> vertices;
  std::vector<std::array<int, 3>> triangles;
};

// The octahedron on the sphere of radius r, each face split into 4^levels
// (new vertices pushed onto the sphere), wound counter-clockwise outside.
Mesh SphereMesh(double r, int levels) {
  Mesh m;
  m.vertices = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      const Point3 x = Add(m.vertices[a], m.vertices[b]);
      m.vertices.push_back(Scale(x, r / Norm(x)));
      return middle[key] = static_cast<int>(m.vertices.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& t : m.triangles) {
      const int ab = mid(t[0], t[1]);
      const int bc = mid(t[1], t[2]);
      const int ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({ab, t[1], bc});
      next.push_back({ca, bc, t[2]});
      next.push_back({ab, bc, ca});
    }
    m.triangles = next;
  }
  return m;
}

QuadricMesh RadialMesh(const Mesh& m) {
  QuadricMesh q;
  q.vertices = m.vertices;
  q.triangles = m.triangles;
  for (const Point3& v : m.vertices) q.normals.push_back(Scale(v, 1 / Norm(v)));
  return q;
}

// A point of F = 0 near x, by Newton steps along the gradient; the distance
// moved is at least the distance from x to the surface.
Point3 ProjectOnto(const Quadric& f, Point3 x) {
  for (int i = 0; i < 30; ++i) {
    const Point3 g = f.Gradient(x);
    x = Sub(x, Scale(g, f.Value(x) / Dot(g, g)));
  }
  return x;
}

bool InsidePlanes(const std::array<Plane, 3>& planes, const Point3& x, double slack) {
  for (const Plane& p : planes) {
    if (p.Side(x) < -slack) return false;
  }
  return true;
}

// Every cubic of every arc, at its ends and 16 random points: on its
// quadric within the cubic's bound (by projection) and, so projected, inside
// its piece's planes.
void ExpectWithinProvenBound(const QuadricResult& r, double tolerance) {
  EXPECT_LE(r.bound, tolerance);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const QuadricArc& arc : r.arcs) {
    const Quadric& f = r.pieces[arc.triangle].quadric;
    EXPECT_LE(arc.bound, tolerance);
    for (const CubicArc& cubic : arc.cubics) {
      // The ends, and random points between.
      for (int i = 0; i <= 17; ++i) {
        const double t = i == 0 ? 0 : i == 17 ? 1 : unit(random);
        const Point3 x = CubicAt(cubic.b, t);
        const Point3 on = ProjectOnto(f, x);
        ASSERT_LT(std::fabs(f.Value(on)), 1e-9);
        EXPECT_LE(Norm(Sub(on, x)), cubic.bound) << "triangle " << arc.triangle;
        EXPECT_TRUE(InsidePlanes(r.planes[arc.triangle], on, 2 * tolerance))
            << "triangle " << arc.triangle;
      }
    }
  }
}

TEST(QuadricMeshes, ASphereIsReproducedExactlyWithMuFromTheNormals) {
  constexpr double kR = 50;
  for (int levels : {0, 1}) {
    QuadricMesh mesh = RadialMesh(SphereMesh(kR, levels));
    mesh.mu_from_normals = true;
    mesh.sections = 6;
    const double tolerance = 1e-3;
    const QuadricResult r = BuildQuadricMesh(mesh, tolerance, "sphere");
    // Each piece is the sphere itself: μ = 1/r and F = (|X|² − r²)/r.
    for (const QuadricPiece& piece : r.pieces) {
      EXPECT_NEAR(piece.mu, 1 / kR, 1e-12);
      for (const Point3& x : {Point3{3, -7, 20}, Point3{-40, 10, 5}}) {
        EXPECT_NEAR(piece.quadric.Value(x), (Dot(x, x) - kR * kR) / kR, 1e-9);
      }
    }
    for (const QuadricGlue& glue : r.glues) {
      EXPECT_TRUE(glue.conics_coincide);
      EXPECT_LT(glue.worst_normal_angle_deg, 1e-6);  // G1 everywhere
      // The glue plane of two pieces of one sphere through the centre: a
      // great circle.
      EXPECT_NEAR(Dot(glue.plane_normal, mesh.vertices[glue.vertex_a]), 0, 1e-9);
    }
    // Every drawn point on the sphere within the proven bound.
    ASSERT_EQ(r.planes.size(), mesh.triangles.size());
    for (const QuadricArc& arc : r.arcs) {
      for (const CubicArc& cubic : arc.cubics) {
        for (int i = 0; i <= 16; ++i) {
          EXPECT_LE(std::fabs(Norm(CubicAt(cubic.b, i / 16.0)) - kR), cubic.bound);
        }
      }
    }
    ExpectWithinProvenBound(r, tolerance);
    // All faces covered: the pieces' planes tile the sphere (every point in
    // exactly one piece), and every piece has its outline and its sections.
    std::mt19937 random(7);
    std::normal_distribution<double> normal;
    for (int i = 0; i < 2000; ++i) {
      Point3 x{normal(random), normal(random), normal(random)};
      x = Scale(x, kR / Norm(x));
      int inside = 0;
      for (const auto& planes : r.planes) inside += InsidePlanes(planes, x, 0) ? 1 : 0;
      EXPECT_EQ(inside, 1) << x[0] << " " << x[1] << " " << x[2];
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      int outline = 0;
      int sections = 0;
      for (const QuadricArc& arc : r.arcs) {
        if (arc.triangle != static_cast<int>(t)) continue;
        (arc.role == QuadricArc::Role::kOutline ? outline : sections) += 1;
      }
      EXPECT_GE(outline, 3) << t;
      EXPECT_GE(sections, mesh.sections) << t;
    }
  }
}

TEST(QuadricMeshes, MuBendsThePiecesButKeepsTheVerticesAndNormals) {
  constexpr double kR = 50;
  for (double mu : {0.5 / kR, 2 / kR}) {
    QuadricMesh mesh = RadialMesh(SphereMesh(kR, 1));
    mesh.mu = {mu};
    const QuadricResult r = BuildQuadricMesh(mesh, 1e-3, "bent");
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const QuadricPiece& piece = r.pieces[t];
      EXPECT_NEAR(piece.mu, mu, 1e-12);
      for (int k = 0; k < 3; ++k) {
        const Point3& v = mesh.vertices[mesh.triangles[t][k]];
        EXPECT_NEAR(piece.quadric.Value(v), 0, 1e-9);
        const Point3 g = piece.quadric.Gradient(v);
        EXPECT_LT(Norm(Cross(Scale(g, 1 / Norm(g)), mesh.normals[mesh.triangles[t][k]])), 1e-9);
      }
    }
    ExpectWithinProvenBound(r, 1e-3);
  }
}

std::string ErrorOf(const QuadricMesh& mesh) {
  try {
    BuildQuadricMesh(mesh, 1e-3, "q");
  } catch (const ConstructionError& e) {
    return e.what();
  }
  return "(no error)";
}

// A random quadric surface G(X) = XᵀSX + 2b·X + c = 0 through random points:
// a triangulated ellipsoid (closed) or a saddle or bowl over a grid (open),
// turned and moved at random, with G's own unit normals. Those meet every
// triangle's conditions, and with each triangle's μ set to G's (scaled as
// the seed scales F) every piece is G itself: the drawing is checked against
// an exact surface whatever conics its sections are.
struct RandomQuadric {
  QuadricMesh mesh;
  std::array<std::array<double, 3>, 3> s{};
  Point3 b{};
  double c = 0;
  FDSURF_NODISCARD double Value(const Point3& x) const {
    double v = c + 2 * Dot(b, x);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) v += s[i][j] * x[i] * x[j];
    }
    return v;
  }
  FDSURF_NODISCARD Point3 Gradient(const Point3& x) const {
    Point3 g = Scale(b, 2);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) g[i] += 2 * s[i][j] * x[j];
    }
    return g;
  }
};

RandomQuadric MakeRandomQuadric(unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  // A random rotation R (from a random unit quaternion) and shift t.
  double q[4] = {unit(random), unit(random), unit(random), unit(random)};
  const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& x : q) x /= qn;
  const double r[3][3] = {{1 - 2 * (q[2] * q[2] + q[3] * q[3]), 2 * (q[1] * q[2] - q[0] * q[3]),
                           2 * (q[1] * q[3] + q[0] * q[2])},
                          {2 * (q[1] * q[2] + q[0] * q[3]), 1 - 2 * (q[1] * q[1] + q[3] * q[3]),
                           2 * (q[2] * q[3] - q[0] * q[1])},
                          {2 * (q[1] * q[3] - q[0] * q[2]), 2 * (q[2] * q[3] + q[0] * q[1]),
                           1 - 2 * (q[1] * q[1] + q[2] * q[2])}};
  const Point3 shift{20 * unit(random), 20 * unit(random), 20 * unit(random)};
  // In the local frame: an ellipsoid, or z = (κ1·x² + κ2·y²)/2 over a grid.
  const bool closed = seed % 2 == 1;
  double local_s[3][3] = {};
  Point3 local_b{};
  double local_c = 0;
  std::vector<Point3> local_points;
  std::vector<std::array<int, 3>> triangles;
  if (closed) {
    const Point3 axes{40 + 10 * unit(random), 40 + 10 * unit(random), 40 + 10 * unit(random)};
    for (int i = 0; i < 3; ++i) local_s[i][i] = 1 / (axes[i] * axes[i]);
    local_c = -1;
    const Mesh m = SphereMesh(1, 1);
    for (const Point3& v : m.vertices)
      local_points.push_back({axes[0] * v[0], axes[1] * v[1], axes[2] * v[2]});
    triangles = m.triangles;
  } else {
    const double k1 = (0.5 + 0.5 * unit(random)) / 30;
    const double k2 = (seed % 4 == 0 ? 1 : -1) * (0.5 + 0.4 * unit(random)) / 30;
    local_s[0][0] = k1 / 2;
    local_s[1][1] = k2 / 2;
    local_b = {0, 0, -0.5};
    constexpr int kN = 5;
    for (int i = 0; i < kN; ++i) {
      for (int j = 0; j < kN; ++j) {
        const double x = -30 + 15 * i + 3 * unit(random);
        const double y = -30 + 15 * j + 3 * unit(random);
        local_points.push_back({x, y, (k1 * x * x + k2 * y * y) / 2});
      }
    }
    for (int i = 0; i + 1 < kN; ++i) {
      for (int j = 0; j + 1 < kN; ++j) {
        const int v = i * kN + j;
        triangles.push_back({v, v + kN, v + kN + 1});
        triangles.push_back({v, v + kN + 1, v + 1});
      }
    }
  }
  // G(X) = L(Rᵀ(X − t)) with L the local quadric: S = R·Sl·Rᵀ,
  // b = R·bl − S·t, c = cl − 2·bl·(Rᵀt) + tᵀ·S·t.
  RandomQuadric out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 3; ++l) out.s[i][j] += r[i][k] * local_s[k][l] * r[j][l];
      }
    }
  }
  Point3 rt{};
  for (int k = 0; k < 3; ++k) rt[k] = r[0][k] * shift[0] + r[1][k] * shift[1] + r[2][k] * shift[2];
  for (int i = 0; i < 3; ++i) {
    out.b[i] = r[i][0] * local_b[0] + r[i][1] * local_b[1] + r[i][2] * local_b[2];
    for (int j = 0; j < 3; ++j) out.b[i] -= out.s[i][j] * shift[j];
  }
  out.c = local_c - 2 * Dot(local_b, rt);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.c += shift[i] * out.s[i][j] * shift[j];
  }
  out.mesh.triangles = triangles;
  for (const Point3& p : local_points) {
    Point3 x = shift;
    for (int i = 0; i < 3; ++i) x[i] += r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2];
    out.mesh.vertices.push_back(x);
    const Point3 g = out.Gradient(x);
    out.mesh.normals.push_back(Scale(g, 1 / Norm(g)));
  }
  // μ of G scaled as the seed scales F (∇F(P₁) = 2·A₁, |A₁| = 1).
  for (const auto& tri : out.mesh.triangles) {
    const Point3& p0 = out.mesh.vertices[tri[0]];
    const Point3 n =
        Scale(Cross(Sub(out.mesh.vertices[tri[1]], p0), Sub(out.mesh.vertices[tri[2]], p0)), 1);
    const Point3 unit_n = Scale(n, 1 / Norm(n));
    double form = 0;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) form += unit_n[i] * out.s[i][j] * unit_n[j];
    }
    out.mesh.mu.push_back(form * 2 / Norm(out.Gradient(p0)));
  }
  return out;
}

// The largest (distance to G = level, by projection along ∇G) / (the
// cubic's proven bound) over the drawing: ≤ 1 when the bound holds.
double WorstBoundRatio(const RandomQuadric& g, const QuadricResult& r, double level) {
  double worst = 0;
  for (const QuadricArc& arc : r.arcs) {
    for (const CubicArc& cubic : arc.cubics) {
      for (int i = 0; i <= 8; ++i) {
        Point3 x = CubicAt(cubic.b, i / 8.0);
        const Point3 start = x;
        for (int it = 0; it < 30; ++it) {
          const Point3 grad = g.Gradient(x);
          x = Sub(x, Scale(grad, (g.Value(x) - level) / Dot(grad, grad)));
        }
        worst = std::max(worst, Norm(Sub(x, start)) / cubic.bound);
      }
    }
  }
  return worst;
}

TEST(QuadricMeshes, RandomQuadricMeshesKeepTheProvenBoundOnEveryArc) {
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const RandomQuadric g = MakeRandomQuadric(seed);
    const QuadricResult r = BuildQuadricMesh(g.mesh, 1e-3, "random");
    EXPECT_FALSE(r.curves.empty());
    ExpectWithinProvenBound(r, 1e-3);
    // Against G itself, independently of the pieces' own F: every drawn
    // point within its bound of G = 0. The check has teeth: against the
    // neighbouring level set, 3 tolerances away, it fails.
    EXPECT_LE(WorstBoundRatio(g, r, 0), 1) << "seed " << seed;
    const double shifted = 3e-3 * Norm(g.Gradient(g.mesh.vertices[0]));
    EXPECT_GT(WorstBoundRatio(g, r, shifted), 1) << "seed " << seed;
    for (const QuadricGlue& glue : r.glues) EXPECT_TRUE(glue.conics_coincide) << "seed " << seed;
  }
}

TEST(QuadricMeshes, NormalsThatMissTheConditionsAreTurnedToTheNearestCompatibleOnes) {
  for (unsigned seed : {3u, 4u}) {
    RandomQuadric g = MakeRandomQuadric(seed);
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> unit(-1, 1);
    QuadricMesh turned = g.mesh;
    for (Point3& n : turned.normals)
      n = Add(n, {0.01 * unit(random), 0.01 * unit(random), 0.01 * unit(random)});
    EXPECT_NE(ErrorOf(turned).find("the linear conditions are inconsistent"), std::string::npos);
    turned.adjust_normals = true;
    const QuadricResult r = BuildQuadricMesh(turned, 1e-3, "turned");
    // Turned by about what they were tilted (up to 0.01·√3 rad ≈ 1°).
    EXPECT_GT(r.largest_normal_turn_deg, 0.01);
    EXPECT_LT(r.largest_normal_turn_deg, 5);
    ASSERT_EQ(r.normals.size(), turned.normals.size());
  }
}

// The glue curves of two neighbours, each drawn from its own quadric, are
// the same curve within their bounds where the conics coincide.
void ExpectGlueCurvesMeet(const QuadricMesh& mesh, const QuadricResult& r) {
  int checked = 0;
  for (const QuadricGlue& glue : r.glues) {
    if (!glue.conics_coincide) continue;
    const auto outline_of = [&](int t) {
      std::vector<const QuadricArc*> arcs;
      for (const QuadricArc& arc : r.arcs) {
        if (arc.triangle != t || arc.role != QuadricArc::Role::kOutline) continue;
        const int va = mesh.triangles[t][arc.index];
        const int vb = mesh.triangles[t][(arc.index + 1) % 3];
        if (std::minmax(va, vb) == std::minmax(glue.vertex_a, glue.vertex_b)) arcs.push_back(&arc);
      }
      return arcs;
    };
    const auto a = outline_of(glue.triangle_a);
    const auto b = outline_of(glue.triangle_b);
    ASSERT_FALSE(a.empty());
    ASSERT_FALSE(b.empty());
    std::vector<Point3> dense;  // piece b's exact arcs, densely
    double bound_b = 0;
    for (const QuadricArc* arc : b) {
      bound_b = std::max(bound_b, arc->bound);
      for (int i = 0; i <= 400; ++i) dense.push_back(arc->arc.At(i / 400.0));
    }
    for (const QuadricArc* arc : a) {
      for (const CubicArc& cubic : arc->cubics) {
        for (int i = 0; i <= 8; ++i) {
          const Point3 x = CubicAt(cubic.b, i / 8.0);
          // To the polyline through the dense points (its segments' sag is
          // far below the bounds).
          double nearest = 1e300;
          for (std::size_t k = 1; k < dense.size(); ++k) {
            const Point3 d = Sub(dense[k], dense[k - 1]);
            const double len2 = Dot(d, d);
            double s = len2 > 0 ? Dot(Sub(x, dense[k - 1]), d) / len2 : 0;
            s = std::clamp(s, 0.0, 1.0);
            nearest = std::min(nearest, Norm(Sub(x, Add(dense[k - 1], Scale(d, s)))));
          }
          EXPECT_LE(nearest, cubic.bound + 1e-4 * (1 + bound_b));
        }
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(QuadricMeshes, GlueCurvesOfNeighboursMeet) {
  QuadricMesh sphere = RadialMesh(SphereMesh(50, 0));
  sphere.mu_from_normals = true;
  ExpectGlueCurvesMeet(sphere, BuildQuadricMesh(sphere, 1e-3, "sphere"));
  QuadricMesh seed;
  seed.vertices = {{1, 1, 1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}};
  seed.normals = {{1, 1, -1}, {1, 1, 0}, {1, -1, 0}, {-3, 3, 0}};
  seed.triangles = {{0, 1, 2}, {3, 1, 0}};
  seed.free = {{0.5}, {1.5}};
  ExpectGlueCurvesMeet(seed, BuildQuadricMesh(seed, 1e-3, "seed"));
}

// Real meshes nobody here wrote (examples/README.md). Uranium's test sphere
// (Meshlab's icosphere, radius 10, 1,280 triangles, Meshlab's normals):
// drawn within its proven bound of its pieces, and the pieces within 1e-4
// of the sphere (measured 8.7e-5; the normals are turned by 0.68° at most,
// and the vertices carry 6 digits). MatGeom's apple: refused with the turn it
// would need.
QuadricMesh FromFile(const std::string& name) {
  const TriangleMesh file = ReadMeshFile(std::string(FDSURF_EXAMPLES_DIR) + "/" + name);
  QuadricMesh mesh;
  mesh.vertices = file.vertices;
  mesh.normals = file.normals;
  mesh.triangles = file.triangles;
  mesh.mu_from_normals = true;
  mesh.adjust_normals = true;
  return mesh;
}

TEST(QuadricMeshes, ARealSphereMeshIsDrawnOnItsSphere) {
  QuadricMesh mesh = FromFile("uranium-sphere.obj");
  ASSERT_EQ(mesh.triangles.size(), 1280u);
  mesh.sections = 2;
  const QuadricResult r = BuildQuadricMesh(mesh, 1e-3, "uranium");
  EXPECT_LT(r.largest_normal_turn_deg, 1);
  ExpectWithinProvenBound(r, 1e-3);
  for (const QuadricArc& arc : r.arcs) {
    for (const CubicArc& cubic : arc.cubics) {
      for (int i = 0; i <= 8; ++i) EXPECT_NEAR(Norm(CubicAt(cubic.b, i / 8.0)), 10, 1e-4);
    }
  }
}

TEST(QuadricMeshes, ARealMeshFarFromQuadricPiecesIsRefusedWithTheTurnItWouldNeed) {
  QuadricMesh mesh = FromFile("apple.ply");
  mesh.sections = 0;
  try {
    BuildQuadricMesh(mesh, 1e-3, "apple");
    ADD_FAILURE() << "the apple was drawn";
  } catch (const ConstructionError& e) {
    EXPECT_NE(std::string(e.what()).find("the normals would have to turn by up to 89.3 degrees"),
              std::string::npos)
        << e.what();
  }
}

TEST(QuadricMeshes, AFlatRegionIsDrawnAsItsPlane) {
  // Two coplanar triangles with the plane's normal: rank 5, λ₂ and λ₃ free;
  // they default to the plane's (2·A₁·Â_i), not to 0 (a zero gradient).
  QuadricMesh flat;
  flat.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10, 10, 0}};
  flat.normals.assign(4, {0, 0, 1});
  flat.triangles = {{0, 1, 3}, {0, 3, 2}};
  flat.mu_from_normals = true;
  const QuadricResult r = BuildQuadricMesh(flat, 1e-3, "flat");
  for (const QuadricPiece& piece : r.pieces) {
    EXPECT_EQ(piece.solution.rank, 5);
    EXPECT_NEAR(piece.quadric.Value({3, 4, 1}), 2, 1e-12);  // F = 2z
  }
  // The outline only (sections parallel to a plane piece are empty), the
  // shared diagonal once: 5 segments, all in z = 0.
  EXPECT_EQ(r.curves.size(), 5u);
  for (const Curve& c : r.curves) {
    for (const Point3& p : c.g) EXPECT_NEAR(p[2], 0, 1e-12);
  }
}

TEST(QuadricMeshes, RefusesNonManifoldMeshesUnboundedPiecesAndConflictingParameters) {
  // Two octahedra sharing only vertex 0: two fans of triangles there.
  QuadricMesh pinched = RadialMesh(SphereMesh(50, 0));
  pinched.mu_from_normals = true;
  const std::size_t n = pinched.vertices.size();
  for (std::size_t v = 1; v < n; ++v) {
    const Point3 p = pinched.vertices[v];
    pinched.vertices.push_back({100 - p[0], p[1], p[2]});  // mirrored about x = 50
    pinched.normals.push_back(
        {-pinched.normals[v][0], pinched.normals[v][1], pinched.normals[v][2]});
  }
  const std::size_t triangles = pinched.triangles.size();
  for (std::size_t t = 0; t < triangles; ++t) {
    std::array<int, 3> tri = pinched.triangles[t];
    for (int& v : tri) v = v == 0 ? 0 : v + static_cast<int>(n) - 1;
    std::swap(tri[1], tri[2]);  // the mirror reverses the winding
    pinched.triangles.push_back(tri);
  }
  EXPECT_EQ(
      ErrorOf(pinched),
      "vertex 0: its triangles form 2 separate fans that meet only there (the mesh is pinched: "
      "not a manifold)");
  QuadricMesh mesh = RadialMesh(SphereMesh(50, 0));
  mesh.mu_from_normals = true;
  QuadricMesh three = mesh;
  three.triangles.push_back({0, 2, 1});  // a third triangle on the edge 0–2
  EXPECT_EQ(ErrorOf(three),
            "the edge between vertices 0 and 2 belongs to 3 triangles (at most 2: the mesh is not "
            "a manifold)");
  QuadricMesh flipped = mesh;
  std::swap(flipped.triangles[1][0], flipped.triangles[1][1]);
  EXPECT_EQ(ErrorOf(flipped),
            "the edge between vertices 1 and 2: triangles 1 and 5 run along it in the same "
            "direction (inconsistent orientation)");
  QuadricMesh both = mesh;
  both.free.assign(mesh.triangles.size(), {0.0});
  EXPECT_EQ(ErrorOf(both),
            "triangles[0]: give either \"free\" or \"mu\": both choose the one free parameter");
  QuadricMesh sizes = mesh;
  sizes.mu_from_normals = false;
  sizes.mu = {1, 2};
  EXPECT_EQ(ErrorOf(sizes), "\"mu\" needs one value, or one per triangle (8)");
  // The seed's a = −1/8: the glue curve is a hyperbola with the shared
  // vertices on different branches, so the piece runs to infinity.
  QuadricMesh seed;
  seed.vertices = {{1, 1, 1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}};
  seed.normals = {{1, 1, -1}, {1, 1, 0}, {1, -1, 0}, {-3, 3, 0}};
  seed.triangles = {{0, 1, 2}, {3, 1, 0}};
  seed.free = {{-0.125}, {-0.375}};
  EXPECT_EQ(ErrorOf(seed),
            "triangles[0]: the edge from vertex 0 to vertex 1: the quadric's curve in the edge's "
            "trimming plane "
            "does not run from vertex to vertex without passing through infinity (the piece is "
            "unbounded)");
}

}  // namespace
}  // namespace fdsurf::host
