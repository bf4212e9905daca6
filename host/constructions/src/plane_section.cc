// SPDX-License-Identifier: MIT
#include "fdsurf/host/plane_section.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "fdsurf/host/vec3.h"

namespace fdsurf::host {
namespace {

constexpr double kPi = std::numbers::pi;

// θ reduced to [0, π).
double ReduceAngle(double theta) {
  double r = std::fmod(theta, kPi);
  if (r < 0) r += kPi;
  return r >= kPi ? 0 : r;
}

// The directions θ ∈ [0, π) where the binary form s11·x² + 2·s12·xy + s22·y²
// vanishes: 0, 1 or 2 of them. Both roots are formed without cancellation
// (the sign of the square root follows s12).
std::vector<double> FormZeros(double s11, double s12, double s22) {
  const double scale = std::max({std::fabs(s11), std::fabs(s12), std::fabs(s22)});
  if (!(scale > 0)) return {};
  const double discriminant = s12 * s12 - s11 * s22;
  if (discriminant < -1e-14 * scale * scale) return {};
  const double root = std::sqrt(std::max(0.0, discriminant));
  const double sum = s12 >= 0 ? s12 + root : s12 - root;
  std::vector<double> out;
  // (−sum, s11) and (s22, −sum) are the two zero directions.
  if (std::fabs(sum) + std::fabs(s11) > 0) out.push_back(ReduceAngle(std::atan2(s11, -sum)));
  if (std::fabs(sum) + std::fabs(s22) > 0) {
    const double second = ReduceAngle(std::atan2(-sum, s22));
    if (out.empty() || std::fabs(second - out[0]) > 1e-15) out.push_back(second);
  }
  return out;
}

struct Frame {
  Point3 origin;
  Point3 e1;
  Point3 e2;
};

// q in the frame, coefficients a, b, c, d, e, g (q = a·u² + 2b·uv + c·v² +
// 2d·u + 2e·v + g).
std::array<double, 6> RestrictQuadric(const Quadric& f, const Frame& fr) {
  const Point3 d0 = Sub(fr.origin, f.p);
  return {f.Form(fr.e1, fr.e1),
          f.Form(fr.e1, fr.e2),
          f.Form(fr.e2, fr.e2),
          f.Form(d0, fr.e1) + Dot(f.a, fr.e1),
          f.Form(d0, fr.e2) + Dot(f.a, fr.e2),
          f.Value(fr.origin)};
}

double Evaluate(const std::array<double, 6>& q, double u, double v) {
  return q[0] * u * u + 2 * q[1] * u * v + q[2] * v * v + 2 * q[3] * u + 2 * q[4] * v + q[5];
}

// The real roots of α·t² + 2β·t + γ = 0, stably.
std::vector<double> QuadraticRoots(double alpha, double beta, double gamma) {
  const double scale = std::max({std::fabs(alpha), std::fabs(beta), std::fabs(gamma)});
  if (!(scale > 0)) return {};
  if (std::fabs(alpha) <= 1e-15 * scale) {
    if (std::fabs(beta) <= 1e-15 * scale) return {};
    return {-gamma / (2 * beta)};
  }
  const double discriminant = beta * beta - alpha * gamma;
  if (discriminant < 0) return {};
  const double sum =
      beta >= 0 ? -(beta + std::sqrt(discriminant)) : -(beta - std::sqrt(discriminant));
  if (sum == 0) return {0.0};
  return {sum / alpha, gamma / sum};
}

// A point of the conic near the frame origin: the nearest crossing of 16
// lines through the origin, else the end of an axis from the centre.
bool FindConicPoint(const std::array<double, 6>& q, double reach, double (&k)[2]) {
  double best = 16 * reach;
  bool found = false;
  for (int j = 0; j < 16; ++j) {
    const double cu = std::cos(kPi * j / 16);
    const double sv = std::sin(kPi * j / 16);
    const double alpha = q[0] * cu * cu + 2 * q[1] * cu * sv + q[2] * sv * sv;
    for (double t : QuadraticRoots(alpha, q[3] * cu + q[4] * sv, q[5])) {
      if (std::fabs(t) < best) {
        best = std::fabs(t);
        k[0] = t * cu;
        k[1] = t * sv;
        found = true;
      }
    }
  }
  if (found) return true;
  const double det = q[0] * q[2] - q[1] * q[1];
  if (std::fabs(det) <= 1e-12 * (q[0] * q[0] + q[2] * q[2] + 2 * q[1] * q[1])) return false;
  const double cu = (-q[3] * q[2] + q[4] * q[1]) / det;
  const double cv = (-q[4] * q[0] + q[3] * q[1]) / det;
  const double value = Evaluate(q, cu, cv);
  // Eigenvectors of the quadratic part; go along the one that crosses.
  const double mean = (q[0] + q[2]) / 2;
  const double radius = std::hypot((q[0] - q[2]) / 2, q[1]);
  for (double lambda : {mean + radius, mean - radius}) {
    if (!(lambda * value < 0)) continue;
    const double angle = std::atan2(lambda - q[0], q[1]);
    const double vu = std::fabs(q[1]) > 0 ? std::cos(angle) : (lambda == q[0] ? 1 : 0);
    const double vv = std::fabs(q[1]) > 0 ? std::sin(angle) : (lambda == q[0] ? 0 : 1);
    const double t = std::sqrt(-value / lambda);
    k[0] = cu + t * vu;
    k[1] = cv + t * vv;
    return std::hypot(k[0], k[1]) <= 16 * reach;
  }
  return false;
}

// The lines of a degenerate conic, each as l0·u + l1·v + l2 = 0 (C is the
// conic's symmetric 3×3 matrix): for a pair of lines l, m, C ∝ l·mᵀ + m·lᵀ,
// its adjugate is −p·pᵀ with p = l × m, and C + [p]× is the rank-one l·mᵀ.
std::vector<std::array<double, 3>> SplitLines(const double (&c)[3][3]) {
  double adj[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const int i1 = (i + 1) % 3;
      const int i2 = (i + 2) % 3;
      const int j1 = (j + 1) % 3;
      const int j2 = (j + 2) % 3;
      adj[j][i] = c[i1][j1] * c[i2][j2] - c[i1][j2] * c[i2][j1];
    }
  }
  double scale = 0;
  for (const auto& row : c) {
    for (double v : row) scale = std::max(scale, std::fabs(v));
  }
  int i = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::fabs(adj[k][k]) > std::fabs(adj[i][i])) i = k;
  }
  if (std::fabs(adj[i][i]) <= 1e-16 * scale * scale) {
    // A double line: C = l·lᵀ.
    int k = 0;
    for (int m = 1; m < 3; ++m) {
      if (std::fabs(c[m][m]) > std::fabs(c[k][k])) k = m;
    }
    if (!(c[k][k] > 0) && !(c[k][k] < 0)) return {};
    const double root = std::sqrt(std::fabs(c[k][k]));
    return {{c[0][k] / root, c[1][k] / root, c[2][k] / root}};
  }
  if (adj[i][i] > 0) return {};  // two complex lines through one real point
  const double beta = std::sqrt(-adj[i][i]);
  const double p[3] = {adj[0][i] / beta, adj[1][i] / beta, adj[2][i] / beta};
  const double cross[3][3] = {{0, p[2], -p[1]}, {-p[2], 0, p[0]}, {p[1], -p[0], 0}};
  double d[3][3];
  int bi = 0;
  int bj = 0;
  for (int r = 0; r < 3; ++r) {
    for (int s = 0; s < 3; ++s) {
      d[r][s] = c[r][s] + cross[r][s];
      if (std::fabs(d[r][s]) > std::fabs(d[bi][bj])) {
        bi = r;
        bj = s;
      }
    }
  }
  return {{d[bi][0], d[bi][1], d[bi][2]}, {d[0][bj], d[1][bj], d[2][bj]}};
}

