// The fixed input set, set up with the engine and handed to a visitor (the
// Reporter on every target; on the host also the table writer that feeds the
// ATmega328P image, targets/tools/). Each item is marked small when it is part
// of the reduced set that the 328P steps from host-prepared tables.
#pragma once

#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"
#include "inputs.h"

namespace fdsurf {
namespace image {

/// Teapot patch `patch` as geometry; with kDims == 2 the top view (x, y).
template <int kDims>
void TeapotGeometry(int patch, PatchGeometry1 (&geometry)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 16; ++k) {
      geometry[c].g[k / 4][k % 4] = GeometryFixed::FromRaw(TeapotRaw(patch, c, k));
    }
  }
}

template <int kDims>
void RandomPatch(Xorshift32& random, int bits, PatchGeometry1 (&geometry)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 16; ++k) {
      geometry[c].g[k / 4][k % 4] = GeometryFixed::FromRaw(random.Raw(bits));
    }
  }
}

template <int kDims>
void RandomCurve(Xorshift32& random, int bits, CurveGeometry1 (&geometry)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k) geometry[c].g[k] = GeometryFixed::FromRaw(random.Raw(bits));
  }
}

inline Basis BasisAt(int i) { return static_cast<Basis>(i); }

// Geometry sizes as raw bits: 2^(bits-16) quanta.
constexpr int kSmallBits = 16 + 12;  // ±4096 quanta (±4 mm at Q = 1 µm)
constexpr int kLargeBits = 16 + 20;  // ±2^20 quanta, the edge of the promise
constexpr int kHugeBits = 16 + 26;   // ±2^26 quanta: 128-bit accumulators or a refusal

/// Set-up of teapot patches: 3-D s- and t-line grids, plus the top view at
/// 8×8 (small set).
template <typename Visitor>
void TeapotCases(Visitor& v) {
  const PrepareOptions options;
  static const uint16_t kGrids[][2] = {{1, 1}, {4, 4}, {8, 8}, {16, 16}, {3, 7}, {64, 64}};
  for (const auto& grid : kGrids) {
    // 64×64 for a third of the patches keeps the slowest emulator under a minute.
    const int step = grid[0] == 64 ? 3 : 1;
    for (int p = 0; p < kTeapotPatches; p += step) {
      PatchGeometry1 geometry[3];
      TeapotGeometry(p, geometry);
      PreparedPatch<3> prepared{};
      const Status status =
          PreparePatch(geometry, Basis::kBezier, grid[0], grid[1], options, &prepared);
      v.Patch(false, grid[0] == grid[1] ? "teapot-square" : "teapot-3x7",
              static_cast<uint16_t>(p * 100 + grid[0]), status, prepared);
    }
  }
  for (int p = 0; p < 8; ++p) {
    PatchGeometry1 geometry[2];
    TeapotGeometry(p, geometry);
    PreparedPatch<2> prepared{};
    const Status status = PreparePatch(geometry, Basis::kBezier, 8, 8, options, &prepared);
    v.Patch(true, "teapot-top-8x8", static_cast<uint16_t>(p), status, prepared);
  }
}

/// Random patches of every basis, 2-D and 3-D, three geometry sizes.
template <typename Visitor>
void RandomPatchCases(Visitor& v) {
  Xorshift32 random(0x2545F491u);
  const PrepareOptions options;
  static const int kBits[] = {kSmallBits, kLargeBits, kHugeBits};
  uint16_t index = 0;
  for (int b = 0; b < kBasisCount; ++b) {
    for (const int bits : kBits) {
      {
        PatchGeometry1 geometry[2];
        RandomPatch(random, bits, geometry);
        PreparedPatch<2> prepared{};
        const Status status = PreparePatch(geometry, BasisAt(b), 7, 5, options, &prepared);
        v.Patch(bits == kSmallBits, "random-7x5", index++, status, prepared);
      }
      {
        PatchGeometry1 geometry[3];
        RandomPatch(random, bits, geometry);
        PreparedPatch<3> prepared{};
        const Status status = PreparePatch(geometry, BasisAt(b), 32, 20, options, &prepared);
        v.Patch(false, "random-32x20", index++, status, prepared);
      }
    }
  }
}

