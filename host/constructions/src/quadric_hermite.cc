// SPDX-License-Identifier: MIT
#include "fdsurf/host/quadric_hermite.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/vec3.h"
#include "quadric_pieces.h"

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

// The working state of BuildQuadricMesh, filled in by its stages in order.
struct QuadricBuild {
  const QuadricMesh& mesh;
  double tolerance;
  const std::string& origin;
  QuadricResult result;
  std::vector<PieceMap> maps;
  /// Per triangle and edge k (vertex k to k + 1): the neighbour across it
  /// (−1 on the boundary) and its glue (index into result.glues, or −1).
  std::vector<std::array<int, 3>> neighbour;
  std::vector<std::array<int, 3>> glue_of;
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
  if (mesh.mu.size() > 1 && mesh.mu.size() != mesh.triangles.size()) {
    throw ConstructionError("\"mu\" needs one value, or one per triangle (" +
                            std::to_string(mesh.triangles.size()) + ")");
  }
  if (mesh.sections < 0 || mesh.sections > 1000) {
    throw ConstructionError("\"sections\" must be between 0 and 1000");
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
  note += "; mu = " + FormatNumber(piece.mu);
  const auto& m = piece.quadric.m;
  // Terms with their own signs; coefficients below 1e-12 of the largest are
  // rounding (a sphere's cross terms come out as 1e-18) and left out.
  const double terms[9] = {m[0][0],     m[1][1],   m[2][2],   2 * m[0][1], 2 * m[0][2],
                           2 * m[1][2], 2 * a1[0], 2 * a1[1], 2 * a1[2]};
  static const char* const kNames[9] = {"dx²",   "dy²", "dz²", "dx·dy", "dx·dz",
                                        "dy·dz", "dx",  "dy",  "dz"};
  double largest = 0;
  for (double v : terms) largest = std::max(largest, std::fabs(v));
  std::string f;
  for (int k = 0; k < 9; ++k) {
    if (std::fabs(terms[k]) <= 1e-12 * largest) continue;
    f += f.empty() ? (terms[k] < 0 ? "-" : "") : (terms[k] < 0 ? " - " : " + ");
    f += FormatNumber(std::fabs(terms[k])) + "·" + kNames[k];
  }
  note += "; F = " + (f.empty() ? std::string("0") : f) + ", d = X − vertex " +
          std::to_string(first_vertex);
  return note;
}

// The free unknowns' values when "free" does not give them: 0 for the
// quadric's coefficients (the seed's choice), and for a free λ_i (a flat
// triangle whose normals are parallel leaves them free) the value of the
// plane F = 2·A₁·D, whose gradient 2·A₁ is λ_i·Â_i: λ_i = 2·A₁·Â_i. Zero
// there would make the gradient vanish at that vertex.
std::vector<double> DefaultFree(const QuadricSolution& solution, const std::array<Point3, 3>& n) {
  std::vector<double> values;
  for (int unknown : solution.free_unknowns) {
    values.push_back(unknown >= 6 ? 2 * Dot(n[0], Unit(n[unknown - 5])) : 0.0);
  }
  return values;
}

// μ from the normals: |A₁| times the mean over the edges of the normal
// curvature (g_i − g_j)·(P_i − P_j)/|P_i − P_j|², 1/r on a sphere of radius r.
double MuFromNormals(const std::array<Point3, 3>& p, const std::array<Point3, 3>& n) {
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const Point3 d = Sub(p[(k + 1) % 3], p[k]);
    sum += Dot(Sub(Unit(n[(k + 1) % 3]), Unit(n[k])), d) / Dot(d, d);
  }
  return Norm(n[0]) * sum / 3;
}

// Replaces the L² part of F: M ← M + (μ − nᵀMn)·nnᵀ (F and F + c·L² meet
// the same conditions, so this stays a solution).
void SetMu(double mu, const Point3& n, Quadric* f) {
  const double current = f->Form(n, n);
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 3; ++k) f->m[j][k] += (mu - current) * n[j] * n[k];
  }
}

