// SPDX-License-Identifier: MIT
// Host glue for curves: a double-precision cubic curve converted to the
// engine's geometry format and stepped by the core's CurveStepper, exactly as
// fixed_engine.h does for patches.
#pragma once

#include <cstdint>

#include "fdsurf/forward_difference.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quantum.h"

namespace fdsurf::host {

/// Converts `curve` into quanta with kGeometryFracBits guard bits and prepares
/// it for `steps` steps (1..kMaxCurveSteps). Throws EngineError naming
/// curve.origin when a coordinate is not finite or too large, or the engine
/// cannot serve the request within the 0.51-quantum bound.
PreparedCurve<3> PrepareFixedCurve(const Curve& curve, const Quantum& quantum, int steps,
                                   const PrepareOptions& options = {});

/// Steps a prepared curve with the accumulator the plan chose:
/// sink(i, const int32_t (&)[3]) for i = 0..steps.
template <typename Sink>
void ForEachCurvePoint(const PreparedCurve<3>& curve, Sink&& sink) {
  if (curve.format.acc_bits == 64) {
    CurveStepper<std::int64_t, 3>(curve).ForEachPoint(sink);
  } else {
    CurveStepper<Int128, 3>(curve).ForEachPoint(sink);
  }
}

}  // namespace fdsurf::host
