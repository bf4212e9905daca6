// SPDX-License-Identifier: MIT
#include "fdsurf/host/reference.h"

#include <stdexcept>

namespace fdsurf::host {
namespace {

// Blending weights S·M for the parameter u: w[i] multiplies geometry row i.
std::array<double, 4> Weights(const BasisMatrix4& m, double u) {
  const double powers[4] = {u * u * u, u * u, u, 1.0};
  std::array<double, 4> w{};
  for (int i = 0; i < 4; ++i) {
    for (int r = 0; r < 4; ++r) w[i] += powers[r] * m[r][i];
  }
  return w;
}

Point3 Lerp(const Point3& a, const Point3& b, double u) {
  return {a[0] + (b[0] - a[0]) * u, a[1] + (b[1] - a[1]) * u, a[2] + (b[2] - a[2]) * u};
}

Point3 DeCasteljauCurve(std::array<Point3, 4> p, double u) {
  for (int level = 3; level > 0; --level) {
    for (int i = 0; i < level; ++i) p[i] = Lerp(p[i], p[i + 1], u);
  }
  return p[0];
}

}  // namespace

Point3 EvaluateDeCasteljau(const Patch& patch, double s, double t) {
  std::array<Point3, 4> column{};
  for (int i = 0; i < 4; ++i) column[i] = DeCasteljauCurve(patch.g[i], t);
  return DeCasteljauCurve(column, s);
}

// The basis matrices again, in floating point, so that the reference does not
// depend on the engine's integer tables (seed 004; Catmull & Rom 1974).
BasisMatrix4 ReferenceBasisMatrix(Basis basis) {
  switch (basis) {
    case Basis::kPower:
      return {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    case Basis::kHermite:
      return {{{2, -2, 1, 1}, {-3, 3, -2, -1}, {0, 0, 1, 0}, {1, 0, 0, 0}}};
    case Basis::kBezier:
      return {{{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}}};
    case Basis::kBSpline: {
      const double k = 1.0 / 6.0;
      return {{{-k, 3 * k, -3 * k, k},
               {3 * k, -6 * k, 3 * k, 0},
               {-3 * k, 0, 3 * k, 0},
               {k, 4 * k, k, 0}}};
    }
    case Basis::kCatmullRom:
      return {{{-0.5, 1.5, -1.5, 0.5}, {1, -2.5, 2, -0.5}, {-0.5, 0, 0.5, 0}, {0, 1, 0, 0}}};
  }
  throw std::invalid_argument("unknown basis");
}

Point3 EvaluateReference(const Patch& patch, double s, double t) {
  if (patch.basis == Basis::kBezier) return EvaluateDeCasteljau(patch, s, t);
  const BasisMatrix4 m = ReferenceBasisMatrix(patch.basis);
  const std::array<double, 4> ws = Weights(m, s);
  const std::array<double, 4> wt = Weights(m, t);
  Point3 p{};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double w = ws[i] * wt[j];
      for (int c = 0; c < 3; ++c) p[c] += w * patch.g[i][j][c];
    }
  }
  return p;
}

PowerCoefficients CoefficientsOf(const Patch& patch) {
  const BasisMatrix4 m = ReferenceBasisMatrix(patch.basis);
  PowerCoefficients result;
  for (int c = 0; c < 3; ++c) {
    double mg[4][4] = {};
    for (int a = 0; a < 4; ++a) {
      for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) mg[a][j] += m[a][i] * patch.g[i][j][c];
      }
    }
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        double sum = 0;
        for (int j = 0; j < 4; ++j) sum += mg[a][j] * m[b][j];
        result.c[a][b][c] = sum;
      }
    }
  }
  return result;
}

Point3 EvaluateHorner(const PowerCoefficients& coefficients, double s, double t) {
  Point3 p{};
  for (int c = 0; c < 3; ++c) {
    double rows[4];
    for (int a = 0; a < 4; ++a) {
      const auto& r = coefficients.c[a];
      rows[a] = ((r[0][c] * t + r[1][c]) * t + r[2][c]) * t + r[3][c];
    }
    p[c] = ((rows[0] * s + rows[1]) * s + rows[2]) * s + rows[3];
  }
  return p;
}

}  // namespace fdsurf::host
