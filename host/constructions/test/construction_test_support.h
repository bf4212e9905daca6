// SPDX-License-Identifier: MIT
// Helpers shared by the construction tests (docs/constructions.md): every
// test checks a defining property against the construction's formula
// evaluated here again in double, not against the code under test, and the
// engine's bound on the result.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {

inline double Distance(const Point3& a, const Point3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

inline std::string InputErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// The largest |fixed − reference| in quanta over a grid, for every patch.
inline double WorstFixedError(const PatchSet& set, int n, int m, const Quantum& q) {
  double worst = 0;
  for (const Patch& patch : set.patches) {
    const PreparedPatch<3> prepared = PrepareFixedPatch(patch, q, n, m);
    ForEachGridPoint(prepared, [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      const Point3 exact =
          EvaluateReference(patch, static_cast<double>(i) / n, static_cast<double>(j) / m);
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(k[c] - q.ToQuanta(exact[c])));
    });
  }
  return worst;
}

inline Curve BezierCurve(const std::array<Point3, 4>& p) {
  Curve c;
  c.basis = Basis::kBezier;
  c.g = p;
  return c;
}

inline PatchSet AsSet(const PolySurface& surface) {
  PatchSet set;
  AppendPatches(surface, 1, "test", &set.patches);
  return set;
}

// One-sided second-order difference of the patch along s (dir 0) or t at a
// boundary: forward from 0 or backward from 1.
inline Point3 Derivative(const Patch& p, double s, double t, int dir) {
  const double h = 1e-4;
  const double sign = (dir == 0 ? s : t) == 0 ? 1 : -1;
  const auto at = [&](double k) {
    return dir == 0 ? EvaluateReference(p, s + sign * k * h, t)
                    : EvaluateReference(p, s, t + sign * k * h);
  };
  Point3 d{};
  for (int c = 0; c < 3; ++c) d[c] = sign * (-3 * at(0)[c] + 4 * at(1)[c] - at(2)[c]) / (2 * h);
  return d;
}

// A flat Bézier patch on [x0, x0 + 3·w] × [0, 3] with control columns spaced
// by w, and z bumps on the inner points.
inline Patch FlatPatch(double x0, double w, double z_first_inner, double z_last_inner) {
  Patch p;
  p.basis = Basis::kBezier;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) p.g[i][j] = {x0 + w * i, static_cast<double>(j), 0};
  }
  for (int j = 0; j < 4; ++j) {
    p.g[1][j][2] = z_first_inner;
    p.g[2][j][2] = z_last_inner;
  }
  return p;
}

}  // namespace fdsurf::host
