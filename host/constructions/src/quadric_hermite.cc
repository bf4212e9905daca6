// SPDX-License-Identifier: MIT
#include "fdsurf/host/quadric_hermite.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/vec3.h"

namespace fdsurf::host {
namespace {

Point3 Unit(const Point3& a) { return Scale(a, 1 / Norm(a)); }

// The angle in degrees between two lines (directions up to sign).
double LineAngle(const Point3& a, const Point3& b) {
  return std::atan2(Norm(Cross(a, b)), std::fabs(Dot(a, b))) * 180 / std::numbers::pi;
}

// A piece's quadric, vertices and oriented unit normals.
struct PieceMap {
  const Quadric* f;
  std::array<Point3, 3> p;
  std::array<Point3, 3> g;  // oriented unit normals at the vertices
};

}  // namespace

const char* const kQuadricUnknowns[8] = {"a11", "a22", "a33",     "a12",
                                         "a13", "a23", "lambda2", "lambda3"};

double Quadric::Value(const Point3& x) const {
  const Point3 d = Sub(x, p);
  return Form(d, d) + 2 * Dot(a, d);
}

Point3 Quadric::Gradient(const Point3& x) const {
  const Point3 d = Sub(x, p);
  Point3 g{};
  for (int j = 0; j < 3; ++j) {
    g[j] = 2 * a[j];
    for (int k = 0; k < 3; ++k) g[j] += 2 * m[j][k] * d[k];
  }
  return g;
}

double Quadric::Form(const Point3& d, const Point3& e) const {
  double sum = 0;
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 3; ++k) sum += m[j][k] * d[j] * e[k];
  }
  return sum;
}

Quadric QuadricSolution::With(const std::vector<double>& parameters) const {
  std::array<double, 8> x = particular;
  for (std::size_t k = 0; k < null.size() && k < parameters.size(); ++k) {
    for (int i = 0; i < 8; ++i) x[i] += parameters[k] * null[k][i];
  }
  Quadric q;
  q.p = p1;
  q.a = a1;
  q.m[0][0] = x[0];
  q.m[1][1] = x[1];
  q.m[2][2] = x[2];
  q.m[0][1] = q.m[1][0] = x[3] / 2;
  q.m[0][2] = q.m[2][0] = x[4] / 2;
  q.m[1][2] = q.m[2][1] = x[5] / 2;
  return q;
}

namespace {

void CheckTriangle(const std::array<Point3, 3>& p, const std::array<Point3, 3>& n) {
  for (int i = 0; i < 3; ++i) {
    if (!(Norm(n[i]) > 0)) {
      throw ConstructionError("the normal at vertex " + std::to_string(i) + " has zero length");
    }
  }
  const double size =
      std::max({Norm(Sub(p[1], p[0])), Norm(Sub(p[2], p[0])), Norm(Sub(p[2], p[1]))});
  if (!(Norm(Cross(Sub(p[1], p[0]), Sub(p[2], p[0]))) > 1e-12 * size * size)) {
    throw ConstructionError("the triangle is degenerate: its vertices are " +
                            std::string(size == 0 ? "coincident" : "collinear"));
  }
}

// The augmented system [8 unknowns | right-hand side], rows in groups of four
// per vertex P_2, P_3.
using QuadricSystem = double[8][9];

// Conditions (1), (2) of the seed for P_2, P_3 with D = P_i − P_1:
// F(P_i) = 0 and ∂F/∂x_j (P_i) = λ_i·A_i,j, linear in a_jk and λ_i.
void SetUpConditions(const std::array<Point3, 3>& p, const std::array<Point3, 3>& n,
                     QuadricSystem& sys) {
  const Point3& a1 = n[0];
  for (int i = 1; i < 3; ++i) {
    const Point3 d = Sub(p[i], p[0]);
    const Point3 ni = Unit(n[i]);
    double* f = sys[(i - 1) * 4];
    const double row_f[9] = {d[0] * d[0], d[1] * d[1], d[2] * d[2], d[0] * d[1],    d[0] * d[2],
                             d[1] * d[2], 0,           0,           -2 * Dot(a1, d)};
    std::copy(row_f, row_f + 9, f);
    const double gx[9] = {2 * d[0], 0, 0, d[1], d[2], 0, 0, 0, -2 * a1[0]};
    const double gy[9] = {0, 2 * d[1], 0, d[0], 0, d[2], 0, 0, -2 * a1[1]};
    const double gz[9] = {0, 0, 2 * d[2], 0, d[0], d[1], 0, 0, -2 * a1[2]};
    std::copy(gx, gx + 9, sys[(i - 1) * 4 + 1]);
    std::copy(gy, gy + 9, sys[(i - 1) * 4 + 2]);
    std::copy(gz, gz + 9, sys[(i - 1) * 4 + 3]);
    for (int j = 0; j < 3; ++j) sys[(i - 1) * 4 + 1 + j][6 + (i - 1)] = -ni[j];
  }
}

// Reduced row echelon form with partial pivoting, columns in order. Returns
// the rank; pivot_col[r] is the column of row r's pivot.
int ReduceRowEchelon(QuadricSystem& sys, double tol, int (&pivot_col)[8]) {
  int rank = 0;
  for (int col = 0; col < 8 && rank < 8; ++col) {
    int best = rank;
    for (int r = rank + 1; r < 8; ++r) {
      if (std::fabs(sys[r][col]) > std::fabs(sys[best][col])) best = r;
    }
    if (std::fabs(sys[best][col]) <= tol) continue;
    for (int c = 0; c < 9; ++c) std::swap(sys[rank][c], sys[best][c]);
    const double pivot = sys[rank][col];
    for (int c = 0; c < 9; ++c) sys[rank][c] /= pivot;
    for (int r = 0; r < 8; ++r) {
      if (r == rank || sys[r][col] == 0) continue;
      const double k = sys[r][col];
      for (int c = 0; c < 9; ++c) sys[r][c] -= k * sys[rank][c];
    }
    pivot_col[rank++] = col;
  }
  return rank;
}

// Reads the particular solution and the null space off the reduced system.
void ReadSolution(const QuadricSystem& sys, int rank, const int (&pivot_col)[8],
                  QuadricSolution* solution) {
  solution->rank = rank;
  bool is_pivot[8] = {};
  for (int r = 0; r < rank; ++r) {
    is_pivot[pivot_col[r]] = true;
    solution->particular[pivot_col[r]] = sys[r][8];
  }
  for (int col = 0; col < 8; ++col) {
    if (is_pivot[col]) continue;
    std::array<double, 8> v{};
    v[col] = 1;
    for (int r = 0; r < rank; ++r) v[pivot_col[r]] = -sys[r][col];
    solution->free_unknowns.push_back(col);
    solution->null.push_back(v);
  }
}

}  // namespace

