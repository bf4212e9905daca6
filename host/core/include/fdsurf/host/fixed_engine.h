// SPDX-License-Identifier: MIT
// Host glue for the fixed-point engine: converts a double-precision patch to
// the engine's geometry format for a quantum, plans it, and steps it with the
// accumulator width the plan chose.
#pragma once

#include <cstdint>
#include <string>

#include "fdsurf/forward_difference.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quantum.h"

namespace fdsurf::host {

/// Converts `patch` into quanta with kGeometryFracBits guard bits and prepares
/// it for a steps_s × steps_t grid. Throws EngineError (naming patch.origin)
/// when a coordinate is not finite or too large, or the engine cannot serve
/// the grid within the bound.
PreparedPatch<3> PrepareFixedPatch(const Patch& patch, const Quantum& quantum, int steps_s,
                                   int steps_t, const PrepareOptions& options = {});

/// Steps a prepared patch along s-lines (the grid, i-major) with a 64-bit
/// inner loop where the plan allows it: the per-line rounding
/// (LinePatchStepper) where the plan has the lines' format (every table
/// with more than 32 fractional bits whose lines fit 64 bits), else the
/// table's own accumulator. sink(i, j, const int32_t (&)[3]).
template <typename Sink>
void ForEachGridPoint(const PreparedPatch<3>& patch, Sink&& sink) {
  if (patch.s_line_frac_bits != 0) {
    LinePatchStepper<3>(patch).ForEachSLinePoint(sink);
  } else if (patch.format.acc_bits == 64) {
    PatchStepper<std::int64_t, 3>(patch).ForEachSLinePoint(sink);
  } else {
    PatchStepper<Int128, 3>(patch).ForEachSLinePoint(sink);
  }
}

/// As above along t-lines.
template <typename Sink>
void ForEachTLinePoint(const PreparedPatch<3>& patch, Sink&& sink) {
  if (patch.t_line_frac_bits != 0) {
    LinePatchStepper<3>(patch).ForEachTLinePoint(sink);
  } else if (patch.format.acc_bits == 64) {
    PatchStepper<std::int64_t, 3>(patch).ForEachTLinePoint(sink);
  } else {
    PatchStepper<Int128, 3>(patch).ForEachTLinePoint(sink);
  }
}

/// A rigorous a-priori bound (in quanta) of |fixed − exact| before the final
/// rounding to whole quanta, for this basis and grid, as ForEachGridPoint and
/// ForEachTLinePoint step it: the stepping term S(n)·S(m)·2^-(F+1), the
/// per-line rounding term S(line steps)·2^-(F_line+1) when a family uses it
/// (the larger of the two families'), plus the geometry conversion term
/// L·(2^-17 + 2^-20) (docs/precision.md). The emitted positions are within
/// 0.5 + this.
double ErrorBoundBeforeRounding(const PreparedPatch<3>& patch, Basis basis);

}  // namespace fdsurf::host
