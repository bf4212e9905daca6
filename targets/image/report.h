// Text output and checksums of the test image. Everything the image prints is
// a function of the engine's integer results, so the host reference and every
// target must print the same bytes.
#pragma once

#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"
#include "port.h"

namespace fdsurf {
namespace image {

void PutString(const char* text);
void PutDecimal(int32_t value);
void PutUnsigned(uint32_t value);
void PutHex(uint32_t value);

/// CRC-32 (IEEE 802.3, reflected, bitwise: no table to spend flash on) over
/// the little-endian bytes of every coordinate of every point, plus the point
/// count and the first and last point as a readable sample.
template <int kDims>
class PointDigest {
 public:
  void Add(const int32_t (&point)[kDims]) {
    for (int c = 0; c < kDims; ++c) {
      const uint32_t bits = static_cast<uint32_t>(point[c]);
      for (int byte = 0; byte < 4; ++byte) AddByte(static_cast<uint8_t>(bits >> (8 * byte)));
      if (count_ == 0) first_[c] = point[c];
      last_[c] = point[c];
    }
    ++count_;
  }

  /// " points N crc X first x y [z] last x y [z]"
  void Put() const {
    PutString(" points ");
    PutUnsigned(count_);
    PutString(" crc ");
    PutHex(~crc_);
    PutString(" first");
    for (int c = 0; c < kDims; ++c) {
      PutString(" ");
      PutDecimal(count_ != 0 ? first_[c] : 0);
    }
    PutString(" last");
    for (int c = 0; c < kDims; ++c) {
      PutString(" ");
      PutDecimal(count_ != 0 ? last_[c] : 0);
    }
  }

 private:
  void AddByte(uint8_t byte) {
    crc_ ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc_ = (crc_ >> 1) ^ (0xEDB88320u & (0u - (crc_ & 1u)));
  }

  uint32_t crc_ = 0xFFFFFFFFu;
  uint32_t count_ = 0;
  int32_t first_[kDims] = {};
  int32_t last_[kDims] = {};
};

/// Prints one line per prepared item: its name, the status of its set-up, the
/// planner's format, and the digest of every point the stepper emits.
class Reporter {
 public:
  /// Items with small = false are left out when small_only is set: the
  /// ATmega328P image steps only the small set (targets/README.md).
  bool small_only = false;

  template <int kDims>
  void Patch(bool small, const char* name, uint16_t index, Status status,
             const PreparedPatch<kDims>& patch);
  template <int kDims>
  void Curve(bool small, const char* name, uint16_t index, Status status,
             const PreparedCurve<kDims>& curve);
  template <int kDims>
  void Adaptive(bool small, const char* name, uint16_t index, Status status,
                const PreparedAdaptiveCurve<kDims>& curve);
  /// The digest of an isoline's power coefficients (IsolineWalker).
  template <int kDims>
  void Coefficients(bool small, const char* name, uint16_t index,
                    const PowerCurve1 (&curve)[kDims]);
};

/// "<kind> <name>-<index> <status>" and, when set up, " acc W frac F".
void PutItemHead(const char* kind, const char* name, uint16_t index, Status status,
                 const DiffFormat& format);

}  // namespace image
}  // namespace fdsurf
