// SPDX-License-Identifier: MIT
#include "fdsurf/host/constructions.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "fdsurf/host/reference.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/vec3.h"

namespace fdsurf::host {
namespace {

Poly Multiply(const Poly& a, const Poly& b) {
  Poly product(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) product[i + j] += a[i] * b[j];
  }
  return product;
}

// The cubic Hermite blending functions in ascending powers of w.
const Poly kH0 = {1, 0, -3, 2};
const Poly kH1 = {0, 0, 3, -2};
const Poly kH2 = {0, 1, -2, 1};
const Poly kH3 = {0, 0, -1, 1};

void Grow(PolySurface* surface, std::size_t rows, std::size_t cols) {
  const std::size_t old_cols = surface->c.empty() ? 0 : surface->c[0].size();
  const std::size_t new_cols = std::max(cols, old_cols);
  if (surface->c.size() < rows) surface->c.resize(rows);
  for (auto& row : surface->c) row.resize(new_cols, Point3{});
}

// surface += k · a(s) · p(t)
void AddOuter(const VecPoly& a, const Poly& p, double k, PolySurface* surface) {
  Grow(surface, a.size(), p.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < p.size(); ++j) {
      surface->c[i][j] = Add(surface->c[i][j], Scale(a[i], k * p[j]));
    }
  }
}

// surface += k · p(s) · a(t)
void AddOuter(const Poly& p, const VecPoly& a, double k, PolySurface* surface) {
  Grow(surface, p.size(), a.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = 0; j < a.size(); ++j) {
      surface->c[i][j] = Add(surface->c[i][j], Scale(a[j], k * p[i]));
    }
  }
}

// surface += k · p(s) · q(t) · point
void AddOuter(const Poly& p, const Poly& q, const Point3& point, double k, PolySurface* surface) {
  Grow(surface, p.size(), q.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = 0; j < q.size(); ++j) {
      surface->c[i][j] = Add(surface->c[i][j], Scale(point, k * p[i] * q[j]));
    }
  }
}

// Power coefficients a[0..3] (ascending) to the 4 Bézier control values.
std::array<Point3, 4> PowerToBezier(const std::array<Point3, 4>& a) {
  return {a[0], Add(a[0], Scale(a[1], 1.0 / 3)),
          Add(Add(a[0], Scale(a[1], 2.0 / 3)), Scale(a[2], 1.0 / 3)),
          Add(Add(a[0], a[1]), Add(a[2], a[3]))};
}

double Falling(std::size_t n, int k) {
  double f = 1;
  for (int i = 0; i < k; ++i) f *= static_cast<double>(n) - i;
  return f;
}

double Binomial(std::size_t n, std::size_t k) {
  double b = 1;
  for (std::size_t i = 1; i <= k; ++i)
    b = b * static_cast<double>(n - k + i) / static_cast<double>(i);
  return b;
}

// max over [0,1]² and the coordinates of |∂^a_s ∂^b_t surface|, bounded by
// the largest Bernstein coefficient of the derivative (the Bernstein basis
// is non-negative and sums to 1, so the polynomial lies within its
// coefficients' range).
double DerivativeBound(const PolySurface& surface, int a, int b) {
  const std::size_t rows = surface.c.size();
  const std::size_t cols = surface.c[0].size();
  if (rows <= static_cast<std::size_t>(a) || cols <= static_cast<std::size_t>(b)) return 0;
  const std::size_t n = rows - a - 1;  // degrees of the derivative
  const std::size_t m = cols - b - 1;
  double worst = 0;
  for (int c = 0; c < 3; ++c) {
    for (std::size_t i = 0; i <= n; ++i) {
      for (std::size_t j = 0; j <= m; ++j) {
        double bernstein = 0;
        for (std::size_t p = 0; p <= i; ++p) {
          for (std::size_t q = 0; q <= j; ++q) {
            const double d = surface.c[p + a][q + b][c] * Falling(p + a, a) * Falling(q + b, b);
            bernstein += Binomial(i, p) / Binomial(n, p) * Binomial(j, q) / Binomial(m, q) * d;
          }
        }
        worst = std::max(worst, std::fabs(bernstein));
      }
    }
  }
  return worst;
}