QuadricSolution SolveQuadricTriangle(const std::array<Point3, 3>& p,
                                     const std::array<Point3, 3>& n) {
  CheckTriangle(p, n);
  double sys[8][9] = {};
  SetUpConditions(p, n, sys);
  double scale = 0;
  for (auto& row : sys) {
    for (double v : row) scale = std::max(scale, std::fabs(v));
  }
  const double tol = 1e-10 * std::max(scale, 1e-300);
  int pivot_col[8];
  const int rank = ReduceRowEchelon(sys, tol, pivot_col);
  for (int r = rank; r < 8; ++r) {
    if (std::fabs(sys[r][8]) > 1e-9 * std::max(scale, 1.0)) {
      throw ConstructionError(
          "no second-order surface through the vertices has normals parallel to the given "
          "vectors (the linear conditions are inconsistent)");
    }
  }
  QuadricSolution solution;
  solution.p1 = p[0];
  solution.a1 = n[0];
  ReadSolution(sys, rank, pivot_col, &solution);
  return solution;
}

namespace {

// Drawing (docs/constructions.md, row 12): a piece hangs from its
// triangle on the side of its oriented normal N. It is sliced by the
// planes N·(X − A) = h parallel to the triangle; in each slice the quadric
// is a conic, and the piece is its arc on the third vertex's side of the
// glue plane G, between the two points where the slice's line in G meets
// the conic (at h = 0: the shared vertices A, B). The slices run down to
// the depth where those two points merge (the bottom of the glue curve).
struct Slicer {
  std::size_t triangle;
  const Quadric* f;
  Point3 a;
  Point3 n;   // slicing normal (oriented triangle normal)
  Point3 nu;  // glue plane normal
  Point3 l;   // along the slice's line in G
  Point3 k;   // in the slice, ⟂ l, towards the third vertex
  double depth;
};

// The working state of BuildQuadricMesh, filled in by its stages in order.
struct QuadricBuild {
  const QuadricMesh& mesh;
  double tolerance;
  const std::string& origin;
  QuadricResult result;
  std::vector<PieceMap> maps;
  std::vector<Slicer> slicers;
  std::vector<bool> drawn;  // per triangle: whether it has a slicer yet
};

// Narrows [lo, hi] around a minimum of f by golden sections.
template <typename F>
void GoldenSection(const F& f, int iterations, double* lo, double* hi) {
  for (int it = 0; it < iterations; ++it) {
    const double m1 = *lo + (*hi - *lo) * 0.381966;
    const double m2 = *lo + (*hi - *lo) * 0.618034;
    if (f(m1) < f(m2)) {
      *hi = m2;
    } else {
      *lo = m1;
    }
  }
}

void ValidateMesh(const QuadricMesh& mesh) {
  if (mesh.normals.size() != mesh.vertices.size()) {
    throw ConstructionError("there are " + std::to_string(mesh.vertices.size()) + " vertices but " +
                            std::to_string(mesh.normals.size()) + " normals");
  }
  for (std::size_t i = 0; i < mesh.normals.size(); ++i) {
    if (!(Norm(mesh.normals[i]) > 0)) {
      throw ConstructionError("normals[" + std::to_string(i) + "] has zero length");
    }
  }
  if (mesh.triangles.empty()) throw ConstructionError("there are no triangles");
  if (!mesh.free.empty() && mesh.free.size() != mesh.triangles.size()) {
    throw ConstructionError("\"free\" needs one list per triangle");
  }
}

void CheckTriangleIndices(const QuadricMesh& mesh, const std::array<int, 3>& tri,
                          const std::string& name) {
  for (int k = 0; k < 3; ++k) {
    if (tri[k] < 0 || static_cast<std::size_t>(tri[k]) >= mesh.vertices.size()) {
      throw ConstructionError(name + ": vertex " + std::to_string(tri[k]) + " does not exist");
    }
  }
  if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
    throw ConstructionError(name + ": a vertex is repeated");
  }
}

