// SPDX-License-Identifier: MIT
// Fixed-point numbers with the format in the type.
//
// A Fixed<Rep, kFracBits> holds value * 2^kFracBits in a signed integer Rep.
// The engine's numbers are all integers scaled by a power of two; naming the
// format in the type keeps the scale visible where values cross an interface
// (geometry in; positions out are plain whole quanta, see the end of this
// file). Conversions are explicit: Raw() and FromRaw() are the only ways in
// and out, so no value is silently rescaled.
#pragma once

#include <stdint.h>
#include "fdsurf/config/nodiscard.h"

namespace fdsurf {

template <typename Rep>
struct FixedRepTraits;
template <>
struct FixedRepTraits<int16_t> {
  static constexpr int kBits = 16;
};
template <>
struct FixedRepTraits<int32_t> {
  static constexpr int kBits = 32;
};
template <>
struct FixedRepTraits<int64_t> {
  static constexpr int kBits = 64;
};

template <typename Rep, int kFracBits>
class Fixed {
 public:
  static constexpr int kTotalBits = FixedRepTraits<Rep>::kBits;
  static constexpr int kFractionalBits = kFracBits;
  /// Bits left of the binary point, not counting the sign bit.
  static constexpr int kIntegerBits = kTotalBits - 1 - kFracBits;
  static_assert(kFracBits >= 0 && kFracBits < kTotalBits,
                "the fractional bits must fit in the representation");

  constexpr Fixed() : raw_(0) {}
  static constexpr Fixed FromRaw(Rep raw) { return Fixed(raw); }
  FDSURF_NODISCARD constexpr Rep Raw() const { return raw_; }

 private:
  constexpr explicit Fixed(Rep raw) : raw_(raw) {}
  Rep raw_;
};

/// Guard bits below the output quantum in geometry values (control points,
/// tangents, power coefficients). Converting a real coordinate to this format
/// errs by at most 2^-17 quanta; docs/precision.md carries that through.
constexpr int kGeometryFracBits = 16;

/// Geometry in quanta: Q47.16. |value| must stay below 2^31 quanta
/// (kGeometryLimitRaw) so that the set-up arithmetic cannot overflow.
using GeometryFixed = Fixed<int64_t, kGeometryFracBits>;
constexpr int64_t kGeometryLimitRaw = int64_t{1} << (31 + kGeometryFracBits);

/// The one range check of geometry: |raw| < kGeometryLimitRaw (2^31 quanta).
/// The decoder refuses a value outside it (kBadField) and the set-up
/// (PreparePatch, CurvePowerCoefficients, IsolineWalker, and
/// PrepareAdaptiveCurve for power coefficients in the same Q47.16) with
/// kGeometryOutOfRange, so every side applies the same bound.
constexpr bool GeometryInRange(int64_t raw) {
  return raw > -kGeometryLimitRaw && raw < kGeometryLimitRaw;
}
constexpr bool GeometryInRange(GeometryFixed value) { return GeometryInRange(value.Raw()); }

static_assert(GeometryInRange(kGeometryLimitRaw - 1) && GeometryInRange(-(kGeometryLimitRaw - 1)),
              "the largest magnitude inside the range");
static_assert(!GeometryInRange(kGeometryLimitRaw) && !GeometryInRange(-kGeometryLimitRaw),
              "2^31 quanta is outside");

// Output positions are whole quanta (Q31.0) as plain int32_t: the steppers
// hand each point to the caller as `const int32_t (&)[kDims]`, and the motion
// loop, the protocol and the host all take those arrays as they are. A
// Fixed<int32_t, 0> wrapper for them (once declared here as `Quanta`) was
// never used by any interface, so it was removed rather than threaded through
// every stepper API for no change in meaning.

static_assert(GeometryFixed::kIntegerBits == 47, "Q47.16");

}  // namespace fdsurf