// The same surface in a piece's parameters: s = s0 + hs·x, t = t0 + ht·y.
PolySurface Reparametrise(const PolySurface& surface, double s0, double hs, double t0, double ht) {
  const std::size_t rows = surface.c.size();
  const std::size_t cols = surface.c[0].size();
  PolySurface local;
  local.c.assign(rows, std::vector<Point3>(cols, Point3{}));
  for (std::size_t p = 0; p < rows; ++p) {
    for (std::size_t q = 0; q < cols; ++q) {
      for (std::size_t i = 0; i <= p; ++i) {
        const double ws = Binomial(p, i) * std::pow(s0, static_cast<double>(p - i)) *
                          std::pow(hs, static_cast<double>(i));
        for (std::size_t j = 0; j <= q; ++j) {
          const double wt = Binomial(q, j) * std::pow(t0, static_cast<double>(q - j)) *
                            std::pow(ht, static_cast<double>(j));
          local.c[i][j] = Add(local.c[i][j], Scale(surface.c[p][q], ws * wt));
        }
      }
    }
  }
  return local;
}

void CheckIncreasing(const std::vector<double>& nodes, const char* name) {
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    if (!std::isfinite(nodes[k])) {
      throw ConstructionError(std::string(name) + "[" + std::to_string(k) + "] is not finite");
    }
    if (k > 0 && !(nodes[k] > nodes[k - 1])) {
      throw ConstructionError(std::string(name) + "[" + std::to_string(k) +
                              "] = " + FormatNumber(nodes[k], 9) + " is not greater than " + name +
                              "[" + std::to_string(k - 1) + "] = " + FormatNumber(nodes[k - 1], 9) +
                              " (parameters must increase)");
    }
  }
}

}  // namespace

// ---- Polynomials ------------------------------------------------------------

VecPoly CurvePolynomial(const Curve& curve) {
  const BasisMatrix4 m = ReferenceBasisMatrix(curve.basis);
  VecPoly p(4, Point3{});
  for (int r = 0; r < 4; ++r) {
    for (int i = 0; i < 4; ++i) p[3 - r] = Add(p[3 - r], Scale(curve.g[i], m[r][i]));
  }
  return p;
}

Point3 EvaluateCurve(const Curve& curve, double u) {
  const BasisMatrix4 m = ReferenceBasisMatrix(curve.basis);
  const double powers[4] = {u * u * u, u * u, u, 1.0};
  Point3 p{};
  for (int i = 0; i < 4; ++i) {
    double w = 0;
    for (int r = 0; r < 4; ++r) w += powers[r] * m[r][i];
    p = Add(p, Scale(curve.g[i], w));
  }
  return p;
}

Point3 EvaluatePoly(const VecPoly& p, double u) {
  Point3 value{};
  for (std::size_t k = p.size(); k-- > 0;) value = Add(Scale(value, u), p[k]);
  return value;
}

double EvaluatePoly(const Poly& p, double x) {
  double value = 0;
  for (std::size_t k = p.size(); k-- > 0;) value = value * x + p[k];
  return value;
}

Point3 EvaluatePolySurface(const PolySurface& surface, double s, double t) {
  return PolySurfaceDerivative(surface, 0, 0, s, t);
}

Point3 PolySurfaceDerivative(const PolySurface& surface, int a, int b, double s, double t) {
  Point3 value{};
  for (std::size_t i = a; i < surface.c.size(); ++i) {
    for (std::size_t j = b; j < surface.c[i].size(); ++j) {
      const double w = Falling(i, a) * std::pow(s, static_cast<double>(i - a)) * Falling(j, b) *
                       std::pow(t, static_cast<double>(j - b));
      value = Add(value, Scale(surface.c[i][j], w));
    }
  }
  return value;
}

Patch BezierPatchOf(const PolySurface& surface) {
  if (surface.c.size() > 4 || (!surface.c.empty() && surface.c[0].size() > 4)) {
    throw ConstructionError("a bicubic patch needs degree <= 3 in each parameter");
  }
  std::array<std::array<Point3, 4>, 4> power{};
  for (std::size_t i = 0; i < surface.c.size(); ++i) {
    for (std::size_t j = 0; j < surface.c[i].size(); ++j) power[i][j] = surface.c[i][j];
  }
  std::array<std::array<Point3, 4>, 4> rows{};  // Bézier in t, power in s
  for (int i = 0; i < 4; ++i) rows[i] = PowerToBezier(power[i]);
  Patch patch;
  patch.basis = Basis::kBezier;
  for (int j = 0; j < 4; ++j) {
    const std::array<Point3, 4> column =
        PowerToBezier({rows[0][j], rows[1][j], rows[2][j], rows[3][j]});
    for (int i = 0; i < 4; ++i) patch.g[i][j] = column[i];
  }
  return patch;
}

