// SPDX-License-Identifier: MIT
// Size group "engine": set-up and stepping, everything a device that receives
// geometry links: PreparePatch/PrepareCurve (2-D, 3-D), the adaptive set-up
// and the isoline walker, and every stepper (size/stepping.cc).
#include "../image/image.h"
#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"

namespace fdsurf {
namespace image {

void RunSteppers();

namespace {

// Geometry the compiler cannot see through.
template <int kDims>
struct Inputs {
  static PatchGeometry1 patch[kDims];
  static CurveGeometry1 curve[kDims];
};
template <int kDims>
PatchGeometry1 Inputs<kDims>::patch[kDims];
template <int kDims>
CurveGeometry1 Inputs<kDims>::curve[kDims];
volatile uint16_t g_steps = 16;
volatile uint8_t g_basis = 2;

template <int kDims>
Status SetUp() {
  const PatchGeometry1(&patch)[kDims] = Inputs<kDims>::patch;
  const CurveGeometry1(&curve)[kDims] = Inputs<kDims>::curve;
  const Basis basis = static_cast<Basis>(g_basis);
  PreparedPatch<kDims> prepared_patch;
  Status status = PreparePatch(patch, basis, g_steps, g_steps, PrepareOptions(), &prepared_patch);
  PreparedCurve<kDims> prepared_curve;
  if (status == Status::kOk) {
    status = PrepareCurve(curve, basis, g_steps, PrepareOptions(), &prepared_curve);
  }
  PowerCurve1 power[kDims];
  if (status == Status::kOk) status = CurvePowerCoefficients(curve, basis, power);
  PreparedAdaptiveCurve<kDims> adaptive;
  if (status == Status::kOk) status = PrepareAdaptiveCurve(power, AdaptiveSettings(), &adaptive);
  IsolineWalker<kDims> walker;
  if (status == Status::kOk) {
    status = IsolineWalker<kDims>::Create(patch, basis, IsolineFamily::kSLines, g_steps, &walker);
  }
  if (status == Status::kOk) walker.Next(power);
  return status;
}

}  // namespace

int RunImage(bool) {
  const Status status2 = SetUp<2>();
  const Status status3 = SetUp<3>();
  RunSteppers();
  return static_cast<int>(status2) + static_cast<int>(status3);
}

}  // namespace image
}  // namespace fdsurf
