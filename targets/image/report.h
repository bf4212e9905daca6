// SPDX-License-Identifier: MIT
// Text output and checksums of the test image. Everything the image prints is
// a function of the engine's integer results, so the host reference and every
// target must print the same bytes.
#pragma once

#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"
#include "port.h"

#ifndef FDSURF_IMAGE_ACC64_ONLY
#define FDSURF_IMAGE_ACC64_ONLY 0
#endif

namespace fdsurf {
namespace image {

/// Whether the image steps 128-bit tables. The ATmega328P image does not:
/// its host-prepared tables all fit 64-bit accumulators (as
/// PrepareOptions::max_acc_bits = 64 would ensure on a device), and the
/// 128-bit steppers would not fit its flash beside them.
constexpr bool kImageWideAccumulators = FDSURF_IMAGE_ACC64_ONLY == 0;

/// Prints a FDSURF_TEXT string (in flash on AVR).
void PutString(const char* text);
void PutDecimal(int32_t value);
void PutUnsigned(uint32_t value);
void PutHex(uint32_t value);

/// The 16-entry table of a nibble-wise CRC-32: 64 bytes, and a quarter of
/// the bitwise loop's work on an 8-bit core.
extern const uint32_t kCrcNibbleTable[16];

/// CRC-32 (IEEE 802.3, reflected) over the little-endian bytes of every
/// coordinate of every point, plus the point count and the first and last
/// point as a readable sample.
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
    PutString(FDSURF_TEXT(" points "));
    PutUnsigned(count_);
    PutString(FDSURF_TEXT(" crc "));
    PutHex(~crc_);
    PutString(FDSURF_TEXT(" first"));
    for (int c = 0; c < kDims; ++c) {
      PutString(FDSURF_TEXT(" "));
      PutDecimal(count_ != 0 ? first_[c] : 0);
    }
    PutString(FDSURF_TEXT(" last"));
    for (int c = 0; c < kDims; ++c) {
      PutString(FDSURF_TEXT(" "));
      PutDecimal(count_ != 0 ? last_[c] : 0);
    }
  }

 private:
  void AddByte(uint8_t byte) {
    crc_ ^= byte;
    crc_ = (crc_ >> 4) ^ kCrcNibbleTable[crc_ & 0xFu];
    crc_ = (crc_ >> 4) ^ kCrcNibbleTable[crc_ & 0xFu];
  }

  uint32_t crc_ = 0xFFFFFFFFu;
  uint32_t count_ = 0;
  int32_t first_[kDims] = {};
  int32_t last_[kDims] = {};
};

/// Steps an adaptive curve with the accumulator its format names and returns
/// the number of points; with digests, digests the points and their
/// parameter positions. Shared by the report and the bench (which passes
/// nullptr), so that small flash holds one copy of the adaptive stepper.
template <int kDims>
uint32_t StepAdaptive(const PreparedAdaptiveCurve<kDims>& curve, PointDigest<kDims>* points,
                      PointDigest<1>* positions);

/// Names passed to the Reporter are FDSURF_TEXT strings too.
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