Patch ToBezier(const Patch& patch) {
  if (patch.basis == Basis::kBezier) return patch;
  const PowerCoefficients pc = CoefficientsOf(patch);
  PolySurface surface;
  surface.c.assign(4, std::vector<Point3>(4));
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) surface.c[i][j] = pc.c[3 - i][3 - j];
  }
  Patch bezier = BezierPatchOf(surface);
  bezier.origin = patch.origin;
  return bezier;
}

double AppendPatches(const PolySurface& surface, double tolerance, const std::string& origin,
                     std::vector<Patch>* out) {
  if (surface.c.size() <= 4 && surface.c[0].size() <= 4) {
    Patch patch = BezierPatchOf(surface);
    patch.origin = origin;
    out->push_back(patch);
    return 0;
  }
  if (!(tolerance > 0)) throw ConstructionError("the tolerance must be positive");
  // Piecewise bicubic Hermite interpolation. With P_s, P_t the cubic Hermite
  // interpolation operators on a piece, f − P_s·P_t·f = (f − P_s f) + P_s(f − P_t f);
  // |f − P_x f| ≤ h⁴/384·max|f⁗| and |P_s g| ≤ max|g| + h_s/4·max|g_s|
  // (H0 + H1 = 1, |H2| + |H3| = w(1−w) ≤ 1/4), and ∂_s commutes with P_t.
  // In each piece's own parameters (h = 1) the bound is
  // M₄₀/384 + (M₀₄ + M₁₄/4)/384, with M bounded by the local coefficients.
  constexpr int kMaxPieces = 256;
  int ks = 1;
  int kt = 1;
  double bound = 0;
  for (;;) {
    double worst_s = 0;
    double worst_t = 0;
    for (int a = 0; a < ks; ++a) {
      for (int b = 0; b < kt; ++b) {
        const PolySurface local = Reparametrise(surface, static_cast<double>(a) / ks, 1.0 / ks,
                                                static_cast<double>(b) / kt, 1.0 / kt);
        worst_s = std::max(worst_s, DerivativeBound(local, 4, 0) / 384);
        worst_t = std::max(worst_t,
                           (DerivativeBound(local, 0, 4) + DerivativeBound(local, 1, 4) / 4) / 384);
      }
    }
    bound = worst_s + worst_t;
    if (bound <= tolerance) break;
    if (worst_s > tolerance / 2) ks *= 2;
    if (worst_t > tolerance / 2) kt *= 2;
    if (ks > kMaxPieces || kt > kMaxPieces) {
      throw ConstructionError("the surface has degree > 3 and needs more than " +
                              std::to_string(kMaxPieces) +
                              " bicubic pieces per direction for tolerance " +
                              FormatNumber(tolerance, 9) + "; give a larger \"tolerance\"");
    }
  }
  const double hs = 1.0 / ks;
  const double ht = 1.0 / kt;
  for (int a = 0; a < ks; ++a) {
    for (int b = 0; b < kt; ++b) {
      Patch patch;
      patch.basis = Basis::kHermite;
      for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
          const double s = (a + i) * hs;
          const double t = (b + j) * ht;
          patch.g[i][j] = PolySurfaceDerivative(surface, 0, 0, s, t);
          patch.g[i][2 + j] = Scale(PolySurfaceDerivative(surface, 0, 1, s, t), ht);
          patch.g[2 + i][j] = Scale(PolySurfaceDerivative(surface, 1, 0, s, t), hs);
          patch.g[2 + i][2 + j] = Scale(PolySurfaceDerivative(surface, 1, 1, s, t), hs * ht);
        }
      }
      patch.origin = origin + " piece (" + std::to_string(a) + "," + std::to_string(b) + ")";
      out->push_back(patch);
    }
  }
  return bound;
}

// ---- Row 1 --------------------------------------------------------------------

Curve HermiteSegment(const Point3& p0, const Point3& p1, const Point3& t0, const Point3& t1) {
  Curve curve;
  curve.basis = Basis::kHermite;
  curve.g = {p0, p1, t0, t1};
  return curve;
}

