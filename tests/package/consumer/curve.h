// SPDX-License-Identifier: MIT
// A 2-D Bézier curve stepped by the fixed-point core: (0,0) (0,300) (300,300)
// (300,0) quanta in 2 steps, so the points are (0,0) (150,225) (300,0).
#pragma once

#include <stdint.h>
#include <stdio.h>

#include "fdsurf/forward_difference.h"
#include "fdsurf/status.h"

inline int PrintBezierCurve() {
  using fdsurf::GeometryFixed;
  const int64_t control[2][4] = {{0, 0, 300, 300}, {0, 300, 300, 0}};
  fdsurf::CurveGeometry1 geometry[2];
  for (int c = 0; c < 2; ++c) {
    for (int k = 0; k < 4; ++k) {
      geometry[c].g[k] =
          GeometryFixed::FromRaw(control[c][k] * (int64_t{1} << fdsurf::kGeometryFracBits));
    }
  }
  fdsurf::PreparedCurve<2> curve;
  const fdsurf::Status status = fdsurf::PrepareCurve<2>(geometry, fdsurf::Basis::kBezier, 2,
                                                        fdsurf::PrepareOptions(), &curve);
  if (status != fdsurf::Status::kOk) {
    printf("prepare: %s\n", fdsurf::StatusMessage(status));
    return 1;
  }
  printf("curve:");
  if (curve.format.acc_bits == 64) {
    fdsurf::CurveStepper<int64_t, 2>(curve).ForEachPoint(
        [](uint32_t, const int32_t(&p)[2]) { printf(" %ld,%ld", long(p[0]), long(p[1])); });
  } else {
    fdsurf::CurveStepper<fdsurf::Int128, 2>(curve).ForEachPoint(
        [](uint32_t, const int32_t(&p)[2]) { printf(" %ld,%ld", long(p[0]), long(p[1])); });
  }
  printf("\n");
  return 0;
}
