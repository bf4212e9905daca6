// SPDX-License-Identifier: MIT
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

// Each item is set up in its own (not inlined) function, so that its
// geometry and table leave the stack before the next item: the set-up alone
// needs about 6 KB of stack on AVR, and the ATmega2560 has 8 KB of RAM.
#define FDSURF_ITEM __attribute__((noinline))

template <int kDims, typename Visitor>
FDSURF_ITEM void TeapotPatchItem(Visitor& v, bool small, const char* name, uint16_t index,
                                 int patch, uint16_t steps_s, uint16_t steps_t) {
  PatchGeometry1 geometry[kDims];
  TeapotGeometry(patch, geometry);
  PreparedPatch<kDims> prepared{};
  const Status status =
      PreparePatch(geometry, Basis::kBezier, steps_s, steps_t, PrepareOptions(), &prepared);
  v.Patch(small, name, index, status, prepared);
}

template <int kDims, typename Visitor>
FDSURF_ITEM void RandomPatchItem(Visitor& v, bool small, const char* name, uint16_t index,
                                 Xorshift32& random, int bits, Basis basis, uint16_t steps_s,
                                 uint16_t steps_t) {
  PatchGeometry1 geometry[kDims];
  RandomPatch(random, bits, geometry);
  PreparedPatch<kDims> prepared{};
  const Status status =
      PreparePatch(geometry, basis, steps_s, steps_t, PrepareOptions(), &prepared);
  v.Patch(small, name, index, status, prepared);
}

template <int kDims, typename Visitor>
FDSURF_ITEM void RandomCurveItem(Visitor& v, bool small, const char* name, uint16_t index,
                                 Xorshift32& random, int bits, Basis basis, uint16_t steps) {
  CurveGeometry1 geometry[kDims];
  RandomCurve(random, bits, geometry);
  PreparedCurve<kDims> prepared{};
  const Status status = PrepareCurve(geometry, basis, steps, PrepareOptions(), &prepared);
  v.Curve(small, name, index, status, prepared);
}

template <int kDims, typename Visitor>
FDSURF_ITEM void RandomAdaptiveItem(Visitor& v, bool small, uint16_t index, Xorshift32& random,
                                    int bits, Basis basis, const AdaptiveSettings& settings) {
  CurveGeometry1 geometry[kDims];
  RandomCurve(random, bits, geometry);
  PowerCurve1 power[kDims];
  PreparedAdaptiveCurve<kDims> prepared{};
  Status status = CurvePowerCoefficients(geometry, basis, power);
  if (status == Status::kOk) status = PrepareAdaptiveCurve(power, settings, &prepared);
  v.Adaptive(small, FDSURF_TEXT("random"), index, status, prepared);
}

/// Set-up of teapot patches: 3-D s- and t-line grids, plus the top view at
/// 8×8 (small set).
template <typename Visitor>
void TeapotCases(Visitor& v) {
  static const uint16_t kGrids[][2] = {{1, 1}, {4, 4}, {8, 8}, {16, 16}, {3, 7}, {64, 64}};
  for (const auto& grid : kGrids) {
    // 64×64 for every eighth patch keeps the slowest emulator within seconds.
    const int step = grid[0] == 64 ? 8 : 1;
    for (int p = 0; p < kTeapotPatches; p += step) {
      TeapotPatchItem<3>(
          v, false, grid[0] == grid[1] ? FDSURF_TEXT("teapot-square") : FDSURF_TEXT("teapot-3x7"),
          static_cast<uint16_t>(p * 100 + grid[0]), p, grid[0], grid[1]);
    }
  }
  for (int p = 0; p < 8; ++p) {
    // The first two in the small set.
    TeapotPatchItem<2>(v, p < 2, FDSURF_TEXT("teapot-top-8x8"), static_cast<uint16_t>(p), p, 8, 8);
  }
}