const char* JoinClassName(JoinClass join) {
  switch (join) {
    case JoinClass::kNotSmooth:
      return "not smooth";
    case JoinClass::kGeometric:
      return "geometrically smooth (G1)";
    case JoinClass::kParametric:
      return "parametrically smooth (C1)";
  }
  return "?";
}

JoinClass ClassifyJoin(const Point3& end, const Point3& start, double tolerance) {
  const double a = Norm(end);
  const double b = Norm(start);
  if (a == 0 || b == 0) return JoinClass::kNotSmooth;
  if (Norm(Sub(end, start)) <= tolerance * std::max(a, b)) return JoinClass::kParametric;
  if (Dot(end, start) > 0 && Norm(Cross(end, start)) <= tolerance * a * b) {
    return JoinClass::kGeometric;
  }
  return JoinClass::kNotSmooth;
}

HermiteChain MakeHermiteChain(const std::vector<Point3>& points,
                              const std::vector<Point3>& in_vectors,
                              const std::vector<Point3>& out_vectors) {
  if (points.size() < 2) {
    throw ConstructionError("a Hermite chain needs at least 2 points, got " +
                            std::to_string(points.size()));
  }
  if (in_vectors.size() != points.size() || out_vectors.size() != points.size()) {
    throw ConstructionError("a Hermite chain needs one vector per point");
  }
  HermiteChain chain;
  for (std::size_t k = 0; k + 1 < points.size(); ++k) {
    chain.segments.push_back(
        HermiteSegment(points[k], points[k + 1], out_vectors[k], in_vectors[k + 1]));
    if (k > 0) chain.joins.push_back(ClassifyJoin(in_vectors[k], out_vectors[k]));
  }
  return chain;
}

// ---- Rows 2-4 -----------------------------------------------------------------

PolySurface RuledSurface(const Curve& r1, const Curve& r2) {
  PolySurface surface;
  AddOuter(CurvePolynomial(r1), Poly{1, -1}, 1, &surface);
  AddOuter(CurvePolynomial(r2), Poly{0, 1}, 1, &surface);
  return surface;
}

PolySurface BilinearSurface(const Point3& p00, const Point3& p10, const Point3& p01,
                            const Point3& p11) {
  PolySurface surface;
  const Poly down{1, -1};
  const Poly up{0, 1};
  AddOuter(down, down, p00, 1, &surface);
  AddOuter(up, down, p10, 1, &surface);
  AddOuter(down, up, p01, 1, &surface);
  AddOuter(up, up, p11, 1, &surface);
  return surface;
}

PolySurface CoonsPatch(const Curve& r1, const Curve& r2, const Curve& r3, const Curve& r4,
                       CoonsBlend blend, double tolerance) {
  struct Corner {
    const char* name;
    int a;  // boundary along u (0: r(u,0), 1: r(u,1))
    double u;
    int b;  // boundary along v (2: r(0,v), 3: r(1,v))
    double v;
  };
  const Curve* boundary[4] = {&r1, &r2, &r3, &r4};
  static const char* const kBoundaryName[4] = {"r(u,0)", "r(u,1)", "r(0,v)", "r(1,v)"};
  const Corner corners[4] = {
      {"(0,0)", 0, 0, 2, 0}, {"(1,0)", 0, 1, 3, 0}, {"(0,1)", 1, 0, 2, 1}, {"(1,1)", 1, 1, 3, 1}};
  Point3 corner_point[4];
  double scale = 1;
  for (const Curve* c : boundary) {
    for (const Point3& p : c->g) {
      for (double x : p) scale = std::max(scale, std::fabs(x));
    }
  }
  for (int k = 0; k < 4; ++k) {
    const Corner& c = corners[k];
    const Point3 pa = EvaluateCurve(*boundary[c.a], c.u);
    const Point3 pb = EvaluateCurve(*boundary[c.b], c.v);
    const double gap = Norm(Sub(pa, pb));
    if (!(gap <= tolerance * scale)) {
      throw ConstructionError(
          std::string("corner ") + c.name + ": boundary " + std::to_string(c.a) + " (" +
          kBoundaryName[c.a] + ") " + (c.u == 0 ? "starts" : "ends") + " at " + FormatPoint(pa) +
          " but boundary " + std::to_string(c.b) + " (" + kBoundaryName[c.b] + ") " +
          (c.v == 0 ? "starts" : "ends") + " at " + FormatPoint(pb) + ", " + FormatNumber(gap, 9) +
          " apart (tolerance " + FormatNumber(tolerance * scale, 9) + ")");
    }
    corner_point[k] = pa;
  }
  const Poly f = blend == CoonsBlend::kLinear ? Poly{0, 1} : kH1;
  const Poly one_minus_f = blend == CoonsBlend::kLinear ? Poly{1, -1} : kH0;
  PolySurface surface;
  AddOuter(CurvePolynomial(r1), one_minus_f, 1, &surface);
  AddOuter(CurvePolynomial(r2), f, 1, &surface);
  AddOuter(one_minus_f, CurvePolynomial(r3), 1, &surface);
  AddOuter(f, CurvePolynomial(r4), 1, &surface);
  AddOuter(one_minus_f, one_minus_f, corner_point[0], -1, &surface);
  AddOuter(f, one_minus_f, corner_point[1], -1, &surface);
  AddOuter(one_minus_f, f, corner_point[2], -1, &surface);
  AddOuter(f, f, corner_point[3], -1, &surface);
  return surface;
}

