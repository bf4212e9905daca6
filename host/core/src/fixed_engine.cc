// SPDX-License-Identifier: MIT
#include "fdsurf/host/fixed_engine.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace fdsurf::host {
namespace {

const char* const kAxisNames[3] = {"x", "y", "z"};

// λ² for λ = max over u in [0,1] of Σ|b_i(u)|, the blending functions of the
// basis (docs/precision.md, "Geometry conversion").
double LebesgueConstant(Basis basis) {
  switch (basis) {
    case Basis::kPower:
      return 16.0;
    case Basis::kHermite:
    case Basis::kCatmullRom:
      return 1.5625;
    case Basis::kBezier:
    case Basis::kBSpline:
      return 1.0;
  }
  return 16.0;
}

std::string Explain(Status status, const Patch& patch, int steps_s, int steps_t,
                    const PrepareOptions& options) {
  std::ostringstream why;
  why << patch.origin << ": the fixed-point engine cannot evaluate this patch on a " << steps_s
      << "x" << steps_t << " grid: ";
  switch (status) {
    case Status::kGridOutOfRange:
      why << "each grid dimension must be between 1 and " << kMaxPatchSteps;
      break;
    case Status::kGeometryOutOfRange:
      why << "the sum of its power coefficients, which bounds the surface, reaches ±2^31 "
             "quanta (the output range); use a larger quantum";
      break;
    case Status::kPrecisionUnreachable:
      why << "its differences need more than " << int{options.max_acc_bits}
          << " accumulator bits for the 0.51-quantum bound; use a larger quantum or a "
             "smaller grid";
      break;
    default:
      why << StatusMessage(status);
  }
  return why.str();
}

}  // namespace

PreparedPatch<3> PrepareFixedPatch(const Patch& patch, const Quantum& quantum, int steps_s,
                                   int steps_t, const PrepareOptions& options) {
  PatchGeometry1 geometry[3];
  // Checked here, before any rounding, so the message can name the value.
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      for (int c = 0; c < 3; ++c) {
        const double v = patch.g[i][j][c];
        const std::optional<GeometryFixed> g = ToGeometry(v, quantum);
        if (!g) {
          std::ostringstream why;
          why << patch.origin << ": geometry [" << i << "][" << j << "]." << kAxisNames[c] << " = "
              << v << " is " << (std::isfinite(v) ? "out of range" : "not finite")
              << ": at quantum " << quantum.Format(1)
              << " values must stay below 2^31 quanta in magnitude";
          throw EngineError(why.str());
        }
        geometry[c].g[i][j] = *g;
      }
    }
  }
  if (steps_s < 1 || steps_t < 1 || steps_s > kMaxPatchSteps || steps_t > kMaxPatchSteps) {
    throw EngineError(Explain(Status::kGridOutOfRange, patch, steps_s, steps_t, options));
  }
  PreparedPatch<3> prepared;
  const Status status = PreparePatch(geometry, patch.basis, static_cast<std::uint16_t>(steps_s),
                                     static_cast<std::uint16_t>(steps_t), options, &prepared);
  if (status != Status::kOk) {
    throw EngineError(Explain(status, patch, steps_s, steps_t, options));
  }
  return prepared;
}

double ErrorBoundBeforeRounding(const PreparedPatch<3>& patch, Basis basis) {
  const auto propagation = [](double n) {
    return 1 + n + n * (n - 1) / 2 + n * (n - 1) * (n - 2) / 6;
  };
  const double stepping = patch.exact ? 0.0
                                      : propagation(patch.steps_s) * propagation(patch.steps_t) *
                                            std::ldexp(1.0, -(patch.format.frac_bits + 1));
  // Per-line rounding: each of a line's 4 entries off by at most half a unit
  // of its format, propagated over the steps of one segment (a line is
  // re-rounded from its exact state at every segment's start).
  double line = 0;
  if (patch.s_line_frac_bits != 0) {
    line = propagation(patch.s_line_segment_steps) * std::ldexp(1.0, -(patch.s_line_frac_bits + 1));
  }
  if (patch.t_line_frac_bits != 0) {
    line = std::max(line, propagation(patch.t_line_segment_steps) *
                              std::ldexp(1.0, -(patch.t_line_frac_bits + 1)));
  }
  const double conversion = LebesgueConstant(basis) * (std::ldexp(1.0, -17) + std::ldexp(1.0, -20));
  return stepping + line + conversion;
}

}  // namespace fdsurf::host