// The note on one piece: its rank, free parameters and the resulting F.
std::string PieceNote(const std::string& origin, const std::string& name, const QuadricPiece& piece,
                      const Point3& a1, int first_vertex) {
  const std::size_t free_count = piece.solution.free_unknowns.size();
  std::string note = origin;
  note += ": " + name;
  note += ": rank " + std::to_string(piece.solution.rank) + "/8";
  if (free_count == 0) {
    note += ", a unique quadric";
  } else {
    note +=
        free_count == 1 ? ": free" : ", degenerate (more than the usual one free parameter): free";
    for (std::size_t k = 0; k < free_count; ++k) {
      note += std::string(k ? "," : "") + " " + kQuadricUnknowns[piece.solution.free_unknowns[k]] +
              " = " + FormatNumber(piece.parameters[k]);
    }
  }
  const auto& m = piece.quadric.m;
  note += "; F = " + FormatNumber(m[0][0]) + "·dx² + " + FormatNumber(m[1][1]) + "·dy² + " +
          FormatNumber(m[2][2]) + "·dz² + " + FormatNumber(2 * m[0][1]) + "·dx·dy + " +
          FormatNumber(2 * m[0][2]) + "·dx·dz + " + FormatNumber(2 * m[1][2]) + "·dy·dz + 2·(" +
          FormatNumber(a1[0]) + "·dx + " + FormatNumber(a1[1]) + "·dy + " + FormatNumber(a1[2]) +
          "·dz), d = X − vertex " + std::to_string(first_vertex);
  return note;
}

// Stage 1: every triangle's quadric, with the free parameters chosen.
void SolvePieces(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const std::string name = "triangles[" + std::to_string(t) + "]";
    CheckTriangleIndices(mesh, tri, name);
    const std::array<Point3, 3> p = {mesh.vertices[tri[0]], mesh.vertices[tri[1]],
                                     mesh.vertices[tri[2]]};
    const std::array<Point3, 3> n = {mesh.normals[tri[0]], mesh.normals[tri[1]],
                                     mesh.normals[tri[2]]};
    QuadricPiece piece;
    try {
      piece.solution = SolveQuadricTriangle(p, n);
    } catch (const ConstructionError& e) {
      throw ConstructionError(name + ": " + e.what());
    }
    const std::size_t free_count = piece.solution.free_unknowns.size();
    if (!mesh.free.empty() && mesh.free[t].size() != free_count) {
      throw ConstructionError(name + ": the system leaves " + std::to_string(free_count) +
                              " free parameter(s), but \"free\" gives " +
                              std::to_string(mesh.free[t].size()));
    }
    piece.parameters = mesh.free.empty() ? std::vector<double>(free_count, 0.0) : mesh.free[t];
    piece.quadric = piece.solution.With(piece.parameters);
    b.result.notes.push_back(PieceNote(b.origin, name, piece, n[0], tri[0]));
    b.result.pieces.push_back(piece);
  }
}