// ---- Rows 5, 6, 9 ---------------------------------------------------------

std::vector<Poly> LagrangeBasis(const std::vector<double>& nodes) {
  if (nodes.size() < 2) {
    throw ConstructionError("Lagrange interpolation needs at least 2 nodes, got " +
                            std::to_string(nodes.size()));
  }
  CheckIncreasing(nodes, "nodes");
  const double span = nodes.back() - nodes.front();
  std::vector<double> x(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) x[k] = (nodes[k] - nodes.front()) / span;
  x.back() = 1;
  std::vector<Poly> basis;
  for (std::size_t k = 0; k < x.size(); ++k) {
    Poly p{1};
    for (std::size_t m = 0; m < x.size(); ++m) {
      if (m == k) continue;
      const double d = x[k] - x[m];
      p = Multiply(p, Poly{-x[m] / d, 1 / d});
    }
    basis.push_back(p);
  }
  return basis;
}

std::vector<Poly> BernsteinBasis(int n) {
  std::vector<Poly> basis;
  for (int i = 0; i <= n; ++i) {
    double binomial = 1;
    for (int k = 1; k <= i; ++k) binomial = binomial * (n - k + 1) / k;
    Poly p{binomial};
    for (int k = 0; k < i; ++k) p = Multiply(p, Poly{0, 1});
    for (int k = i; k < n; ++k) p = Multiply(p, Poly{1, -1});
    basis.push_back(p);
  }
  return basis;
}

PolySurface LagrangeGrid(const std::vector<double>& u_nodes, const std::vector<double>& v_nodes,
                         const std::vector<std::vector<Point3>>& points) {
  const std::vector<Poly> lu = LagrangeBasis(u_nodes);
  const std::vector<Poly> lv = LagrangeBasis(v_nodes);
  if (points.size() != u_nodes.size()) {
    throw ConstructionError("the grid has " + std::to_string(points.size()) + " rows but " +
                            std::to_string(u_nodes.size()) + " u values");
  }
  PolySurface surface;
  for (std::size_t k = 0; k < lu.size(); ++k) {
    if (points[k].size() != v_nodes.size()) {
      throw ConstructionError("row " + std::to_string(k) + " has " +
                              std::to_string(points[k].size()) + " points but there are " +
                              std::to_string(v_nodes.size()) + " v values");
    }
    for (std::size_t l = 0; l < lv.size(); ++l) AddOuter(lu[k], lv[l], points[k][l], 1, &surface);
  }
  return surface;
}

PolySurface BlendCurves(const std::vector<VecPoly>& curves, const std::vector<Poly>& blend) {
  PolySurface surface;
  for (std::size_t i = 0; i < curves.size(); ++i) AddOuter(curves[i], blend[i], 1, &surface);
  return surface;
}

// ---- Row 7 ------------------------------------------------------------------