// Branches for the line l0·u + l1·v + l2 = 0 (frame coordinates).
void AddLine(const Frame& fr, const std::array<double, 3>& l, std::vector<SectionBranch>* out) {
  const double norm = std::hypot(l[0], l[1]);
  if (!(norm > 0)) return;
  const double n[2] = {l[0] / norm, l[1] / norm};
  const double p[2] = {-l[2] / norm * n[0], -l[2] / norm * n[1]};
  const double dir[2] = {-n[1], n[0]};
  out->push_back(SectionBranch::Line(fr.origin, fr.e1, fr.e2, p, dir));
}

}  // namespace

double Plane::Side(const Point3& x) const { return Dot(normal, x) - offset; }

Plane Plane::Through(const Point3& point, const Point3& unit_normal) {
  return Plane{unit_normal, Dot(unit_normal, point)};
}

SectionBranch SectionBranch::Conic(const Point3& origin, const Point3& e1, const Point3& e2,
                                   const double (&coefficients)[6], const double (&k)[2]) {
  SectionBranch b;
  b.kind_ = Kind::kConic;
  b.origin_ = origin;
  b.e1_ = e1;
  b.e2_ = e2;
  b.quad_[0] = coefficients[0];
  b.quad_[1] = coefficients[1];
  b.quad_[2] = coefficients[2];
  b.k_[0] = k[0];
  b.k_[1] = k[1];
  b.grad_[0] = coefficients[0] * k[0] + coefficients[1] * k[1] + coefficients[3];
  b.grad_[1] = coefficients[1] * k[0] + coefficients[2] * k[1] + coefficients[4];
  return b;
}