// Stage 2: oriented unit normals, the gradient of each piece's own F.
void OrientPieces(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  b.maps.resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    PieceMap& map = b.maps[t];
    map.f = &b.result.pieces[t].quadric;
    for (int k = 0; k < 3; ++k) {
      map.p[k] = mesh.vertices[mesh.triangles[t][k]];
      const Point3 g = map.f->Gradient(map.p[k]);
      const double size = std::max(1.0, Norm(mesh.normals[mesh.triangles[t][k]]));
      if (!(Norm(g) > 1e-12 * size)) {
        throw ConstructionError("triangles[" + std::to_string(t) +
                                "]: the quadric is singular at vertex " +
                                std::to_string(mesh.triangles[t][k]) +
                                " (zero gradient); choose other free parameters");
      }
      map.g[k] = Unit(g);
    }
  }
}

// The triangle's unit normal, turned to the side its piece's normals point.
Point3 OrientedTriangleNormal(const PieceMap& map) {
  Point3 n = Unit(Cross(Sub(map.p[1], map.p[0]), Sub(map.p[2], map.p[0])));
  if (Dot(n, Add(Add(map.g[0], map.g[1]), map.g[2])) < 0) n = Scale(n, -1);
  return n;
}

// Two pieces around their shared edge a–b, with the planes through the edge
// parametrised by θ: spanned by e and Direction(θ).
struct EdgePair {
  const Quadric& f1;
  const Quadric& f2;
  Point3 e;  // along the edge
  Point3 u;  // u, w: across it
  Point3 w;
  Point3 ga1;  // the pieces' gradients at a
  Point3 ga2;

  EdgePair(const Quadric& first, const Quadric& second, const Point3& a, const Point3& b)
      : f1(first), f2(second), e(Unit(Sub(b, a))), ga1(f1.Gradient(a)), ga2(f2.Gradient(a)) {
    u = Cross(e, {1, 0, 0});
    if (Norm(u) < 0.5) u = Cross(e, {0, 1, 0});
    u = Unit(u);
    w = Cross(e, u);
  }

  FDSURF_NODISCARD Point3 Direction(double theta) const {
    return Add(Scale(u, std::cos(theta)), Scale(w, std::sin(theta)));
  }

  // For the plane through the edge spanned by e and p(θ), both pieces cut
  // conics through a and b; they coincide when the coefficient vectors of
  // F restricted to the plane are proportional (seed 000: the plane through
  // the two shared vertices and a common point of both surfaces).
  FDSURF_NODISCARD double Residual(double theta) const {
    const Point3 p = Direction(theta);
    const double c1[5] = {f1.Form(e, e), 2 * f1.Form(e, p), f1.Form(p, p), Dot(ga1, e),
                          Dot(ga1, p)};
    const double c2[5] = {f2.Form(e, e), 2 * f2.Form(e, p), f2.Form(p, p), Dot(ga2, e),
                          Dot(ga2, p)};
    // sin of the angle between c1 and c2, by Lagrange's identity (no
    // cancellation near 0, so the root is found to full precision).
    double n1 = 0;
    double n2 = 0;
    double cross = 0;
    for (int i = 0; i < 5; ++i) {
      n1 += c1[i] * c1[i];
      n2 += c2[i] * c2[i];
      for (int j = i + 1; j < 5; ++j) {
        const double minor = c1[i] * c2[j] - c1[j] * c2[i];
        cross += minor * minor;
      }
    }
    return std::sqrt(cross / (n1 * n2));
  }
};

// The angle θ of the glue plane: among the roots of the residual, the one
// nearest the reference plane through the edge along the mean oriented
// normal of the two triangles, i.e. "between" them; the triangles' own
// planes are excluded (both conics lie in them only when the pieces are flat
// there). Without a root, the reference itself, and *found is false.
double FindGlueAngle(const EdgePair& pair, const Point3& n1, const Point3& n2, bool* found) {
  const Point3& e = pair.e;
  Point3 reference = Sub(Add(n1, n2), Scale(e, Dot(Add(n1, n2), e)));
  if (Norm(reference) < 1e-9) reference = Cross(e, n1);
  reference = Unit(reference);
  constexpr int kScan = 3600;
  double best_theta = std::atan2(Dot(reference, pair.w), Dot(reference, pair.u));
  *found = false;
  double best_score = -1;
  const auto residual = [&](double theta) { return pair.Residual(theta); };
  std::vector<double> values(kScan);
  for (int i = 0; i < kScan; ++i) values[i] = residual(std::numbers::pi * i / kScan);
  for (int i = 0; i < kScan; ++i) {
    const double prev = values[(i + kScan - 1) % kScan];
    const double next = values[(i + 1) % kScan];
    if (values[i] > prev || values[i] > next) continue;
    // Golden-section refinement of the local minimum.
    double lo = std::numbers::pi * (i - 1) / kScan;
    double hi = std::numbers::pi * (i + 1) / kScan;
    GoldenSection(residual, 80, &lo, &hi);
    const double theta = (lo + hi) / 2;
    if (residual(theta) > 1e-7) continue;
    const Point3 p = pair.Direction(theta);
    const Point3 plane_normal = Cross(e, p);
    // Not a triangle's own plane.
    if (LineAngle(plane_normal, n1) < 1 || LineAngle(plane_normal, n2) < 1) continue;
    const double score = std::fabs(Dot(p, reference));
    if (score > best_score) {
      best_score = score;
      best_theta = theta;
      *found = true;
    }
  }
  return best_theta;
}