/// Random curves of every basis, 2-D and 3-D, from 1 step to 65535.
template <typename Visitor>
void RandomCurveCases(Visitor& v) {
  Xorshift32 random(0x9E3779B9u);
  const PrepareOptions options;
  static const uint16_t kSteps[] = {1, 10, 100, 1000};
  static const int kBits[] = {kSmallBits, kHugeBits};
  uint16_t index = 0;
  for (int b = 0; b < kBasisCount; ++b) {
    for (const uint16_t steps : kSteps) {
      for (const int bits : kBits) {
        const bool small = steps == 100;
        {
          CurveGeometry1 geometry[2];
          RandomCurve(random, bits, geometry);
          PreparedCurve<2> prepared{};
          const Status status = PrepareCurve(geometry, BasisAt(b), steps, options, &prepared);
          v.Curve(small, "random", index++, status, prepared);
        }
        {
          CurveGeometry1 geometry[3];
          RandomCurve(random, bits, geometry);
          PreparedCurve<3> prepared{};
          const Status status = PrepareCurve(geometry, BasisAt(b), steps, options, &prepared);
          v.Curve(small, "random", index++, status, prepared);
        }
      }
    }
  }
  // The longest curves: 65536 points, 128-bit accumulators at the huge size.
  for (const int bits : kBits) {
    CurveGeometry1 geometry[2];
    RandomCurve(random, bits, geometry);
    PreparedCurve<2> prepared{};
    const Status status =
        PrepareCurve(geometry, Basis::kBezier, kMaxCurveSteps, options, &prepared);
    v.Curve(true, "long", index++, status, prepared);
  }
}

/// Adaptive forward differencing of random curves of every basis: within a
/// tolerance, and step-exact.
template <typename Visitor>
void AdaptiveCases(Visitor& v) {
  Xorshift32 random(0x6C078965u);
  uint16_t index = 0;
  for (int b = 0; b < kBasisCount; ++b) {
    for (int mode = 0; mode < 2; ++mode) {
      AdaptiveSettings settings;
      settings.mode = mode == 0 ? AdaptiveMode::kTolerance : AdaptiveMode::kStepExact;
      settings.tolerance_q8 = 2 * 256;  // 2 quanta
      // Step-exact emits about one point per quantum of path: small geometry.
      const int bits = mode == 0 ? kLargeBits : 16 + 9;
      {
        CurveGeometry1 geometry[2];
        RandomCurve(random, bits, geometry);
        PowerCurve1 power[2];
        PreparedAdaptiveCurve<2> prepared{};
        Status status = CurvePowerCoefficients(geometry, BasisAt(b), power);
        if (status == Status::kOk) status = PrepareAdaptiveCurve(power, settings, &prepared);
        v.Adaptive(true, "random", index++, status, prepared);
      }
      {
        CurveGeometry1 geometry[3];
        RandomCurve(random, bits, geometry);
        PowerCurve1 power[3];
        PreparedAdaptiveCurve<3> prepared{};
        Status status = CurvePowerCoefficients(geometry, BasisAt(b), power);
        if (status == Status::kOk) status = PrepareAdaptiveCurve(power, settings, &prepared);
        v.Adaptive(false, "random", index++, status, prepared);
      }
    }
  }
}

/// The isoline walker on teapot patches (what `fdsurf plot` draws): 5 s-lines
/// and 5 t-lines per patch, each stepped adaptively within 0.05 mm (50 quanta).
template <int kDims, typename Visitor>
void WalkerCases(Visitor& v, int first_patch, int patch_step, bool small) {
  AdaptiveSettings settings;
  settings.tolerance_q8 = 50 * 256;
  for (int p = first_patch; p < kTeapotPatches; p += patch_step) {
    PatchGeometry1 geometry[kDims];
    TeapotGeometry(p, geometry);
    for (int family = 0; family < 2; ++family) {
      IsolineWalker<kDims> walker;
      const Status status = IsolineWalker<kDims>::Create(
          geometry, Basis::kBezier, static_cast<IsolineFamily>(family), 5, &walker);
      const uint16_t base = static_cast<uint16_t>(p * 100 + family * 10);
      if (status != Status::kOk) {
        PreparedAdaptiveCurve<kDims> none{};
        v.Adaptive(small, "walker", base, status, none);
        continue;
      }
      PowerCurve1 line[kDims];
      for (uint16_t i = 0; walker.Next(line); ++i) {
        v.Coefficients(small, "walker", static_cast<uint16_t>(base + i), line);
        PreparedAdaptiveCurve<kDims> prepared{};
        const Status line_status = PrepareAdaptiveCurve(line, settings, &prepared);
        v.Adaptive(small, "walker", static_cast<uint16_t>(base + i), line_status, prepared);
      }
    }
  }
}

template <typename Visitor>
void RunCases(Visitor& v) {
  TeapotCases(v);
  RandomPatchCases(v);
  RandomCurveCases(v);
  AdaptiveCases(v);
  WalkerCases<3>(v, 0, 1, false);
  WalkerCases<2>(v, 0, 8, true);
}

}  // namespace image
}  // namespace fdsurf
