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

  constexpr WideInt() : limb_{} {}

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

  bool IsNegative() const { return (limb_[kLimbs - 1] >> 31) != 0; }

  bool IsZero() const {
    for (int i = 0; i < kLimbs; ++i) {
      if (limb_[i] != 0) return false;
    }
    return true;
  }

  uint32_t limb(int i) const { return limb_[i]; }

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
        const uint64_t t = static_cast<uint64_t>(x.limb_[i]) * y.limb_[j] +
                           product.limb_[i + j] + carry;
        product.limb_[i + j] = static_cast<uint32_t>(t);
        carry = t >> 32;
      }
    }
    return negative ? -product : product;
  }

  WideInt Abs() const { return IsNegative() ? -*this : *this; }

  /// Logical shift left by 0 <= bits < kBits.
  WideInt ShiftedLeft(int bits) const {
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
  int MagnitudeBits() const {
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

  /// Divides a non-negative value by 1 <= divisor <= 65536 in place, rounding
  /// towards zero, and returns the remainder. Works in 16-bit halves so that
  /// only a 32-bit by 32-bit division is needed on every target.
  uint32_t DivideInPlace(uint32_t divisor) {
    uint32_t remainder = 0;
    for (int i = kLimbs - 1; i >= 0; --i) {
      const uint32_t high = (remainder << 16) | (limb_[i] >> 16);
      const uint32_t q_high = high / divisor;
      remainder = high % divisor;
      const uint32_t low = (remainder << 16) | (limb_[i] & 0xFFFFu);
      const uint32_t q_low = low / divisor;
      remainder = low % divisor;
      limb_[i] = (q_high << 16) | q_low;
    }
    return remainder;
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
  uint32_t limb_[kLimbs];
};

}  // namespace internal
}  // namespace fdsurf