// Stage 3: the edges shared by two triangles, and for each the glue plane.
void FindGlues(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  std::map<std::pair<int, int>, std::vector<std::pair<std::size_t, int>>> edges;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      int va = mesh.triangles[t][(k + 1) % 3];
      int vb = mesh.triangles[t][(k + 2) % 3];
      if (va > vb) std::swap(va, vb);
      edges[{va, vb}].emplace_back(t, k);
    }
  }
  for (const auto& [key, users] : edges) {
    if (users.size() > 2) {
      throw ConstructionError("the edge between vertices " + std::to_string(key.first) + " and " +
                              std::to_string(key.second) + " has " + std::to_string(users.size()) +
                              " triangles (at most 2)");
    }
    if (users.size() < 2) continue;
    const std::size_t t1 = users[0].first;
    const std::size_t t2 = users[1].first;
    const EdgePair pair(b.result.pieces[t1].quadric, b.result.pieces[t2].quadric,
                        mesh.vertices[key.first], mesh.vertices[key.second]);
    bool found = false;
    const double theta = FindGlueAngle(pair, OrientedTriangleNormal(b.maps[t1]),
                                       OrientedTriangleNormal(b.maps[t2]), &found);
    QuadricGlue glue;
    glue.triangle_a = static_cast<int>(t1);
    glue.triangle_b = static_cast<int>(t2);
    glue.vertex_a = key.first;
    glue.vertex_b = key.second;
    glue.plane_normal = Unit(Cross(pair.e, pair.Direction(theta)));
    glue.conics_coincide = found;
    b.result.glues.push_back(glue);
  }
}

// The two points where the slice at depth h meets G and the quadric: their
// midpoint and half their distance (false where the slice misses).
bool SliceEnds(const Slicer& sl, double h, Point3* mid, double* half) {
  const Point3 origin_h = Add(sl.a, Scale(sl.n, h));
  const double v0 = -h * Dot(sl.nu, sl.n) / Dot(sl.nu, sl.k);
  const Point3 y = Add(origin_h, Scale(sl.k, v0));
  const double c2 = sl.f->Form(sl.l, sl.l);
  const double c1 = Dot(sl.f->Gradient(y), sl.l);
  const double c0 = sl.f->Value(y);
  if (std::fabs(c2) < 1e-300) return false;
  const double disc = c1 * c1 - 4 * c2 * c0;
  if (disc < 0) return false;
  const double centre = -c1 / (2 * c2);
  *half = std::sqrt(disc) / (2 * std::fabs(c2));
  *mid = Add(y, Scale(sl.l, centre));
  return true;
}

// The depth where the end points merge: where the slice's line in G stops
// meeting the quadric (bisect), or touches it (the half distance has a
// minimum at 0: golden section). -1 where neither happens within 16 edge
// lengths.
double GlueCurveBottom(const Slicer& sl, double size) {
  const double step = size / 64;
  constexpr int kSteps = 64 * 16;
  Point3 mid{};
  double half = 0;
  const auto half_at = [&](double h) { return SliceEnds(sl, h, &mid, &half) ? half : -1.0; };
  double previous = half_at(0);
  double depth = -1;
  for (int i = 1; i <= kSteps && depth < 0; ++i) {
    const double h = step * i;
    const double current = half_at(h);
    if (current < 0) {
      double lo = step * (i - 1);
      double hi = h;
      for (int it = 0; it < 100; ++it) {
        const double m = (lo + hi) / 2;
        (half_at(m) >= 0 ? lo : hi) = m;
      }
      depth = lo;
    } else if (i >= 2 && previous <= current && previous < 0.25 * size) {
      double lo = step * (i - 2);
      double hi = h;
      GoldenSection(half_at, 200, &lo, &hi);
      if (half_at((lo + hi) / 2) <= 1e-6 * size) depth = (lo + hi) / 2;
    }
    previous = current;
  }
  return depth;
}

