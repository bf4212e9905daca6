// SPDX-License-Identifier: MIT
// The fixed input set of the test image: Newell's teapot compiled in, and a
// written-out xorshift generator for random geometry, so that every target
// and the host reference see exactly the same numbers.
#pragma once

#include <stdint.h>

#include "port.h"

namespace fdsurf {
namespace image {

constexpr int kTeapotPatches = 32;

/// GeometryFixed raw values (Q = 0.001, 16 fractional bits) of the teapot's
/// control points: kTeapot[patch][coordinate][4 * row + column]. Generated
/// by targets/tools/gen_teapot.py; in flash on AVR (read with TeapotRaw).
extern const int32_t kTeapot[kTeapotPatches][3][16] FDSURF_IMAGE_ROM;

inline int64_t TeapotRaw(int patch, int coordinate, int index) {
  int32_t value;
  PortReadRom(&value, &kTeapot[patch][coordinate][index], sizeof value);
  return value;
}

/// Marsaglia's xorshift32 (shifts 13, 17, 5), never seeded with 0.
class Xorshift32 {
 public:
  explicit Xorshift32(uint32_t seed) : state_(seed) {}
  uint32_t Next() {
    state_ ^= state_ << 13;
    state_ ^= state_ >> 17;
    state_ ^= state_ << 5;
    return state_;
  }
  /// A raw GeometryFixed value uniform in (-2^bits, 2^bits) quanta units of
  /// 2^-16, i.e. |value| < 2^(bits - 16) quanta; 1 <= bits <= 62.
  int64_t Raw(int bits) {
    const uint64_t word = (static_cast<uint64_t>(Next()) << 32) | Next();
    const uint64_t magnitude = word >> (64 - bits);
    return (Next() & 1u) != 0 ? -static_cast<int64_t>(magnitude) : static_cast<int64_t>(magnitude);
  }

 private:
  uint32_t state_;
};

}  // namespace image
}  // namespace fdsurf
