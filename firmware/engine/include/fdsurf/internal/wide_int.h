// SPDX-License-Identifier: MIT
// Fixed-width signed integers for the one-time set-up arithmetic.
//
// Forming the difference matrix exactly needs products of about 180 bits
// (see docs/precision.md, "Set-up arithmetic"). WideInt holds a two's
// complement integer in 32-bit limbs, so the same code gives the same bits on
// an 8-bit AVR, a Cortex-M0 and an x86-64 host. It is used only at set-up,
// never in the stepping loop.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/int128.h"

namespace fdsurf {
namespace internal {

/// A signed integer of 32 * kLimbs bits, least significant limb first.
/// Arithmetic wraps like unsigned integers; callers prove their operands are
/// small enough (the set-up code checks bit lengths before it multiplies).
template <int kLimbs>
class WideInt {
 public:
  static_assert(kLimbs >= 2, "WideInt needs at least 64 bits");
  static constexpr int kBits = 32 * kLimbs;

  constexpr WideInt() = default;

  static WideInt FromInt64(int64_t value) {
    WideInt w;
    const uint64_t bits = static_cast<uint64_t>(value);
    w.limb_[0] = static_cast<uint32_t>(bits);
    w.limb_[1] = static_cast<uint32_t>(bits >> 32);
    const uint32_t fill = value < 0 ? 0xFFFFFFFFu : 0u;
    for (int i = 2; i < kLimbs; ++i) w.limb_[i] = fill;
    return w;
  }

  static WideInt FromUint64(uint64_t value) {
    WideInt w;
    w.limb_[0] = static_cast<uint32_t>(value);
    w.limb_[1] = static_cast<uint32_t>(value >> 32);
    return w;
  }

  /// 2^bits; bits must be below kBits - 1.
  static WideInt PowerOfTwo(int bits) {
    WideInt w;
    w.limb_[bits / 32] = uint32_t{1} << (bits % 32);
    return w;
  }

  FDSURF_NODISCARD bool IsNegative() const { return (limb_[kLimbs - 1] >> 31) != 0; }

  FDSURF_NODISCARD bool IsZero() const {
    for (int i = 0; i < kLimbs; ++i) {
      if (limb_[i] != 0) return false;
    }
    return true;
  }

  FDSURF_NODISCARD uint32_t limb(int i) const { return limb_[i]; }

  WideInt& operator+=(const WideInt& other) {
    uint32_t carry = 0;
    for (int i = 0; i < kLimbs; ++i) {
      const uint64_t sum = static_cast<uint64_t>(limb_[i]) + other.limb_[i] + carry;
      limb_[i] = static_cast<uint32_t>(sum);
      carry = static_cast<uint32_t>(sum >> 32);
    }
    return *this;
  }

  WideInt& operator-=(const WideInt& other) { return *this += -other; }

  WideInt operator-() const {
    WideInt result;
    uint32_t carry = 1;
    for (int i = 0; i < kLimbs; ++i) {
      const uint64_t sum = static_cast<uint64_t>(~limb_[i]) + carry;
      result.limb_[i] = static_cast<uint32_t>(sum);
      carry = static_cast<uint32_t>(sum >> 32);
    }
    return result;
  }

  friend WideInt operator+(WideInt a, const WideInt& b) { return a += b; }
  friend WideInt operator-(WideInt a, const WideInt& b) { return a -= b; }

  /// Truncating product (the low kBits bits of a * b).
  friend WideInt operator*(const WideInt& a, const WideInt& b) {
    const bool negative = a.IsNegative() != b.IsNegative();
    const WideInt x = a.Abs();
    const WideInt y = b.Abs();
    WideInt product;
    for (int i = 0; i < kLimbs; ++i) {
      uint64_t carry = 0;
      for (int j = 0; i + j < kLimbs; ++j) {
        const uint64_t t =
            static_cast<uint64_t>(x.limb_[i]) * y.limb_[j] + product.limb_[i + j] + carry;
        product.limb_[i + j] = static_cast<uint32_t>(t);
        carry = t >> 32;
      }
    }
    return negative ? -product : product;
  }

  FDSURF_NODISCARD WideInt Abs() const { return IsNegative() ? -*this : *this; }

  /// Logical shift left by 0 <= bits < kBits.
  FDSURF_NODISCARD WideInt ShiftedLeft(int bits) const {
    WideInt result;
    const int whole = bits / 32;
    const int part = bits % 32;
    for (int i = kLimbs - 1; i >= whole; --i) {
      uint32_t v = limb_[i - whole] << part;
      if (part != 0 && i - whole - 1 >= 0) v |= limb_[i - whole - 1] >> (32 - part);
      result.limb_[i] = v;
    }
    return result;
  }

  /// Number of significant bits of the magnitude (0 for zero).
  FDSURF_NODISCARD int MagnitudeBits() const {
    const WideInt m = Abs();
    for (int i = kLimbs - 1; i >= 0; --i) {
      if (m.limb_[i] != 0) {
        int bits = 32;
        while ((m.limb_[i] >> (bits - 1)) == 0) --bits;
        return 32 * i + bits;
      }
    }
    return 0;
  }