// Sets up the slicer of triangle t hanging from its edge va–vb, cut off by
// the glue plane with the given normal.
void AddSlicer(QuadricBuild& b, std::size_t t, int va, int vb, const Point3& plane_normal) {
  const QuadricMesh& mesh = b.mesh;
  const Point3 a = mesh.vertices[va];
  Point3 c{};
  for (int k = 0; k < 3; ++k) {
    const int v = mesh.triangles[t][k];
    if (v != va && v != vb) c = mesh.vertices[v];
  }
  Slicer sl{
      t, &b.result.pieces[t].quadric, a, OrientedTriangleNormal(b.maps[t]), plane_normal, {}, {},
      0};
  sl.l = Unit(Cross(sl.n, sl.nu));
  sl.k = Unit(Cross(sl.n, sl.l));
  if (Dot(sl.k, Sub(c, a)) < 0) sl.k = Scale(sl.k, -1);
  const double size = Norm(Sub(mesh.vertices[vb], a));
  double depth = GlueCurveBottom(sl, size);
  if (depth < 0) {
    depth = 2 * size;
    b.result.notes.push_back(
        b.origin + ": triangles[" + std::to_string(t) +
        "]: the piece does not close below its triangle (the glue curve is unbounded); "
        "drawn down to depth " +
        FormatNumber(depth));
  }
  sl.depth = depth;
  b.slicers.push_back(sl);
  b.drawn[t] = true;
}

// Stage 4: a slicer per piece, from its first glued edge, or from its first
// edge along its normal where it has no neighbour.
void SetUpSlicers(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  b.drawn.assign(mesh.triangles.size(), false);
  for (const QuadricGlue& glue : b.result.glues) {
    for (int t : {glue.triangle_a, glue.triangle_b}) {
      if (b.drawn[t]) {
        b.result.notes.push_back(b.origin + ": triangles[" + std::to_string(t) +
                                 "] has more than one glued edge; it is drawn from its first only");
        continue;
      }
      AddSlicer(b, t, glue.vertex_a, glue.vertex_b, glue.plane_normal);
    }
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (b.drawn[t]) continue;
    // No neighbour: the plane through the first edge along the normal.
    const Point3 a = mesh.vertices[mesh.triangles[t][0]];
    const Point3 c = mesh.vertices[mesh.triangles[t][1]];
    AddSlicer(b, t, mesh.triangles[t][0], mesh.triangles[t][1],
              Unit(Cross(Sub(c, a), OrientedTriangleNormal(b.maps[t]))));
  }
}

// An ellipse is walked by its own angle from E2 to E1 through the k side
// (smooth in h and φ). False where the slice's conic is not an ellipse.
bool EllipsePoint(const Slicer& sl, const Point3& mid, double half, double phi, Point3* out) {
  const Point3 y = mid;
  const double qa = sl.f->Form(sl.l, sl.l);
  const double qb = sl.f->Form(sl.l, sl.k);
  const double qc = sl.f->Form(sl.k, sl.k);
  const Point3 grad = sl.f->Gradient(y);
  const double gd = Dot(grad, sl.l);
  const double ge = Dot(grad, sl.k);
  const double det = qa * qc - qb * qb;
  if (!(det > 1e-12 * (qa * qa + qc * qc))) return false;
  const double cu = -(qc * gd - qb * ge) / (2 * det);
  const double cv = -(qa * ge - qb * gd) / (2 * det);
  const double fc = sl.f->Value(Add(y, Add(Scale(sl.l, cu), Scale(sl.k, cv))));
  // Eigen-decomposition of [[qa, qb], [qb, qc]].
  const double angle = 0.5 * std::atan2(2 * qb, qa - qc);
  const double c = std::cos(angle);
  const double sn = std::sin(angle);
  const double l1 = qa * c * c + 2 * qb * c * sn + qc * sn * sn;
  const double l2 = qa * sn * sn - 2 * qb * c * sn + qc * c * c;
  if (!(-fc / l1 > 0 && -fc / l2 > 0)) return false;
  const double r1 = std::sqrt(-fc / l1);
  const double r2 = std::sqrt(-fc / l2);
  // (u, v) = centre + r1·cosψ·(c, sn) + r2·sinψ·(−sn, c).
  const auto to_angle = [&](double u, double v) {
    const double du = u - cu;
    const double dv = v - cv;
    return std::atan2((-sn * du + c * dv) / r2, (c * du + sn * dv) / r1);
  };
  const double start = to_angle(half, 0);    // E2
  double span = to_angle(-half, 0) - start;  // to E1
  const auto v_at = [&](double psi) {
    return cv + r1 * std::cos(psi) * sn + r2 * std::sin(psi) * c;
  };
  if (span <= 0) span += 2 * std::numbers::pi;
  if (v_at(start + span / 2) < 0) span -= 2 * std::numbers::pi;
  const double psi = start + span * phi / std::numbers::pi;
  const double u = cu + r1 * std::cos(psi) * c - r2 * std::sin(psi) * sn;
  *out = Add(y, Add(Scale(sl.l, u), Scale(sl.k, v_at(psi))));
  return true;
}