std::vector<VecPoly> EstimateFamilyDerivatives(const std::vector<VecPoly>& curves,
                                               const std::vector<double>& v, bool closed) {
  const std::size_t n = curves.size();
  if (n < (closed ? 3U : 2U)) {
    throw ConstructionError(std::string("a ") + (closed ? "closed " : "") +
                            "Hermite family needs at least " + (closed ? "3" : "2") +
                            " curves, got " + std::to_string(n));
  }
  if (v.size() != n + (closed ? 1 : 0)) {
    throw ConstructionError("v has " + std::to_string(v.size()) + " values but " +
                            (closed ? "a closed family of " : "") + std::to_string(n) +
                            " curves needs " + std::to_string(n + (closed ? 1 : 0)));
  }
  CheckIncreasing(v, "v");
  const std::size_t size = curves[0].size();
  const auto combine = [&](std::initializer_list<std::pair<std::size_t, double>> terms) {
    VecPoly result(size, Point3{});
    for (const auto& [index, weight] : terms) {
      for (std::size_t k = 0; k < size; ++k) {
        result[k] = Add(result[k], Scale(curves[index][k], weight));
      }
    }
    return result;
  };
  // The derivative at v_i of the quadratic through (v_{i-1}, c_p), (v_i, c_i),
  // (v_{i+1}, c_q): seed 003's three-point formula.
  const auto three_point = [&](std::size_t p, double vp, std::size_t i, double vi, std::size_t q,
                               double vq) {
    return combine({{p, (vi - vq) / ((vp - vi) * (vp - vq))},
                    {i, (2 * vi - vp - vq) / ((vi - vp) * (vi - vq))},
                    {q, (vi - vp) / ((vq - vp) * (vq - vi))}});
  };
  std::vector<VecPoly> d(n);
  if (closed) {
    const double period = v[n] - v[0];
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t p = (i + n - 1) % n;
      const std::size_t q = (i + 1) % n;
      const double vp = i == 0 ? v[n - 1] - period : v[i - 1];
      const double vq = v[i + 1];
      d[i] = three_point(p, vp, i, v[i], q, vq);
    }
    return d;
  }
  if (n == 2) {
    const double h = v[1] - v[0];
    d[0] = combine({{0, -1 / h}, {1, 1 / h}});
    d[1] = d[0];
    return d;
  }
  for (std::size_t i = 1; i + 1 < n; ++i)
    d[i] = three_point(i - 1, v[i - 1], i, v[i], i + 1, v[i + 1]);
  // r_vv = 0 on the edge curves: T0 = 3/2·(c1 − c0)/h − T1/2 (and mirrored).
  const double h0 = v[1] - v[0];
  d[0] = combine({{0, -1.5 / h0}, {1, 1.5 / h0}});
  const double hn = v[n - 1] - v[n - 2];
  d[n - 1] = combine({{n - 2, -1.5 / hn}, {n - 1, 1.5 / hn}});
  for (std::size_t k = 0; k < size; ++k) {
    d[0][k] = Sub(d[0][k], Scale(d[1][k], 0.5));
    d[n - 1][k] = Sub(d[n - 1][k], Scale(d[n - 2][k], 0.5));
  }
  return d;
}

std::vector<PolySurface> HermiteFamily(const std::vector<VecPoly>& curves,
                                       const std::vector<VecPoly>& derivatives,
                                       const std::vector<double>& v, bool closed) {
  const std::size_t n = curves.size();
  if (n < 2 || derivatives.size() != n || v.size() != n + (closed ? 1 : 0)) {
    throw ConstructionError("a Hermite family needs >= 2 curves, one derivative and one v each" +
                            std::string(closed ? " (plus the closing v)" : ""));
  }
  CheckIncreasing(v, "v");
  std::vector<PolySurface> pieces;
  const std::size_t intervals = closed ? n : n - 1;
  for (std::size_t i = 0; i < intervals; ++i) {
    const std::size_t q = (i + 1) % n;
    const double delta = v[i + 1] - v[i];
    PolySurface piece;
    AddOuter(curves[i], kH0, 1, &piece);
    AddOuter(curves[q], kH1, 1, &piece);
    AddOuter(derivatives[i], kH2, delta, &piece);
    AddOuter(derivatives[q], kH3, delta, &piece);
    pieces.push_back(piece);
  }
  return pieces;
}

// ---- Row 8 ------------------------------------------------------------------