SectionBranch SectionBranch::Line(const Point3& origin, const Point3& e1, const Point3& e2,
                                  const double (&p)[2], const double (&dir)[2]) {
  SectionBranch b;
  b.kind_ = Kind::kLine;
  b.origin_ = origin;
  b.e1_ = e1;
  b.e2_ = e2;
  b.k_[0] = p[0];
  b.k_[1] = p[1];
  b.dir_[0] = dir[0];
  b.dir_[1] = dir[1];
  return b;
}

Point3 SectionBranch::ToSpace(double u, double v) const {
  return Add(origin_, Add(Scale(e1_, u), Scale(e2_, v)));
}

Point3 SectionBranch::At(double p) const {
  if (kind_ == Kind::kLine) return ToSpace(k_[0] + p * dir_[0], k_[1] + p * dir_[1]);
  const double du = std::cos(p);
  const double dv = std::sin(p);
  const double along = grad_[0] * du + grad_[1] * dv;
  const double curvature = quad_[0] * du * du + 2 * quad_[1] * du * dv + quad_[2] * dv * dv;
  if (along == 0) return ToSpace(k_[0], k_[1]);
  const double t = -2 * along / curvature;
  return ToSpace(k_[0] + t * du, k_[1] + t * dv);
}

double SectionBranch::ParameterOf(const Point3& x) const {
  const Point3 d = Sub(x, ToSpace(k_[0], k_[1]));
  const double u = Dot(d, e1_);
  const double v = Dot(d, e2_);
  if (kind_ == Kind::kLine) return u * dir_[0] + v * dir_[1];
  const double scale = std::hypot(grad_[0], grad_[1]);
  // At K itself: the tangent's direction, perpendicular to the gradient.
  if (std::hypot(u, v) * scale <= 1e-13 * (1 + Norm(x)) * scale) {
    return ReduceAngle(std::atan2(grad_[0], -grad_[1]));
  }
  return ReduceAngle(std::atan2(v, u));
}

std::vector<double> SectionBranch::Crossings(const Plane& cut) const {
  // The cut's trace in the frame: ℓ(u, v) = m·(u, v) + s0.
  const double m[2] = {Dot(cut.normal, e1_), Dot(cut.normal, e2_)};
  if (std::hypot(m[0], m[1]) < 1e-12) return {};
  const double s0 = cut.Side(ToSpace(k_[0], k_[1]));
  if (kind_ == Kind::kLine) {
    const double rate = m[0] * dir_[0] + m[1] * dir_[1];
    if (std::fabs(rate) < 1e-12) return {};
    return {-s0 / rate};
  }
  // Along the pencil, X = K + t·d with t = −2(G·d)/(dᵀAd), so ℓ(X) = 0 when
  // ℓ(K)·dᵀAd − 2(G·d)(m·d) = 0: a binary quadratic form in d.
  std::vector<double> out;
  for (double theta : FormZeros(s0 * quad_[0] - 2 * grad_[0] * m[0],
                                s0 * quad_[1] - grad_[0] * m[1] - grad_[1] * m[0],
                                s0 * quad_[2] - 2 * grad_[1] * m[1])) {
    const double du = std::cos(theta);
    const double dv = std::sin(theta);
    const double curvature = quad_[0] * du * du + 2 * quad_[1] * du * dv + quad_[2] * dv * dv;
    const double along = grad_[0] * du + grad_[1] * dv;
    // A direction at infinity solves the form only through the factor dᵀAd.
    if (std::fabs(curvature) <= 1e-13 * std::fabs(along) * (1 + std::hypot(k_[0], k_[1]))) continue;
    out.push_back(theta);
  }
  return out;
}

std::vector<double> SectionBranch::AtInfinity() const {
  if (kind_ == Kind::kLine) return {};
  return FormZeros(quad_[0], quad_[1], quad_[2]);
}