// Other conics: the ray from the chord's midpoint at angle φ, to its nearest
// crossing with the quadric.
bool RayPoint(const Slicer& sl, const Point3& mid, double phi, Point3* out) {
  const Point3 w = Add(Scale(sl.l, std::cos(phi)), Scale(sl.k, std::sin(phi)));
  const double c2 = sl.f->Form(w, w);
  const double c1 = Dot(sl.f->Gradient(mid), w);
  const double c0 = sl.f->Value(mid);
  double r = -1;
  if (std::fabs(c2) <= 1e-14 * (std::fabs(c1) + std::fabs(c0) + 1e-300)) {
    if (c1 != 0) r = -c0 / c1;
  } else {
    const double disc = c1 * c1 - 4 * c2 * c0;
    if (disc < 0) return false;
    const double q = -(c1 + std::copysign(std::sqrt(disc), c1)) / 2;
    const double r1 = q / c2;
    const double r2 = q != 0 ? c0 / q : r1;
    r = std::min(r1 > 0 ? r1 : 1e300, r2 > 0 ? r2 : 1e300);
    if (r >= 1e300) r = -1;
  }
  if (r < 0) return false;
  *out = Add(mid, Scale(w, r));
  return true;
}

// The point of slice h at angle φ ∈ [0, π] from the end point E2.
bool SlicePoint(const Slicer& sl, double h, double phi, Point3* out) {
  Point3 mid{};
  double half = 0;
  if (!SliceEnds(sl, h, &mid, &half)) {
    // At the bottom the two ends merge into one point.
    if (!SliceEnds(sl, sl.depth, &mid, &half)) return false;
    *out = mid;
    return true;
  }
  if (phi <= 0 || phi >= std::numbers::pi) {
    *out = Add(mid, Scale(sl.l, phi <= 0 ? half : -half));
    return true;
  }
  if (EllipsePoint(sl, mid, half, phi, out)) return true;
  return RayPoint(sl, mid, phi, out);
}

// h_i = depth·(1 − (1 − i/n)²): finer towards the bottom, where the arcs
// shrink like the square root of the remaining depth.
double DepthAt(const Slicer& sl, double x) { return sl.depth * (1 - (1 - x) * (1 - x)); }

Point3 BilinearAt(const std::array<Point3, 4>& c, double x, double y) {
  return Add(Add(Scale(c[0], (1 - x) * (1 - y)), Scale(c[1], x * (1 - y))),
             Add(Scale(c[2], (1 - x) * y), Scale(c[3], x * y)));
}

// One tessellation attempt's output over all pieces.
struct Tessellation {
  std::vector<Patch> patches;
  int missing = 0;
  double worst = 0;
};

// Cuts one piece into n×n bilinear cells, measuring each at its centre and
// edge midpoints; cells with a corner or probe off the surface are counted
// as missing.
void TessellatePiece(const Slicer& sl, int n, const std::string& origin, Tessellation* out) {
  const auto at = [&](double i, double j, Point3* point) {
    return SlicePoint(sl, DepthAt(sl, i / n), std::numbers::pi * j / n, point);
  };
  std::vector<std::vector<Point3>> grid(n + 1, std::vector<Point3>(n + 1));
  std::vector<std::vector<bool>> ok(n + 1, std::vector<bool>(n + 1));
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) ok[i][j] = at(i, j, &grid[i][j]);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      bool covered = ok[i][j] && ok[i + 1][j] && ok[i][j + 1] && ok[i + 1][j + 1];
      const std::array<Point3, 4> c = {grid[i][j], grid[i + 1][j], grid[i][j + 1],
                                       grid[i + 1][j + 1]};
      static const double kProbe[5][2] = {{0.5, 0.5}, {0.5, 0}, {0.5, 1}, {0, 0.5}, {1, 0.5}};
      double deviation = 0;
      for (const auto& probe : kProbe) {
        Point3 exact{};
        if (!covered || !at(i + probe[0], j + probe[1], &exact)) {
          covered = false;
          break;
        }
        deviation = std::max(deviation, Norm(Sub(exact, BilinearAt(c, probe[0], probe[1]))));
      }
      if (!covered) {
        ++out->missing;
        continue;
      }
      out->worst = std::max(out->worst, deviation);
      Patch patch = BezierPatchOf(BilinearSurface(c[0], c[1], c[2], c[3]));
      patch.origin = origin + " triangle " + std::to_string(sl.triangle) + " cell (" +
                     std::to_string(i) + "," + std::to_string(j) + ")";
      out->patches.push_back(patch);
    }
  }
}

