// SPDX-License-Identifier: MIT
// The double-precision reference evaluation.
//
// Shares no code with the fixed-point engine: Bézier patches are evaluated by
// de Casteljau's algorithm, every other basis directly as S·M·G·Mᵀ·Tᵀ with
// the basis matrices written out here again in floating point. Tests and
// `fdsurf check` measure the engine against it.
#pragma once

#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// A basis matrix M in floating point (row r multiplies u^(3-r)), typed in
/// again here so that the reference shares nothing with the engine's integer
/// tables. Throws std::invalid_argument for a value outside the enum.
using BasisMatrix4 = std::array<std::array<double, 4>, 4>;
BasisMatrix4 ReferenceBasisMatrix(Basis basis);

/// The point of `patch` at parameters (s, t), s, t in [0, 1].
Point3 EvaluateReference(const Patch& patch, double s, double t);

/// Horner evaluation of S·C·Tᵀ from the patch's power coefficients, which are
/// computed once by CoefficientsOf. Used as a speed baseline.
struct PowerCoefficients {
  std::array<std::array<Point3, 4>, 4> c{};
};
PowerCoefficients CoefficientsOf(const Patch& patch);
Point3 EvaluateHorner(const PowerCoefficients& coefficients, double s, double t);

/// De Casteljau on a Bézier patch (also a speed baseline).
Point3 EvaluateDeCasteljau(const Patch& bezier_patch, double s, double t);

}  // namespace fdsurf::host