// Stage 1: every triangle's quadric, with the free parameters or μ chosen.
void SolvePieces(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  const bool mu_given = !mesh.mu.empty() || mesh.mu_from_normals;
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
    if (mu_given && !mesh.free.empty() && free_count == 1) {
      throw ConstructionError(name +
                              ": give either \"free\" or \"mu\": both choose the one free "
                              "parameter");
    }
    piece.parameters = mesh.free.empty() ? DefaultFree(piece.solution, n) : mesh.free[t];
    piece.quadric = piece.solution.With(piece.parameters);
    piece.plane_normal = Unit(Cross(Sub(p[1], p[0]), Sub(p[2], p[0])));
    if (mu_given) {
      const double mu =
          mesh.mu_from_normals ? MuFromNormals(p, n) : mesh.mu[mesh.mu.size() == 1 ? 0 : t];
      SetMu(mu, piece.plane_normal, &piece.quadric);
    }
    piece.mu = piece.quadric.Form(piece.plane_normal, piece.plane_normal);
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

// The angle θ of the glue plane: the reference plane through the edge along
// `along`, the mean of the given normals at its ends (or, where that lies
// along the edge, the mean oriented normal of the two triangles), when both
// pieces cut the same conic there (always when they are the same quadric, as on a sphere);
// else, among the roots of the residual, the one nearest the reference,
// i.e. "between" them. The triangles' own planes are excluded (both conics
// lie in them only when the pieces are flat there). Without a root, the
// reference itself, and *found is false.
double FindGlueAngle(const EdgePair& pair, const Point3& along, const Point3& n1, const Point3& n2,
                     bool* found) {
  const Point3& e = pair.e;
  Point3 reference = Sub(along, Scale(e, Dot(along, e)));
  if (Norm(reference) < 1e-9 * Norm(along)) {
    reference = Sub(Add(n1, n2), Scale(e, Dot(Add(n1, n2), e)));
  }
  if (Norm(reference) < 1e-9) reference = Cross(e, n1);
  reference = Unit(reference);
  const auto own_plane = [&](double theta) {
    const Point3 plane_normal = Cross(e, pair.Direction(theta));
    return LineAngle(plane_normal, n1) < 1 || LineAngle(plane_normal, n2) < 1;
  };
  const double reference_theta = std::atan2(Dot(reference, pair.w), Dot(reference, pair.u));
  const auto residual = [&](double theta) { return pair.Residual(theta); };
  *found = residual(reference_theta) <= 1e-12 && !own_plane(reference_theta);
  if (*found) return reference_theta;
  constexpr int kScan = 3600;
  double best_theta = reference_theta;
  double best_score = -1;
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
    if (residual(theta) > 1e-7 || own_plane(theta)) continue;
    const double score = std::fabs(Dot(pair.Direction(theta), reference));
    if (score > best_score) {
      best_score = score;
      best_theta = theta;
      *found = true;
    }
  }
  return best_theta;
}

std::string EdgeName(int va, int vb) {
  return "the edge between vertices " + std::to_string(va) + " and " + std::to_string(vb);
}

// (lower vertex, higher vertex) -> (triangle, edge k) of the edge's users.
using EdgeUsers = std::map<std::pair<int, int>, std::vector<std::pair<int, int>>>;

EdgeUsers EdgeUsersOf(const QuadricMesh& mesh) {
  EdgeUsers edges;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int va = mesh.triangles[t][k];
      const int vb = mesh.triangles[t][(k + 1) % 3];
      edges[{std::min(va, vb), std::max(va, vb)}].emplace_back(static_cast<int>(t), k);
    }
  }
  return edges;
}