Transition TransitionSurface(const Patch& a, const Patch& b, double k_a, double k_b) {
  const PowerCoefficients ca = CoefficientsOf(a);
  const PowerCoefficients cb = CoefficientsOf(b);
  // Ascending: coefficient of s^i t^j is c[3-i][3-j].
  VecPoly a1(4, Point3{});
  VecPoly a1_t(4, Point3{});
  VecPoly b0(4, Point3{});
  VecPoly b0_t(4, Point3{});
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      a1[i] = Add(a1[i], ca.c[3 - i][3 - j]);
      a1_t[i] = Add(a1_t[i], Scale(ca.c[3 - i][3 - j], j));
    }
    b0[i] = cb.c[3 - i][3];
    b0_t[i] = cb.c[3 - i][2];
  }
  constexpr int kSamples = 256;
  double distance = 0;
  double length_a = 0;
  double length_b = 0;
  double scale = 1;
  for (int k = 0; k <= kSamples; ++k) {
    const double u = static_cast<double>(k) / kSamples;
    const double w = k == 0 || k == kSamples ? 0.5 : 1.0;
    const Point3 pa = EvaluatePoly(a1, u);
    const Point3 pb = EvaluatePoly(b0, u);
    for (int c = 0; c < 3; ++c) scale = std::max({scale, std::fabs(pa[c]), std::fabs(pb[c])});
    distance += w * Norm(Sub(pb, pa));
    length_a += w * Norm(EvaluatePoly(a1_t, u));
    length_b += w * Norm(EvaluatePoly(b0_t, u));
  }
  // Edges that coincide up to rounding have no distance to scale by.
  if (distance <= 1e-12 * scale * kSamples) distance = 0;
  Transition result;
  result.k_a = k_a > 0 ? k_a : (length_a > 0 ? distance / length_a : 0);
  result.k_b = k_b > 0 ? k_b : (length_b > 0 ? distance / length_b : 0);
  if (!(result.k_a > 0) || !(result.k_b > 0)) {
    throw ConstructionError(
        length_a == 0 || length_b == 0
            ? std::string("the cross-derivative of ") + (length_a == 0 ? "a" : "b") +
                  " along its edge is zero, so its direction is undefined"
            : "the two edges coincide (mean distance 0), so the scale factors are 0; give "
              "\"ka\" and \"kb\"");
  }
  AddOuter(a1, kH0, 1, &result.surface);
  AddOuter(b0, kH1, 1, &result.surface);
  AddOuter(a1_t, kH2, result.k_a, &result.surface);
  AddOuter(b0_t, kH3, result.k_b, &result.surface);
  return result;
}

// ---- Row 10 -------------------------------------------------------------------

namespace {

// A patch's boundary edge in Bézier form.
struct PatchEdge {
  std::size_t patch;
  const char* name;
  std::array<Point3, 4> on;     // the edge's control points
  std::array<Point3, 4> inner;  // the next row inward, point by point
};

// The four boundary edges of every patch, and in *scale the largest
// coordinate of any control point (at least 1), the tolerance's unit.
std::vector<PatchEdge> BoundaryEdges(const std::vector<Patch>& patches, double* scale) {
  std::vector<PatchEdge> edges;
  for (std::size_t p = 0; p < patches.size(); ++p) {
    const Patch b = ToBezier(patches[p]);
    for (const auto& row : b.g) {
      for (const Point3& x : row) {
        for (double v : x) *scale = std::max(*scale, std::fabs(v));
      }
    }
    PatchEdge e0{p, "s=0", {}, {}};
    PatchEdge e1{p, "s=1", {}, {}};
    PatchEdge e2{p, "t=0", {}, {}};
    PatchEdge e3{p, "t=1", {}, {}};
    for (int k = 0; k < 4; ++k) {
      e0.on[k] = b.g[0][k];
      e0.inner[k] = b.g[1][k];
      e1.on[k] = b.g[3][k];
      e1.inner[k] = b.g[2][k];
      e2.on[k] = b.g[k][0];
      e2.inner[k] = b.g[k][1];
      e3.on[k] = b.g[k][3];
      e3.inner[k] = b.g[k][2];
    }
    edges.push_back(e0);
    edges.push_back(e1);
    edges.push_back(e2);
    edges.push_back(e3);
  }
  return edges;
}

// How two coinciding edges join: the angle and length ratio between the legs
// from each edge's control points to the next row inward, row by row (ea's
// point k against eb's point k, or 3 − k when eb runs backward).
EdgeJoin MeasureEdgeJoin(const PatchEdge& ea, const PatchEdge& eb, bool forward, double tol,
                         double angle_deg, double ratio) {
  EdgeJoin join;
  join.patch_a = ea.patch;
  join.patch_b = eb.patch;
  join.edge_a = ea.name;
  join.edge_b = eb.name;
  int rows = 0;
  for (int k = 0; k < 4; ++k) {
    const int kb = forward ? k : 3 - k;
    const Point3 leg_a = Sub(ea.on[k], ea.inner[k]);
    const Point3 leg_b = Sub(eb.inner[kb], eb.on[kb]);
    const double la = Norm(leg_a);
    const double lb = Norm(leg_b);
    if (la <= tol || lb <= tol) {
      ++join.degenerate_rows;
      continue;
    }
    ++rows;
    const double angle =
        std::atan2(Norm(Cross(leg_a, leg_b)), Dot(leg_a, leg_b)) * 180 / std::numbers::pi;
    join.worst_angle_deg = std::max(join.worst_angle_deg, angle);
    join.worst_ratio_error = std::max(join.worst_ratio_error, std::fabs(lb / la - 1));
  }
  if (rows == 0) {
    join.join = "degenerate";
  } else if (join.worst_angle_deg > angle_deg) {
    join.join = "C0";
  } else {
    join.join = join.worst_ratio_error <= ratio ? "C1" : "G1";
  }
  return join;
}

}  // namespace

