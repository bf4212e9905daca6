// SPDX-License-Identifier: MIT
// The accumulator types of the stepping loop.
//
// Differences are held as integers in units of 2^-F quanta (F chosen by the
// precision planner) in either a native int64_t or in Int128, a portable pair
// of 64-bit limbs. Both only ever add in the hot loop; because the arithmetic
// is exact integer addition, every target produces the same bits.
#pragma once

#include <stdint.h>
#include "fdsurf/config/nodiscard.h"

namespace fdsurf {

/// A 128-bit two's complement integer that supports the few operations the
/// stepping loop needs. Written out rather than relying on __int128, which
/// 32-bit and 8-bit targets lack.
struct Int128 {
  uint64_t lo;
  uint64_t hi;  // Two's complement: the sign is bit 63 of hi.

#if defined(__AVR__)
  // On an 8-bit core avr-gcc makes each 64-bit addition and comparison a
  // libgcc call (about 370 cycles for one 128-bit addition, a sixth of a
  // Mega's cycles on issue 36's job). Here lo then hi are one 16-byte
  // little-endian number, added or subtracted a byte at a time through the
  // carry: the same bits (modulo 2^128), in about 170 cycles. The loop's
  // `dec` and `brne` leave the carry alone.
  Int128& operator+=(const Int128& other) {
    uint8_t* target = reinterpret_cast<uint8_t*>(this);
    const uint8_t* source = reinterpret_cast<const uint8_t*>(&other);
    uint8_t count = 16;
    uint8_t augend;
    uint8_t addend;
    asm volatile(
        "clc\n"
        "1:\n\t"
        "ld %[addend], %a[source]+\n\t"
        "ld %[augend], %a[target]\n\t"
        "adc %[augend], %[addend]\n\t"
        "st %a[target]+, %[augend]\n\t"
        "dec %[count]\n\t"
        "brne 1b"
        : [target] "+e"(target), [source] "+e"(source), [count] "+r"(count), [augend] "=&r"(augend),
          [addend] "=&r"(addend)
        :
        : "memory");
    return *this;
  }

  Int128& operator-=(const Int128& other) {
    uint8_t* target = reinterpret_cast<uint8_t*>(this);
    const uint8_t* source = reinterpret_cast<const uint8_t*>(&other);
    uint8_t count = 16;
    uint8_t minuend;
    uint8_t subtrahend;
    asm volatile(
        "clc\n"
        "1:\n\t"
        "ld %[subtrahend], %a[source]+\n\t"
        "ld %[minuend], %a[target]\n\t"
        "sbc %[minuend], %[subtrahend]\n\t"
        "st %a[target]+, %[minuend]\n\t"
        "dec %[count]\n\t"
        "brne 1b"
        : [target] "+e"(target), [source] "+e"(source), [count] "+r"(count),
          [minuend] "=&r"(minuend), [subtrahend] "=&r"(subtrahend)
        :
        : "memory");
    return *this;
  }
#else
  Int128& operator+=(const Int128& other) {
    const uint64_t lo_sum = lo + other.lo;
    hi += other.hi + (lo_sum < lo ? 1u : 0u);
    lo = lo_sum;
    return *this;
  }

  Int128& operator-=(const Int128& other) {
    const uint64_t lo_difference = lo - other.lo;
    hi -= other.hi + (lo < other.lo ? 1u : 0u);
    lo = lo_difference;
    return *this;
  }
#endif

  Int128 operator-() const {
    Int128 zero{0, 0};
    zero -= *this;
    return zero;
  }

  FDSURF_NODISCARD bool IsNegative() const { return (hi >> 63) != 0; }