std::vector<RationalQuadratic> SectionBranch::Arc(double p0, double p1) const {
  std::vector<RationalQuadratic> out;
  if (kind_ == Kind::kLine) {
    out.push_back(RationalQuadratic{At(p0), At((p0 + p1) / 2), At(p1), 1});
    return out;
  }
  double span = ReduceAngle(p1) - ReduceAngle(p0);
  if (span <= 0) span += kPi;
  // Pieces of at most π/8 of the pencil, so that the end weights keep one
  // sign and the middle weight stays away from 0 (ArcSpan halves further).
  const int pieces = std::max(1, static_cast<int>(std::ceil(span / (kPi / 8))));
  for (int i = 0; i < pieces; ++i) {
    ArcSpan(p0 + span * i / pieces, p0 + span * (i + 1) / pieces, 0, &out);
  }
  return out;
}

void SectionBranch::ArcSpan(double t0, double t1, int depth,
                            std::vector<RationalQuadratic>* out) const {
  // With d(σ) = (1 − σ)·d0 + σ·d1, X(σ) = [K·(dᵀAd) − 2(G·d)·d] / (dᵀAd):
  // numerator and denominator are quadratic in σ, so the arc is a rational
  // quadratic with Bernstein weights W_j and points N_j / W_j.
  const double d0[2] = {std::cos(t0), std::sin(t0)};
  const double d1[2] = {std::cos(t1), std::sin(t1)};
  const auto form = [&](const double(&x)[2], const double(&y)[2]) {
    return quad_[0] * x[0] * y[0] + quad_[1] * (x[0] * y[1] + x[1] * y[0]) + quad_[2] * x[1] * y[1];
  };
  const double w0 = form(d0, d0);
  const double w1 = form(d0, d1);
  const double w2 = form(d1, d1);
  const double g0 = grad_[0] * d0[0] + grad_[1] * d0[1];
  const double g1 = grad_[0] * d1[0] + grad_[1] * d1[1];
  const double weight = w0 * w2 > 0 ? w1 / (std::copysign(1.0, w0) * std::sqrt(w0 * w2)) : -1;
  if (weight < 0.25 && depth < 40) {
    const double middle = (t0 + t1) / 2;
    ArcSpan(t0, middle, depth + 1, out);
    ArcSpan(middle, t1, depth + 1, out);
    return;
  }
  const auto point = [&](double weight_j, double a, const double(&da)[2], double b,
                         const double(&db)[2]) {
    // (K·W_j − (a·db + b·da)) / W_j, with a, b the G·d products.
    const double u = k_[0] - (a * db[0] + b * da[0]) / weight_j;
    const double v = k_[1] - (a * db[1] + b * da[1]) / weight_j;
    return ToSpace(u, v);
  };
  out->push_back(RationalQuadratic{point(w0, g0, d0, g0, d0), point(w1, g0, d0, g1, d1),
                                   point(w2, g1, d1, g1, d1), weight});
}

std::vector<SectionBranch> SectionOf(const Quadric& f, const Point3& origin, const Point3& e1,
                                     const Point3& e2, const std::optional<Point3>& known,
                                     double reach) {
  const Frame fr{origin, e1, e2};
  const std::array<double, 6> q = RestrictQuadric(f, fr);
  // Degeneracy is judged on coordinates scaled by `reach`, where the conic's
  // matrix has entries of comparable size.
  const double r = reach;
  const double c[3][3] = {{q[0] * r * r, q[1] * r * r, q[3] * r},
                          {q[1] * r * r, q[2] * r * r, q[4] * r},
                          {q[3] * r, q[4] * r, q[5]}};
  double scale = 0;
  for (const auto& row : c) {
    for (double v : row) scale = std::max(scale, std::fabs(v));
  }
  std::vector<SectionBranch> out;
  if (!(scale > 0)) return out;
  const double quad_scale = std::max({std::fabs(c[0][0]), std::fabs(c[0][1]), std::fabs(c[1][1])});
  if (quad_scale <= 1e-12 * scale) {
    AddLine(fr, {2 * q[3], 2 * q[4], q[5]}, &out);  // q is linear: one line
    return out;
  }
  const double det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1]) -
                     c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0]) +
                     c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
  if (std::fabs(det) <= 1e-10 * scale * scale * scale) {
    for (const auto& l : SplitLines(c)) AddLine(fr, {l[0] / r, l[1] / r, l[2]}, &out);
    return out;
  }
  double k[2] = {0, 0};
  if (known) {
    const Point3 d = Sub(*known, origin);
    k[0] = Dot(d, e1);
    k[1] = Dot(d, e2);
  } else if (!FindConicPoint(q, reach, k)) {
    return out;
  }
  const double coefficients[6] = {q[0], q[1], q[2], q[3], q[4], q[5]};
  out.push_back(SectionBranch::Conic(origin, e1, e2, coefficients, k));
  return out;
}

}  // namespace fdsurf::host