std::vector<EdgeJoin> CheckBezierJoins(const std::vector<Patch>& patches, double tolerance,
                                       double angle_deg, double ratio) {
  double scale = 1;
  const std::vector<PatchEdge> edges = BoundaryEdges(patches, &scale);
  const double tol = tolerance * scale;
  const auto same = [&](const Point3& x, const Point3& y) { return Norm(Sub(x, y)) <= tol; };
  std::vector<EdgeJoin> joins;
  for (std::size_t x = 0; x < edges.size(); ++x) {
    for (std::size_t y = x + 1; y < edges.size(); ++y) {
      const PatchEdge& ea = edges[x];
      const PatchEdge& eb = edges[y];
      bool forward = true;
      bool backward = true;
      for (int k = 0; k < 4; ++k) {
        forward = forward && same(ea.on[k], eb.on[k]);
        backward = backward && same(ea.on[k], eb.on[3 - k]);
      }
      if (!forward && !backward) continue;
      // An edge collapsed to one point matches everything around a pole.
      if (same(ea.on[0], ea.on[3]) && same(ea.on[0], ea.on[1]) && same(ea.on[0], ea.on[2])) {
        continue;
      }
      joins.push_back(MeasureEdgeJoin(ea, eb, forward, tol, angle_deg, ratio));
    }
  }
  return joins;
}

// ---- Row 11 -------------------------------------------------------------------

std::vector<Patch> PeriodicNetPatches(const std::vector<std::vector<Point3>>& net, Basis basis,
                                      bool closed_s, bool closed_t, const std::string& origin) {
  if (basis != Basis::kBSpline && basis != Basis::kCatmullRom) {
    throw ConstructionError("a closed net must use the bspline or catmull-rom basis");
  }
  const std::size_t rows = net.size();
  const std::size_t cols = rows == 0 ? 0 : net[0].size();
  const std::size_t need_s = closed_s ? 3 : 4;
  const std::size_t need_t = closed_t ? 3 : 4;
  if (rows < need_s || cols < need_t) {
    throw ConstructionError("the net is " + std::to_string(rows) + "x" + std::to_string(cols) +
                            " but needs at least " + std::to_string(need_s) + "x" +
                            std::to_string(need_t) + " points (" + (closed_s ? "closed" : "open") +
                            " rows, " + (closed_t ? "closed" : "open") + " columns)");
  }
  for (const auto& row : net) {
    if (row.size() != cols)
      throw ConstructionError("every row of the net must have the same length");
  }
  const std::size_t ps = closed_s ? rows : rows - 3;
  const std::size_t pt = closed_t ? cols : cols - 3;
  std::vector<Patch> patches;
  for (std::size_t a = 0; a < ps; ++a) {
    for (std::size_t b = 0; b < pt; ++b) {
      Patch patch;
      patch.basis = basis;
      for (std::size_t i = 0; i < 4; ++i) {
        for (std::size_t j = 0; j < 4; ++j) patch.g[i][j] = net[(a + i) % rows][(b + j) % cols];
      }
      patch.origin = origin + " patch (" + std::to_string(a) + "," + std::to_string(b) + ")";
      patches.push_back(patch);
    }
  }
  return patches;
}

}  // namespace fdsurf::host