// Every vertex's triangles must form one fan, joined through the edges at
// the vertex: two fans meeting at a point pinch the surface there.
void CheckVertexFans(const QuadricMesh& mesh, const EdgeUsers& edges) {
  // Per vertex, a union-find over its triangles.
  std::vector<std::map<int, int>> parent(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int v : mesh.triangles[t]) parent[v][static_cast<int>(t)] = static_cast<int>(t);
  }
  const auto find = [&](std::map<int, int>& p, int x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  };
  for (const auto& [key, users] : edges) {
    if (users.size() != 2) continue;
    for (int v : {key.first, key.second}) {
      parent[v][find(parent[v], users[0].first)] = find(parent[v], users[1].first);
    }
  }
  for (std::size_t v = 0; v < parent.size(); ++v) {
    int fans = 0;
    for (const auto& [t, up] : parent[v]) fans += t == up ? 1 : 0;
    if (fans > 1) {
      throw ConstructionError("vertex " + std::to_string(v) + ": its triangles form " +
                              std::to_string(fans) +
                              " separate fans that meet only there (the mesh is pinched: not a "
                              "manifold)");
    }
  }
}

// Before anything is solved: every edge in at most two triangles, run in
// opposite directions by them, and every vertex's triangles one fan.
void CheckTopology(const QuadricMesh& mesh) {
  const EdgeUsers edges = EdgeUsersOf(mesh);
  for (const auto& [key, users] : edges) {
    if (users.size() > 2) {
      throw ConstructionError(EdgeName(key.first, key.second) + " belongs to " +
                              std::to_string(users.size()) +
                              " triangles (at most 2: the mesh is not a manifold)");
    }
  }
  for (const auto& [key, users] : edges) {
    if (users.size() == 2 && mesh.triangles[users[0].first][users[0].second] ==
                                 mesh.triangles[users[1].first][users[1].second]) {
      throw ConstructionError(EdgeName(key.first, key.second) + ": triangles " +
                              std::to_string(users[0].first) + " and " +
                              std::to_string(users[1].first) +
                              " run along it in the same direction (inconsistent orientation)");
    }
  }
  CheckVertexFans(mesh, edges);
}

// Stage 3: for each shared edge the glue plane (the topology was checked
// first).
void FindGlues(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  const EdgeUsers edges = EdgeUsersOf(mesh);
  b.neighbour.assign(mesh.triangles.size(), {-1, -1, -1});
  b.glue_of.assign(mesh.triangles.size(), {-1, -1, -1});
  for (const auto& [key, users] : edges) {
    if (users.size() < 2) continue;
    const auto [t1, k1] = users[0];
    const auto [t2, k2] = users[1];
    b.neighbour[t1][k1] = t2;
    b.neighbour[t2][k2] = t1;
    const EdgePair pair(b.result.pieces[t1].quadric, b.result.pieces[t2].quadric,
                        mesh.vertices[key.first], mesh.vertices[key.second]);
    bool found = false;
    const Point3 along = Add(Unit(mesh.normals[key.first]), Unit(mesh.normals[key.second]));
    const double theta = FindGlueAngle(pair, along, OrientedTriangleNormal(b.maps[t1]),
                                       OrientedTriangleNormal(b.maps[t2]), &found);
    QuadricGlue glue;
    glue.triangle_a = std::min(t1, t2);
    glue.triangle_b = std::max(t1, t2);
    glue.vertex_a = key.first;
    glue.vertex_b = key.second;
    glue.plane_normal = Unit(Cross(pair.e, pair.Direction(theta)));
    glue.conics_coincide = found;
    b.glue_of[t1][k1] = b.glue_of[t2][k2] = static_cast<int>(b.result.glues.size());
    b.result.glues.push_back(glue);
  }
}

// Stage 4: each piece's three trimming planes: the glue plane of a shared
// edge; on the boundary the plane through the edge along the triangle's
// normal (the piece's normals can lie in the triangle's plane, as in the
// seed's example). Oriented towards the third vertex.
void SetUpPlanes(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  b.result.planes.resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const PieceMap& map = b.maps[t];
    for (int k = 0; k < 3; ++k) {
      const Point3& a = map.p[k];
      const Point3& c = map.p[(k + 2) % 3];
      const Point3 e = Unit(Sub(map.p[(k + 1) % 3], a));
      Point3 normal{};
      if (b.glue_of[t][k] >= 0) {
        normal = b.result.glues[b.glue_of[t][k]].plane_normal;
      } else {
        normal = Unit(Cross(e, OrientedTriangleNormal(map)));
      }
      Plane plane = Plane::Through(a, normal);
      const double side = plane.Side(c);
      const double size = Norm(Sub(c, a)) + Norm(Sub(map.p[(k + 1) % 3], a));
      if (std::fabs(side) <= 1e-9 * size) {
        throw ConstructionError("triangles[" + std::to_string(t) + "]: the trimming plane of " +
                                EdgeName(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]) +
                                " passes through the triangle's third vertex");
      }
      if (side < 0) plane = Plane::Through(a, Scale(normal, -1));
      b.result.planes[t][k] = plane;
    }
  }
}

