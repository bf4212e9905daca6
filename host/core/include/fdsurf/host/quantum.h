// SPDX-License-Identifier: MIT
// The output quantum Q: a positive decimal, kept exact so positions can be
// printed as their exact decimal value k·Q.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/fixed.h"

namespace fdsurf::host {

class Quantum {
 public:
  /// Parses "0.001", "0.025", "1", "2.5". At most 9 significant digits and 9
  /// decimals; throws InputError naming `what` otherwise.
  static Quantum Parse(const std::string& text, const std::string& what = "quantum");

  /// Q = mantissa · 10^-decimals.
  FDSURF_NODISCARD std::int64_t mantissa() const { return mantissa_; }
  FDSURF_NODISCARD int decimals() const { return decimals_; }
  FDSURF_NODISCARD double value() const;

  /// value / Q as a double, with about 2^-52 relative error (one rounding
  /// for the product, one for the quotient).
  FDSURF_NODISCARD double ToQuanta(double value) const;

  /// The exact decimal text of k·Q ("-1.400" for k = -1400, Q = 0.001).
  FDSURF_NODISCARD std::string Format(std::int64_t k) const;

 private:
  std::int64_t mantissa_ = 1;
  int decimals_ = 3;
};

/// `value` (in the units Q is given in) as the engine's geometry: value / Q
/// rounded to the nearest 2^-16 quantum. The one conversion from doubles to
/// fixed-point geometry on the host; nullopt when `value` is not finite or
/// lies outside the engine's range (GeometryFixed, |value / Q| < 2^31
/// quanta), so that the caller can name the value in its error.
std::optional<GeometryFixed> ToGeometry(double value, const Quantum& quantum);

}  // namespace fdsurf::host
