// SPDX-License-Identifier: MIT
// Host-prepared tables for images without the set-up code (ATmega328P: the
// set-up alone exceeds its 32 KB of flash and 2 KB of RAM). The host reference
// program writes them (fdsurf_image_host --emit-tables) from the same set-up
// code; the image only steps them, as a device that receives tables does.
#pragma once

#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"
#include "port.h"

namespace fdsurf {
namespace image {

constexpr int kRomNameSize = 16;

// The indices are bytes: the small set has far fewer than 256 items of a
// kind (the emitted initializers would not compile otherwise, as narrowing),
// and the ATmega328P's 32 KB of flash has no byte to spare.

struct RomPatch2 {
  char name[kRomNameSize];
  uint8_t index;
  Status status;
  PreparedPatch<2> prepared;
};
struct RomCurve2 {
  char name[kRomNameSize];
  uint8_t index;
  Status status;
  PreparedCurve<2> prepared;
};
struct RomCurve3 {
  char name[kRomNameSize];
  uint8_t index;
  Status status;
  PreparedCurve<3> prepared;
};
struct RomAdaptive2 {
  char name[kRomNameSize];
  uint8_t index;
  Status status;
  PreparedAdaptiveCurve<2> prepared;
};
struct RomCoefficients2 {
  char name[kRomNameSize];
  uint8_t index;
  PowerCurve1 curve[2];
};

enum class RomKind : uint8_t { kPatch2, kCurve2, kCurve3, kAdaptive2, kCoefficients2 };

/// The small set in the order the host reference prints it.
struct RomItem {
  RomKind kind;
  uint8_t index;  // into the array of that kind
};

extern const RomPatch2 kRomPatch2[] FDSURF_IMAGE_ROM;
extern const RomCurve2 kRomCurve2[] FDSURF_IMAGE_ROM;
extern const RomCurve3 kRomCurve3[] FDSURF_IMAGE_ROM;
extern const RomAdaptive2 kRomAdaptive2[] FDSURF_IMAGE_ROM;
extern const RomCoefficients2 kRomCoefficients2[] FDSURF_IMAGE_ROM;
extern const RomItem kRomOrder[] FDSURF_IMAGE_ROM;
extern const uint16_t kRomOrderCount;

/// The bench tables: curve (normal, wide), 3-D curve, 2-D patch, adaptive curve.
extern const PreparedCurve<2> kRomBenchCurve2[2] FDSURF_IMAGE_ROM;
extern const PreparedCurve<3> kRomBenchCurve3 FDSURF_IMAGE_ROM;
extern const PreparedPatch<2> kRomBenchPatch2 FDSURF_IMAGE_ROM;
extern const PreparedAdaptiveCurve<2> kRomBenchAdaptive2 FDSURF_IMAGE_ROM;

}  // namespace image
}  // namespace fdsurf
