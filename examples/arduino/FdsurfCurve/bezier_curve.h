// SPDX-License-Identifier: MIT
// Steps one 2-D cubic Bézier curve with the fdsurf core and hands each point
// to a callback: the set-up runs once, then every point costs additions only.
#pragma once

#include <stdint.h>

/// Called for point i = 0..steps with its coordinates in quanta (e.g. motor steps).
typedef void (*CurvePointSink)(uint16_t i, int32_t x, int32_t y);

/// The curve with control points (x[k], y[k]), k = 0..3, in quanta, in
/// `steps` equal parameter steps. Returns false (and calls nothing) if the
/// core refuses it, e.g. for 0 steps or coordinates beyond ±2^31 quanta.
bool StepBezierCurve(const int32_t (&x)[4], const int32_t (&y)[4], uint16_t steps,
                     CurvePointSink sink);
