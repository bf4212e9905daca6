// SPDX-License-Identifier: MIT
// The measured loops: the engine's steppers and the alternatives a firmware
// author would otherwise write, all producing whole-quantum points from the
// same cubic. Each loop runs between two PortMark() calls; the emulator counts
// cycles (simavr) or guest instructions (QEMU plugin) between them, and the
// image prints one "bench" line per loop with the number of points, so that
// targets/tools/bench_report.py can divide.
#pragma once

#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"
#include "inputs.h"

namespace fdsurf {
namespace image {

/// Steps of the bench curves: 257 points, as a G5 segment split finely.
constexpr uint16_t kBenchSteps = 256;
/// Steps of the wide bench curve: with about 2^27 quanta of geometry, this
/// many steps need the 128-bit accumulator.
constexpr uint16_t kBenchWideSteps = 4096;
/// Grid of the bench patches: 17×17 points.
constexpr uint16_t kBenchGrid = 16;
/// The teapot patch of the patch benches (a body patch).
constexpr int kBenchTeapotPatch = 5;
/// Lines per family of the validation bench's PATCH frame. A frame may ask
/// for 1025; the cost is the same for every line of this frame, and 1025
/// takes simavr over 4 minutes (docs/motion.md quotes both).
constexpr uint16_t kBenchValidateLines = 65;

/// The bench curve: a cubic Bézier about 60 mm long at Q = 1 µm (quanta), in
/// raw GeometryFixed units. `wide` scales it to about 2^27 quanta, where the
/// planner needs 128-bit accumulators.
int64_t BenchControlRaw(int coordinate, int k, bool wide);

template <int kDims>
void BenchCurveGeometry(bool wide, CurveGeometry1 (&geometry)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k)
      geometry[c].g[k] = GeometryFixed::FromRaw(BenchControlRaw(c, k, wide));
  }
}

/// Where the bench gets its prepared tables: set up on the target, or read
/// from host-prepared tables (ATmega328P).
struct BenchSource {
  void (*curve2)(bool wide, PreparedCurve<2>* out);
  void (*curve3)(PreparedCurve<3>* out);  // nullptr: not on this target
  void (*patch2)(PreparedPatch<2>* out);
  void (*patch3)(PreparedPatch<3>* out);  // nullptr: not on this target
  void (*adaptive2)(PreparedAdaptiveCurve<2>* out);
  bool measure_setup;
  /// Whether to measure the 128-bit accumulator (the wide curve).
  bool wide;
  /// Whether to measure the 2-D curve's row-add and rounding apart
  /// (engine-step-only, engine-round-only). The ATmega328P image has no
  /// room for that code or for the 3-D curve bench
  /// (FDSURF_IMAGE_SMALL_BENCH); the host's --small leaves them out too.
  bool parts;
};

/// Runs every measured loop and prints its bench line.
void RunBench(const BenchSource& source);

#if FDSURF_IMAGE_SETUP
/// The set-up side of BenchSource (targets that carry the set-up code).
void SetupBenchCurve2(bool wide, PreparedCurve<2>* out);
void SetupBenchCurve3(PreparedCurve<3>* out);
void SetupBenchPatch2(PreparedPatch<2>* out);
void SetupBenchPatch3(PreparedPatch<3>* out);
void SetupBenchAdaptive2(PreparedAdaptiveCurve<2>* out);
#endif

}  // namespace image
}  // namespace fdsurf