  friend Int128 operator+(Int128 a, const Int128& b) { return a += b; }
  friend Int128 operator-(Int128 a, const Int128& b) { return a -= b; }
  friend bool operator==(const Int128& a, const Int128& b) { return a.lo == b.lo && a.hi == b.hi; }
#if defined(__AVR__)
  friend bool operator<=(const Int128& a, const Int128& b) {
    // b − a through the carry (cpc leaves both alone), then the sign of
    // the exact difference (S = N xor V of the top byte): a ≤ b unless
    // b < a. The last byte is compared after the loop, whose `dec` would
    // set S.
    const uint8_t* left = reinterpret_cast<const uint8_t*>(&a);
    const uint8_t* right = reinterpret_cast<const uint8_t*>(&b);
    uint8_t count = 15;
    uint8_t result = 1;
    uint8_t left_byte;
    uint8_t right_byte;
    asm volatile(
        "clc\n"
        "1:\n\t"
        "ld %[left_byte], %a[left]+\n\t"
        "ld %[right_byte], %a[right]+\n\t"
        "cpc %[right_byte], %[left_byte]\n\t"
        "dec %[count]\n\t"
        "brne 1b\n\t"
        "ld %[left_byte], %a[left]\n\t"
        "ld %[right_byte], %a[right]\n\t"
        "cpc %[right_byte], %[left_byte]\n\t"
        "brge 2f\n\t"
        "clr %[result]\n"
        "2:"
        : [left] "+e"(left), [right] "+e"(right), [count] "+r"(count), [result] "+r"(result),
          [left_byte] "=&r"(left_byte), [right_byte] "=&r"(right_byte)
        :
        : "memory");
    return result != 0;
  }
#else
  friend bool operator<=(const Int128& a, const Int128& b) {
    // Flipping the sign bit maps two's complement order onto unsigned order.
    const uint64_t a_hi = a.hi ^ (uint64_t{1} << 63);
    const uint64_t b_hi = b.hi ^ (uint64_t{1} << 63);
    return a_hi < b_hi || (a_hi == b_hi && a.lo <= b.lo);
  }
#endif
};

namespace internal {

/// value · factor modulo 2^128: the exact product whenever it fits, as the
/// sum of a wrapping stepper would be (intermediate sums may wrap).
inline Int128 MultipliedBy(const Int128& value, uint32_t factor) {
  const uint64_t low = (value.lo & 0xFFFFFFFFu) * factor;
  const uint64_t middle = (value.lo >> 32) * factor + (low >> 32);  // < 2^64
  return Int128{(middle << 32) | (low & 0xFFFFFFFFu), value.hi * factor + (middle >> 32)};
}

/// The Int128 of the same value (sign-extended).
inline Int128 Widen(int64_t value) {
  return Int128{static_cast<uint64_t>(value), value < 0 ? ~uint64_t{0} : uint64_t{0}};
}

/// |value| as uint64_t, exact for every value (INT64_MIN included).
inline uint64_t Magnitude(int64_t value) {
  return value < 0 ? 0 - static_cast<uint64_t>(value) : static_cast<uint64_t>(value);
}

/// Two's complement reinterpretation, well defined for every value.
inline int32_t ToInt32(uint32_t bits) {
  return bits <= 0x7FFFFFFFu ? static_cast<int32_t>(bits) : -static_cast<int32_t>(~bits) - 1;
}

/// The shifts and magnitude test of the adaptive stepper, for both
/// accumulators. Shifts go through unsigned arithmetic so that negative values
/// shift the same way on every compiler; 1 <= bits <= 63.
inline int64_t ShiftLeft(int64_t value, int bits) {
  return static_cast<int64_t>(static_cast<uint64_t>(value) << bits);
}
inline int64_t ShiftRightArithmetic(int64_t value, int bits) {
  const uint64_t u = static_cast<uint64_t>(value);
  return static_cast<int64_t>(value < 0 ? ~(~u >> bits) : u >> bits);
}
/// |value| <= limit, for limit >= 0.
inline bool WithinMagnitude(int64_t value, int64_t limit) {
  return value <= limit && value >= -limit;
}

inline Int128 ShiftLeft(const Int128& value, int bits) {
  return Int128{value.lo << bits, (value.hi << bits) | (value.lo >> (64 - bits))};
}
inline Int128 ShiftRightArithmetic(const Int128& value, int bits) {
  const uint64_t sign_fill = value.IsNegative() ? ~uint64_t{0} : 0;
  return Int128{(value.lo >> bits) | (value.hi << (64 - bits)),
                (value.hi >> bits) | (sign_fill << (64 - bits))};
}
inline bool WithinMagnitude(const Int128& value, const Int128& limit) {
  return value <= limit && -limit <= value;
}

}  // namespace internal

#if defined(__AVR__)
/// Out of line on 8-bit cores: there a run-time 64-bit shift is a long libgcc
/// call, so a copy in every stepper costs far more flash than one call costs
/// time.
#define FDSURF_OUT_OF_LINE_ON_AVR __attribute__((noinline))
#else
#define FDSURF_OUT_OF_LINE_ON_AVR
#endif

/// floor(value / 2^frac_bits) as an int32_t: the whole quanta of a position
/// whose rounding half is already added (the adaptive cursor and the per-line
/// stepper keep it there). Requires 1 <= frac_bits <= 63 and a result that
/// fits in int32_t, which the precision planner guarantees.
FDSURF_OUT_OF_LINE_ON_AVR inline int32_t FloorToQuanta(int64_t value, int frac_bits) {
  // Arithmetic shift written with unsigned operations: floor(x / 2^F) of a
  // negative x is ~(~x >> F).
  const uint64_t bits = static_cast<uint64_t>(value);
  const uint64_t shifted = (bits >> 63) != 0 ? ~(~bits >> frac_bits) : bits >> frac_bits;
  return internal::ToInt32(static_cast<uint32_t>(shifted));
}

/// As above for Int128; 1 <= frac_bits <= 126.
inline int32_t FloorToQuanta(const Int128& value, int frac_bits) {
  const bool negative = (value.hi >> 63) != 0;
  uint64_t low_word;  // Bits frac_bits .. frac_bits + 63 of the value.
  if (frac_bits < 64) {
    low_word = (value.lo >> frac_bits) | (value.hi << (64 - frac_bits));
  } else if (frac_bits == 64) {
    low_word = value.hi;
  } else {
    const int shift = frac_bits - 64;
    low_word = negative ? ~(~value.hi >> shift) : value.hi >> shift;
  }
  return internal::ToInt32(static_cast<uint32_t>(low_word));
}

namespace internal {

/// The rounding half 2^(frac_bits-1) in the accumulator's type.
inline void RoundingHalf(int frac_bits, int64_t* half) {
  *half = static_cast<int64_t>(uint64_t{1} << (frac_bits - 1));
}
inline void RoundingHalf(int frac_bits, Int128* half) {
  *half = frac_bits > 64 ? Int128{0, uint64_t{1} << (frac_bits - 65)}
                         : Int128{uint64_t{1} << (frac_bits - 1), 0};
}

}  // namespace internal

/// Rounds value / 2^frac_bits to the nearest integer (halves upward).
/// Requires 1 <= frac_bits <= 62 and a result that fits in int32_t, which the
/// precision planner guarantees.
inline int32_t RoundToQuanta(int64_t value, int frac_bits) {
  int64_t half;
  internal::RoundingHalf(frac_bits, &half);
  // Added as unsigned: the sum is defined on every compiler.
  const uint64_t biased = static_cast<uint64_t>(value) + static_cast<uint64_t>(half);
  return FloorToQuanta(static_cast<int64_t>(biased), frac_bits);
}

/// As above for Int128; 1 <= frac_bits <= 126.
inline int32_t RoundToQuanta(const Int128& value, int frac_bits) {
  Int128 biased;
  internal::RoundingHalf(frac_bits, &biased);
  biased += value;
  return FloorToQuanta(biased, frac_bits);
}

}  // namespace fdsurf