// Stage 5: every piece drawn; a shared edge's outline goes to the drawing
// once, from the lower-numbered triangle.
void DrawPieces(QuadricBuild& b) {
  const QuadricMesh& mesh = b.mesh;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    internal::PieceInput in;
    in.f = &b.result.pieces[t].quadric;
    in.triangle = static_cast<int>(t);
    in.vertex_ids = mesh.triangles[t];
    in.p = b.maps[t].p;
    in.planes = b.result.planes[t];
    in.n = b.result.pieces[t].plane_normal;
    in.sections = mesh.sections;
    in.tolerance = b.tolerance;
    std::vector<QuadricArc> arcs;
    try {
      arcs = internal::DrawPiece(in);
    } catch (const ConstructionError& e) {
      throw ConstructionError(std::string("triangles[") + std::to_string(t) + "]: " + e.what());
    }
    for (QuadricArc& arc : arcs) {
      const int other = arc.role == QuadricArc::Role::kOutline ? b.neighbour[t][arc.index] : -1;
      arc.drawn = other < 0 || other > static_cast<int>(t);
      b.result.bound = std::max(b.result.bound, arc.bound);
      if (arc.drawn) {
        const std::string what = arc.role == QuadricArc::Role::kOutline
                                     ? " outline " + std::to_string(mesh.triangles[t][arc.index]) +
                                           "-" +
                                           std::to_string(mesh.triangles[t][(arc.index + 1) % 3])
                                     : " section " + std::to_string(arc.index);
        for (const CubicArc& cubic : arc.cubics) {
          Curve curve;
          curve.basis = Basis::kBezier;
          curve.g = cubic.b;
          curve.origin = b.origin + " triangle " + std::to_string(t) + what;
          b.result.curves.push_back(curve);
        }
      }
      b.result.arcs.push_back(std::move(arc));
    }
  }
}

// Along piece a's outline on the glue's edge, piece b's distance (to first
// order) and the angle between the normals.
void MeasureGlue(const QuadricBuild& b, QuadricGlue& glue) {
  const Quadric& fa = b.result.pieces[glue.triangle_a].quadric;
  const Quadric& fb = b.result.pieces[glue.triangle_b].quadric;
  int edge = -1;
  for (int k = 0; k < 3; ++k) {
    if (b.glue_of[glue.triangle_a][k] >= 0 &&
        &b.result.glues[b.glue_of[glue.triangle_a][k]] == &glue) {
      edge = k;
    }
  }
  double gap = 0;
  for (const QuadricArc& arc : b.result.arcs) {
    if (arc.triangle != glue.triangle_a || arc.role != QuadricArc::Role::kOutline ||
        arc.index != edge) {
      continue;
    }
    for (int i = 0; i <= 64; ++i) {
      const Point3 x = arc.arc.At(i / 64.0);
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
  std::size_t outlines = 0;
  std::size_t sections = 0;
  for (const QuadricArc& arc : result.arcs) {
    if (!arc.drawn) continue;
    (arc.role == QuadricArc::Role::kOutline ? outlines : sections) += 1;
  }
  result.notes.push_back(b.origin + ": " + std::to_string(result.pieces.size()) +
                         " pieces drawn as " + std::to_string(result.curves.size()) +
                         " cubic curves (" + std::to_string(outlines) + " outline and " +
                         std::to_string(sections) + " section conic arcs); every point within " +
                         FormatNumber(result.bound) + " of its quadric piece, proven (tolerance " +
                         FormatNumber(b.tolerance) + ")");
}

}  // namespace

namespace {

// The mesh's edges, each once, as (lower, higher) vertex index.
std::vector<std::pair<int, int>> EdgesOf(const QuadricMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  std::map<std::pair<int, int>, int> seen;
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::pair<int, int> key(std::min(tri[k], tri[(k + 1) % 3]),
                                    std::max(tri[k], tri[(k + 1) % 3]));
      if (seen.emplace(key, 0).second) edges.push_back(key);
    }
  }
  return edges;
}