  /// The product with a 64-bit integer: cheaper than a full WideInt product,
  /// and what most of the set-up's matrix products need. Truncating.
  FDSURF_NODISCARD WideInt MulInt64(int64_t factor) const {
    // In two's complement the low kBits of x·y are those of x·(y mod 2^64),
    // less x·2^64 when y is negative.
    const uint64_t y = static_cast<uint64_t>(factor);
    const uint32_t y_limb[2] = {static_cast<uint32_t>(y), static_cast<uint32_t>(y >> 32)};
    WideInt product;
    for (int j = 0; j < 2; ++j) {
      if (y_limb[j] == 0) continue;
      uint64_t carry = 0;
      for (int i = 0; i + j < kLimbs; ++i) {
        const uint64_t t =
            static_cast<uint64_t>(limb_[i]) * y_limb[j] + product.limb_[i + j] + carry;
        product.limb_[i + j] = static_cast<uint32_t>(t);
        carry = t >> 32;
      }
    }
    if (factor < 0) product -= ShiftedLeft(64);
    return product;
  }

  /// The same value in another width (sign-extended or truncated).
  template <int kOtherLimbs>
  FDSURF_NODISCARD WideInt<kOtherLimbs> Resized() const {
    WideInt<kOtherLimbs> result;
    const uint32_t fill = IsNegative() ? 0xFFFFFFFFu : 0u;
    for (int i = 0; i < kOtherLimbs; ++i) result.set_limb(i, i < kLimbs ? limb_[i] : fill);
    return result;
  }

  void set_limb(int i, uint32_t value) { limb_[i] = value; }

  /// Divides a non-negative value by 2^bits (1 <= bits <= 31) in place,
  /// rounding towards zero, and returns the remainder (the bits shifted out).
  uint32_t ShiftRightInPlace(int bits) {
    const uint32_t remainder = limb_[0] & ((uint32_t{1} << bits) - 1);
    for (int i = 0; i < kLimbs - 1; ++i) {
      limb_[i] = (limb_[i] >> bits) | (limb_[i + 1] << (32 - bits));
    }
    limb_[kLimbs - 1] >>= bits;
    return remainder;
  }

  /// Divides a non-negative value by a divisor >= 1 in place, rounding
  /// towards zero, and returns the remainder. Set-up only: on targets without
  /// a hardware divide this calls the compiler's 64-bit division routine.
  uint32_t DivideInPlace(uint32_t divisor) {
    uint64_t remainder = 0;
    for (int i = kLimbs - 1; i >= 0; --i) {
      if (remainder == 0 && limb_[i] < divisor) {
        // Leading limbs below the divisor give a zero quotient limb; most of
        // the set-up's numbers leave the top limbs empty.
        remainder = limb_[i];
        limb_[i] = 0;
        continue;
      }
      const uint64_t current = (remainder << 32) | limb_[i];
      limb_[i] = static_cast<uint32_t>(current / divisor);
      remainder = current % divisor;
    }
    return static_cast<uint32_t>(remainder);
  }

  friend bool operator==(const WideInt& a, const WideInt& b) {
    for (int i = 0; i < kLimbs; ++i) {
      if (a.limb_[i] != b.limb_[i]) return false;
    }
    return true;
  }
  friend bool operator!=(const WideInt& a, const WideInt& b) { return !(a == b); }

  friend bool operator<(const WideInt& a, const WideInt& b) {
    const bool a_neg = a.IsNegative();
    if (a_neg != b.IsNegative()) return a_neg;
    for (int i = kLimbs - 1; i >= 0; --i) {
      if (a.limb_[i] != b.limb_[i]) return a.limb_[i] < b.limb_[i];
    }
    return false;
  }

 private:
  uint32_t limb_[kLimbs] = {};
};

/// The low 128 bits of a WideInt (the caller has proven the value fits).
template <int kLimbs>
Int128 ToInt128(const WideInt<kLimbs>& w) {
  static_assert(kLimbs >= 4, "at least 128 bits");
  Int128 v;
  v.lo = static_cast<uint64_t>(w.limb(0)) | (static_cast<uint64_t>(w.limb(1)) << 32);
  v.hi = static_cast<uint64_t>(w.limb(2)) | (static_cast<uint64_t>(w.limb(3)) << 32);
  return v;
}

/// An Int128 as a 4-limb WideInt.
inline WideInt<4> FromInt128(const Int128& v) {
  WideInt<4> w;
  w.set_limb(0, static_cast<uint32_t>(v.lo));
  w.set_limb(1, static_cast<uint32_t>(v.lo >> 32));
  w.set_limb(2, static_cast<uint32_t>(v.hi));
  w.set_limb(3, static_cast<uint32_t>(v.hi >> 32));
  return w;
}

}  // namespace internal
}  // namespace fdsurf