// Stage 5: doubles the cells per side until every piece is within tolerance.
void Tessellate(QuadricBuild& b) {
  constexpr int kMaxCells = 256;
  for (int n = 2;; n *= 2) {
    if (n > kMaxCells) {
      throw ConstructionError("the tessellation needs more than " + std::to_string(kMaxCells) +
                              "x" + std::to_string(kMaxCells) + " cells per piece for tolerance " +
                              FormatNumber(b.tolerance));
    }
    Tessellation attempt;
    for (const Slicer& sl : b.slicers) TessellatePiece(sl, n, b.origin, &attempt);
    if (attempt.worst <= b.tolerance) {
      b.result.patches = std::move(attempt.patches);
      b.result.cells_per_side = n;
      b.result.missing_cells = attempt.missing;
      b.result.tessellation_error = attempt.worst;
      break;
    }
  }
  if (b.result.patches.empty()) throw ConstructionError("no piece could be drawn");
}

// Along the glue curve (the end points of piece a's slices), piece b's
// distance (to first order) and the angle between the normals.
void MeasureGlue(const QuadricBuild& b, QuadricGlue& glue) {
  const Slicer* sl = nullptr;
  for (const Slicer& s : b.slicers) {
    if (s.triangle == static_cast<std::size_t>(glue.triangle_a)) sl = &s;
  }
  const Quadric& fa = b.result.pieces[glue.triangle_a].quadric;
  const Quadric& fb = b.result.pieces[glue.triangle_b].quadric;
  double gap = 0;
  for (int i = 0; sl != nullptr && i <= 256; ++i) {
    for (double phi : {0.0, std::numbers::pi}) {
      Point3 x{};
      if (!SlicePoint(*sl, DepthAt(*sl, i / 256.0), phi, &x)) continue;
      const Point3 gb = fb.Gradient(x);
      gap = std::max(gap, std::fabs(fb.Value(x)) / Norm(gb));
      glue.worst_normal_angle_deg =
          std::max(glue.worst_normal_angle_deg, LineAngle(fa.Gradient(x), gb));
    }
  }
  glue.gap = gap;
}

std::string GlueNote(const std::string& origin, const QuadricGlue& glue) {
  std::string note =
      origin + ": glue triangles " + std::to_string(glue.triangle_a) + " and " +
      std::to_string(glue.triangle_b) + " along vertices " + std::to_string(glue.vertex_a) + "-" +
      std::to_string(glue.vertex_b) + ": plane with normal (" + FormatNumber(glue.plane_normal[0]) +
      ", " + FormatNumber(glue.plane_normal[1]) + ", " + FormatNumber(glue.plane_normal[2]) + "), ";
  if (!glue.conics_coincide) {
    note +=
        "no plane where both pieces cut the same conic (gap up to " + FormatNumber(glue.gap) + ")";
  } else if (glue.worst_normal_angle_deg <= 1e-6) {
    note += "tangent-plane continuous (G1)";
  } else {
    note += "only continuous (C0): the normals differ by up to " +
            FormatNumber(glue.worst_normal_angle_deg) + " degrees (gap " + FormatNumber(glue.gap) +
            ")";
  }
  return note;
}

// Stage 6: how well each glued pair joins (C0 or G1), and the summary note.
void ReportJoins(QuadricBuild& b) {
  QuadricResult& result = b.result;
  for (QuadricGlue& glue : result.glues) {
    MeasureGlue(b, glue);
    result.notes.push_back(GlueNote(b.origin, glue));
  }
  result.notes.push_back(b.origin + ": tessellated into " + std::to_string(result.patches.size()) +
                         " bilinear patches (" + std::to_string(result.cells_per_side) + "x" +
                         std::to_string(result.cells_per_side) + " cells per piece" +
                         (result.missing_cells > 0
                              ? ", " + std::to_string(result.missing_cells) +
                                    " cells left out where a slice misses the surface"
                              : std::string()) +
                         "), largest sampled deviation " + FormatNumber(result.tessellation_error) +
                         " (tolerance " + FormatNumber(b.tolerance) + ")");
}

}  // namespace

QuadricResult BuildQuadricMesh(const QuadricMesh& mesh, double tolerance,
                               const std::string& origin) {
  ValidateMesh(mesh);
  QuadricBuild build{mesh, tolerance, origin, {}, {}, {}, {}};
  SolvePieces(build);
  OrientPieces(build);
  FindGlues(build);
  SetUpSlicers(build);
  Tessellate(build);
  ReportJoins(build);
  return std::move(build.result);
}

}  // namespace fdsurf::host