/// Random patches of every basis, 2-D and 3-D, three geometry sizes.
template <typename Visitor>
void RandomPatchCases(Visitor& v) {
  Xorshift32 random(0x2545F491u);
  static const int kBits[] = {kSmallBits, kLargeBits, kHugeBits};
  uint16_t index = 0;
  for (int b = 0; b < kBasisCount; ++b) {
    for (const int bits : kBits) {
      // Power, Bézier and Catmull-Rom at the small size in the small set.
      const bool small = bits == kSmallBits && b % 2 == 0;
      RandomPatchItem<2>(v, small, FDSURF_TEXT("random-7x5"), index++, random, bits, BasisAt(b), 7,
                         5);
      RandomPatchItem<3>(v, false, FDSURF_TEXT("random-32x20"), index++, random, bits, BasisAt(b),
                         32, 20);
    }
  }
}

/// Random curves of every basis, 2-D and 3-D, from 1 step to 65535.
template <typename Visitor>
void RandomCurveCases(Visitor& v) {
  Xorshift32 random(0x9E3779B9u);
  static const uint16_t kSteps[] = {1, 10, 100, 1000};
  static const int kBits[] = {kSmallBits, kHugeBits};
  uint16_t index = 0;
  for (int b = 0; b < kBasisCount; ++b) {
    for (const uint16_t steps : kSteps) {
      for (const int bits : kBits) {
        const bool small = steps == 100 && bits == kSmallBits;
        RandomCurveItem<2>(v, small, FDSURF_TEXT("random"), index++, random, bits, BasisAt(b),
                           steps);
        RandomCurveItem<3>(v, small, FDSURF_TEXT("random"), index++, random, bits, BasisAt(b),
                           steps);
      }
    }
  }
  // Long curves with 128-bit accumulators: the longest allowed, and a huge
  // geometry at 4096 steps.
  for (const int bits : kBits) {
    const uint16_t steps = bits == kSmallBits ? kMaxCurveSteps : 4096;
    RandomCurveItem<2>(v, false, FDSURF_TEXT("long"), index++, random, bits, Basis::kBezier, steps);
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
      RandomAdaptiveItem<2>(v, false, index++, random, bits, BasisAt(b), settings);
      RandomAdaptiveItem<3>(v, false, index++, random, bits, BasisAt(b), settings);
    }
  }
}

/// One isoline family of one teapot patch, as `fdsurf plot` draws it: 5
/// lines from the walker, each stepped adaptively within 0.05 mm (50 quanta).
template <int kDims, typename Visitor>
FDSURF_ITEM void WalkerFamily(Visitor& v, bool small, int patch, IsolineFamily family) {
  AdaptiveSettings settings;
  settings.tolerance_q8 = 50 * 256;
  PatchGeometry1 geometry[kDims];
  TeapotGeometry(patch, geometry);
  IsolineWalker<kDims> walker;
  const Status status = IsolineWalker<kDims>::Create(geometry, Basis::kBezier, family, 5, &walker);
  const uint16_t base = static_cast<uint16_t>(patch * 100 + static_cast<int>(family) * 10);
  if (status != Status::kOk) {
    PreparedAdaptiveCurve<kDims> none{};
    v.Adaptive(small, FDSURF_TEXT("walker"), base, status, none);
    return;
  }
  PowerCurve1 line[kDims];
  for (uint16_t i = 0; walker.Next(line); ++i) {
    v.Coefficients(small, FDSURF_TEXT("walker"), static_cast<uint16_t>(base + i), line);
    PreparedAdaptiveCurve<kDims> prepared{};
    const Status line_status = PrepareAdaptiveCurve(line, settings, &prepared);
    v.Adaptive(small, FDSURF_TEXT("walker"), static_cast<uint16_t>(base + i), line_status,
               prepared);
  }
}

/// small: the first patch's lines are in the small set.
template <int kDims, typename Visitor>
void WalkerCases(Visitor& v, int first_patch, int patch_step, bool small) {
  for (int p = first_patch; p < kTeapotPatches; p += patch_step) {
    WalkerFamily<kDims>(v, small && p == first_patch, p, IsolineFamily::kSLines);
    WalkerFamily<kDims>(v, small && p == first_patch, p, IsolineFamily::kTLines);
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
