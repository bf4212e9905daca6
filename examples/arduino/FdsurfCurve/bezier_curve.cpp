// SPDX-License-Identifier: MIT
#include "bezier_curve.h"

#include <fdsurf.h>

namespace {

CurvePointSink g_sink;

template <typename Acc>
void Step(const fdsurf::PreparedCurve<2>& curve) {
  fdsurf::CurveStepper<Acc, 2>(curve).ForEachPoint(
      [](uint32_t i, const int32_t(&p)[2]) { g_sink(static_cast<uint16_t>(i), p[0], p[1]); });
}

}  // namespace

bool StepBezierCurve(const int32_t (&x)[4], const int32_t (&y)[4], uint16_t steps,
                     CurvePointSink sink) {
  fdsurf::CurveGeometry1 geometry[2];
  for (int k = 0; k < 4; ++k) {
    geometry[0].g[k] = fdsurf::GeometryFixed::FromRaw(static_cast<int64_t>(x[k]) *
                                                      (int64_t{1} << fdsurf::kGeometryFracBits));
    geometry[1].g[k] = fdsurf::GeometryFixed::FromRaw(static_cast<int64_t>(y[k]) *
                                                      (int64_t{1} << fdsurf::kGeometryFracBits));
  }
  // The 128-bit accumulator is slow on an 8-bit AVR; a curve that needs it
  // is refused instead.
  fdsurf::PrepareOptions options;
  options.max_acc_bits = 64;
  fdsurf::PreparedCurve<2> curve;
  if (fdsurf::PrepareCurve<2>(geometry, fdsurf::Basis::kBezier, steps, options, &curve) !=
      fdsurf::Status::kOk) {
    return false;
  }
  g_sink = sink;
  Step<int64_t>(curve);
  return true;
}