// The edge rows B of N's equations (g_i + g_j)·u_ij = 0 (u_ij the unit edge
// direction, so that every edge weighs the same), applied by conjugate
// gradients to find y with (B·Bᵀ)·y = B·a: then a − Bᵀ·y is the nearest
// field in N to a. Returns Bᵀ·y, and in *residual the largest |B·(a − Bᵀ·y)|
// per edge (0 up to rounding once converged).
std::vector<Point3> ProjectionCorrection(const QuadricMesh& mesh, const std::vector<Point3>& a,
                                         double* residual) {
  const std::vector<std::pair<int, int>> edges = EdgesOf(mesh);
  std::vector<Point3> dir;
  dir.reserve(edges.size());
  for (const auto& [i, j] : edges) dir.push_back(Unit(Sub(mesh.vertices[j], mesh.vertices[i])));
  const auto transpose_times = [&](const std::vector<double>& y) {  // Bᵀ·y
    std::vector<Point3> x(a.size(), Point3{0, 0, 0});
    for (std::size_t r = 0; r < edges.size(); ++r) {
      x[edges[r].first] = Add(x[edges[r].first], Scale(dir[r], y[r]));
      x[edges[r].second] = Add(x[edges[r].second], Scale(dir[r], y[r]));
    }
    return x;
  };
  const auto times = [&](const std::vector<Point3>& x) {  // B·x
    std::vector<double> out(edges.size());
    for (std::size_t r = 0; r < edges.size(); ++r) {
      out[r] = Dot(Add(x[edges[r].first], x[edges[r].second]), dir[r]);
    }
    return out;
  };
  // Conjugate gradients. The floor is relative to the start and absolute:
  // rows are unit-scaled, so 1e-14 per edge is rounding, and running on
  // below it only amplifies rounding (normals already compatible start
  // there).
  std::vector<double> y(edges.size(), 0.0);
  std::vector<double> r = times(a);
  std::vector<double> d = r;
  double rr = 0;
  for (double v : r) rr += v * v;
  const double floor = std::max(1e-30 * rr, 1e-28 * static_cast<double>(edges.size()));
  for (std::size_t it = 0; it < 20 * edges.size() + 100 && rr > floor; ++it) {
    const std::vector<double> ad = times(transpose_times(d));
    double dad = 0;
    for (std::size_t k = 0; k < d.size(); ++k) dad += d[k] * ad[k];
    if (!(dad > 0)) break;
    const double alpha = rr / dad;
    double next = 0;
    for (std::size_t k = 0; k < d.size(); ++k) {
      y[k] += alpha * d[k];
      r[k] -= alpha * ad[k];
      next += r[k] * r[k];
    }
    for (std::size_t k = 0; k < d.size(); ++k) d[k] = r[k] + (next / rr) * d[k];
    rr = next;
  }
  // What is left of B·g, g = a − Bᵀ·y: 0 once the projection has converged.
  std::vector<Point3> g = a;
  std::vector<Point3> correction = transpose_times(y);
  for (std::size_t v = 0; v < g.size(); ++v) g[v] = Sub(g[v], correction[v]);
  *residual = 0;
  for (double left : times(g)) *residual = std::max(*residual, std::fabs(left));
  return correction;
}

