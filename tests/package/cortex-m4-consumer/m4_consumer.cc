// SPDX-License-Identifier: MIT
// Steps a 2-D Bézier curve with the fdsurf core on a Cortex-M4: what a
// plotter firmware does with each curve it receives. The points go to a
// volatile sink so that nothing is optimised away.
#include <stdint.h>

#include "fdsurf/forward_difference.h"
#include "fdsurf/status.h"

volatile int32_t g_last[2];
volatile uint32_t g_points;

int main() {
  const int64_t control[2][4] = {{0, 0, 300, 300}, {0, 300, 300, 0}};
  fdsurf::CurveGeometry1 geometry[2];
  for (int c = 0; c < 2; ++c) {
    for (int k = 0; k < 4; ++k) {
      geometry[c].g[k] =
          fdsurf::GeometryFixed::FromRaw(control[c][k] * (int64_t{1} << fdsurf::kGeometryFracBits));
    }
  }
  fdsurf::PreparedCurve<2> curve;
  if (fdsurf::PrepareCurve<2>(geometry, fdsurf::Basis::kBezier, 64, fdsurf::PrepareOptions(),
                              &curve) != fdsurf::Status::kOk) {
    return 1;
  }
  const auto sink = [](uint32_t, const int32_t(&p)[2]) {
    g_last[0] = p[0];
    g_last[1] = p[1];
    g_points = g_points + 1;
  };
  if (curve.format.acc_bits == 64) {
    fdsurf::CurveStepper<int64_t, 2>(curve).ForEachPoint(sink);
  } else {
    fdsurf::CurveStepper<fdsurf::Int128, 2>(curve).ForEachPoint(sink);
  }
  return g_points == 65 ? 0 : 1;
}
