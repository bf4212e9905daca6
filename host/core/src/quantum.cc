// SPDX-License-Identifier: MIT
#include "fdsurf/host/quantum.h"

#include <cmath>
#include <cstdlib>

#include "fdsurf/host/errors.h"

namespace fdsurf::host {

Quantum Quantum::Parse(const std::string& text, const std::string& what) {
  const auto fail = [&](const std::string& why) -> InputError {
    return InputError(what + ": '" + text + "' " + why);
  };
  std::int64_t mantissa = 0;
  int decimals = 0;
  int digits = 0;
  bool seen_point = false;
  bool seen_digit = false;
  for (char ch : text) {
    if (ch == '.') {
      if (seen_point) throw fail("is not a decimal number");
      seen_point = true;
      continue;
    }
    if (ch < '0' || ch > '9') throw fail("is not a positive decimal number (like 0.001)");
    seen_digit = true;
    if (seen_point) ++decimals;
    if (mantissa == 0 && ch == '0') continue;  // leading zeros are not significant
    mantissa = mantissa * 10 + (ch - '0');
    if (++digits > 9) throw fail("has more than 9 significant digits");
  }
  if (!seen_digit) throw fail("is not a decimal number");
  if (decimals > 9) throw fail("has more than 9 decimals");
  if (mantissa == 0) throw fail("must be greater than zero");
  // Normalise 0.0010 to mantissa 1, 3 decimals.
  while (decimals > 0 && mantissa % 10 == 0) {
    mantissa /= 10;
    --decimals;
  }
  Quantum q;
  q.mantissa_ = mantissa;
  q.decimals_ = decimals;
  return q;
}

double Quantum::value() const { return static_cast<double>(mantissa_) / std::pow(10.0, decimals_); }

double Quantum::ToQuanta(double value) const {
  // 10^decimals (≤ 10^9) and the mantissa (< 10^9) are exact in a double.
  return value * std::pow(10.0, decimals_) / static_cast<double>(mantissa_);
}

std::string Quantum::Format(std::int64_t k) const {
  const bool negative = k < 0;
  // |k| < 2^31 and mantissa < 10^9: the product fits in 61 bits.
  const std::uint64_t magnitude =
      static_cast<std::uint64_t>(negative ? -k : k) * static_cast<std::uint64_t>(mantissa_);
  std::string digits = std::to_string(magnitude);
  if (decimals_ > 0) {
    if (static_cast<int>(digits.size()) <= decimals_) {
      digits.insert(0, static_cast<std::size_t>(decimals_ + 1 - digits.size()), '0');
    }
    digits.insert(digits.size() - static_cast<std::size_t>(decimals_), 1, '.');
  }
  return (negative && magnitude != 0 ? "-" : "") + digits;
}

std::optional<GeometryFixed> ToGeometry(double value, const Quantum& quantum) {
  const double q = quantum.ToQuanta(value);
  // Checked in double first: a cast of a value beyond int64 is undefined.
  if (!std::isfinite(q) || !(std::fabs(q) < std::ldexp(1.0, 31))) return std::nullopt;
  const auto raw = static_cast<std::int64_t>(std::nearbyint(std::ldexp(q, kGeometryFracBits)));
  if (!GeometryInRange(raw)) return std::nullopt;  // the range the engine itself checks
  return GeometryFixed::FromRaw(raw);
}

}  // namespace fdsurf::host