// The seed's conditions on a triangle have a solution only when its normals
// are compatible (docs/constructions.md, row 12, "Compatible normals"): for
// a quadric, F(P_j) − F(P_i) = ½(∇F(P_i) + ∇F(P_j))·e_ij exactly
// (e_ij = P_j − P_i), so on every edge λ_i·A_i·e_ij + λ_j·A_j·e_ij = 0, three
// equations for the triangle's two free λ. Over a mesh whose every closed
// path bounds triangles, that holds on every triangle exactly when there are
// vectors g_v ∥ A_v, none zero, with (g_i + g_j)·e_ij = 0 on every edge: a
// linear space N of vector fields on the vertices. The nearest field in N to
// the unit normals, normalised, is compatible; it is refused when it turns a
// normal by more than max_turn_deg or vanishes at a vertex.
std::vector<Point3> CompatibleNormals(const QuadricMesh& mesh, double max_turn_deg,
                                      double* largest_turn_deg) {
  std::vector<Point3> a;
  a.reserve(mesh.normals.size());
  for (const Point3& n : mesh.normals) a.push_back(Unit(n));
  double residual = 0;
  const std::vector<Point3> correction = ProjectionCorrection(mesh, a, &residual);
  // Thin triangles make B·Bᵀ ill-conditioned; a projection that stopped
  // short is said so, not passed on to be refused as "inconsistent".
  const bool converged = residual <= 1e-9;
  const std::string unconverged =
      converged ? ""
                : " (the projection stopped short, with " + FormatNumber(residual, 3) +
                      " left per edge: thin triangles make it ill-conditioned)";
  std::vector<Point3> g(a.size());
  *largest_turn_deg = 0;
  double total_turn = 0;
  for (std::size_t v = 0; v < a.size(); ++v) {
    g[v] = Sub(a[v], correction[v]);
    if (!(Norm(g[v]) > 1e-6)) {
      throw ConstructionError("vertex " + std::to_string(v) +
                              ": no compatible normal near the given one (the nearest field of "
                              "compatible normals vanishes there)");
    }
    g[v] = Unit(g[v]);
    *largest_turn_deg = std::max(*largest_turn_deg, LineAngle(g[v], a[v]));
    total_turn += LineAngle(g[v], a[v]);
  }
  if (*largest_turn_deg > max_turn_deg) {
    throw ConstructionError(
        "the normals would have to turn by up to " + FormatNumber(*largest_turn_deg, 3) +
        " degrees (" + FormatNumber(total_turn / static_cast<double>(a.size()), 3) +
        " on average) for every triangle's conditions to have a solution" + unconverged +
        "; more than " + FormatNumber(max_turn_deg) +
        " changes the surface, so it is refused (these vertices do not lie near a surface whose "
        "pieces are quadrics meeting this way: see docs/constructions.md, \"Compatible normals\")");
  }
  if (!converged) {
    throw ConstructionError("the nearest compatible normals could not be found" + unconverged);
  }
  return g;
}

}  // namespace

QuadricResult BuildQuadricMesh(const QuadricMesh& mesh_in, double tolerance,
                               const std::string& origin) {
  ValidateMesh(mesh_in);
  if (!(tolerance > 0)) throw ConstructionError("the tolerance must be positive");
  for (std::size_t t = 0; t < mesh_in.triangles.size(); ++t) {
    CheckTriangleIndices(mesh_in, mesh_in.triangles[t], "triangles[" + std::to_string(t) + "]");
  }
  CheckTopology(mesh_in);
  QuadricMesh mesh = mesh_in;
  double turn = 0;
  if (mesh_in.adjust_normals) {
    mesh.normals = CompatibleNormals(mesh_in, mesh_in.max_normal_turn_deg, &turn);
  }
  QuadricBuild build{mesh, tolerance, origin, {}, {}, {}, {}};
  if (mesh_in.adjust_normals) {
    build.result.normals = mesh.normals;
    build.result.largest_normal_turn_deg = turn;
    build.result.notes.push_back(
        turn < 1e-9 ? origin + ": the normals are compatible as given"
                    : origin + ": normals turned by up to " + FormatNumber(turn) +
                          " degrees so that every triangle's conditions have a solution");
  }
  SolvePieces(build);
  OrientPieces(build);
  FindGlues(build);
  SetUpPlanes(build);
  DrawPieces(build);
  ReportJoins(build);
  return std::move(build.result);
}

}  // namespace fdsurf::host
