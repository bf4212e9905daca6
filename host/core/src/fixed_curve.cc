// SPDX-License-Identifier: MIT
#include "fdsurf/host/fixed_curve.h"

#include <cmath>
#include <sstream>

namespace fdsurf::host {

PreparedCurve<3> PrepareFixedCurve(const Curve& curve, const Quantum& quantum, int steps,
                                   const PrepareOptions& options) {
  static const char* const kAxisNames[3] = {"x", "y", "z"};
  CurveGeometry1 geometry[3];
  for (int k = 0; k < 4; ++k) {
    for (int c = 0; c < 3; ++c) {
      const double v = curve.g[k][c];
      const std::optional<GeometryFixed> g = ToGeometry(v, quantum);
      if (!g) {
        std::ostringstream why;
        why << curve.origin << ": geometry [" << k << "]." << kAxisNames[c] << " = " << v << " is "
            << (std::isfinite(v) ? "out of range" : "not finite") << ": at quantum "
            << quantum.Format(1) << " values must stay below 2^31 quanta in magnitude";
        throw EngineError(why.str());
      }
      geometry[c].g[k] = *g;
    }
  }
  if (steps < 1 || steps > kMaxCurveSteps) {
    throw EngineError(curve.origin + ": a curve takes 1 to " + std::to_string(kMaxCurveSteps) +
                      " steps, got " + std::to_string(steps));
  }
  PreparedCurve<3> prepared;
  const Status status =
      PrepareCurve(geometry, curve.basis, static_cast<std::uint16_t>(steps), options, &prepared);
  if (status != Status::kOk) {
    throw EngineError(curve.origin + ": the fixed-point engine cannot evaluate this curve in " +
                      std::to_string(steps) + " steps: " + StatusMessage(status) +
                      "; use a larger quantum");
  }
  return prepared;
}

}  // namespace fdsurf::host
