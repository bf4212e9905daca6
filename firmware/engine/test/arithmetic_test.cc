// SPDX-License-Identifier: MIT
// The core's integer types against the compiler's native __int128.
#include <gtest/gtest.h>

#include <random>

#include "fdsurf/int128.h"
#include "fdsurf/internal/wide_int.h"

namespace fdsurf {
namespace {

__extension__ typedef __int128 I128;
__extension__ typedef unsigned __int128 U128;
using Wide = internal::WideInt<8>;

I128 ToNative(const Int128& v) { return static_cast<I128>((static_cast<U128>(v.hi) << 64) | v.lo); }
Int128 FromNative(I128 v) {
  const auto u = static_cast<U128>(v);
  return Int128{static_cast<std::uint64_t>(u), static_cast<std::uint64_t>(u >> 64)};
}
// The low 128 bits of a WideInt.
I128 Low128(const Wide& w) {
  U128 u = 0;
  for (int i = 3; i >= 0; --i) u = (u << 32) | w.limb(i);
  return static_cast<I128>(u);
}

I128 RandomI128(std::mt19937_64& rng, int bits) {
  const U128 u = (static_cast<U128>(rng()) << 64) | rng();
  I128 v = static_cast<I128>(u >> (128 - bits));
  return (rng() & 1) != 0 ? -v : v;
}

// floor(v / 2^f + 1/2) computed natively.
I128 RoundNative(I128 v, int f) {
  const I128 biased = v + (static_cast<I128>(1) << (f - 1));
  return biased >> f;  // arithmetic on GCC: floor
}

TEST(Int128, AdditionMatchesNative) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 100000; ++trial) {
    const I128 a = RandomI128(rng, 1 + static_cast<int>(rng() % 126));
    const I128 b = RandomI128(rng, 1 + static_cast<int>(rng() % 126));
    Int128 x = FromNative(a);
    x += FromNative(b);
    ASSERT_EQ(ToNative(x), a + b);
  }
}

TEST(Int128, RoundToQuantaMatchesNativeForEveryShift) {
  std::mt19937_64 rng(2);
  for (int f = 1; f <= 126; ++f) {
    for (int trial = 0; trial < 2000; ++trial) {
      // Values whose rounded result fits in int32.
      const int bits = std::min(126, f + 30);
      const I128 v = RandomI128(rng, 1 + static_cast<int>(rng() % bits));
      const I128 expected = RoundNative(v, f);
      ASSERT_EQ(RoundToQuanta(FromNative(v), f), static_cast<std::int32_t>(expected)) << "f=" << f;
      if (f <= 62 && v > INT64_MIN / 2 && v < INT64_MAX / 2) {
        ASSERT_EQ(RoundToQuanta(static_cast<std::int64_t>(v), f),
                  static_cast<std::int32_t>(expected));
      }
    }
  }
}

TEST(Int128, RoundsHalvesUpAndNegativesTowardsMinusInfinity) {
  EXPECT_EQ(RoundToQuanta(std::int64_t{3} << 9, 10), 2);      // 1.5 → 2
  EXPECT_EQ(RoundToQuanta(-(std::int64_t{3} << 9), 10), -1);  // -1.5 → -1
  EXPECT_EQ(RoundToQuanta(-(std::int64_t{5} << 8), 10), -1);  // -1.25 → -1
  EXPECT_EQ(RoundToQuanta(-(std::int64_t{7} << 8), 10), -2);  // -1.75 → -2
  EXPECT_EQ(RoundToQuanta(Int128{0, 3}, 65), 2);              // 1.5 → 2
}

TEST(WideInt, ArithmeticMatchesNative) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 20000; ++trial) {
    const I128 a = RandomI128(rng, 1 + static_cast<int>(rng() % 62));
    const I128 b = RandomI128(rng, 1 + static_cast<int>(rng() % 62));
    const Wide wa = Wide::FromInt64(static_cast<std::int64_t>(a));
    const Wide wb = Wide::FromInt64(static_cast<std::int64_t>(b));
    ASSERT_EQ(Low128(wa + wb), a + b);
    ASSERT_EQ(Low128(wa - wb), a - b);
    ASSERT_EQ(Low128(wa * wb), a * b);
    ASSERT_EQ(Low128(-wa), -a);
    ASSERT_EQ(wa < wb, a < b);
    ASSERT_EQ(wa == wb, a == b);
    ASSERT_EQ((wa * wb).IsNegative(), a * b < 0);
    const int shift = static_cast<int>(rng() % 60);
    ASSERT_EQ(Low128(wa.ShiftedLeft(shift)), a * (static_cast<I128>(1) << shift));
    const I128 magnitude = a < 0 ? -a : a;
    int bits = 0;
    while ((magnitude >> bits) != 0) ++bits;
    ASSERT_EQ(wa.MagnitudeBits(), bits);
  }
}

TEST(WideInt, DivideInPlaceMatchesNative) {
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 20000; ++trial) {
    const I128 a = RandomI128(rng, 1 + static_cast<int>(rng() % 126));
    const U128 u = static_cast<U128>(a < 0 ? -a : a);
    const std::uint32_t divisor =
        1 + static_cast<std::uint32_t>(rng() % ((trial % 2 == 0) ? 65536 : 0xFFFFFFFFu));
    Wide w = Wide::FromInt64(0);
    for (int shift = 96; shift >= 0; shift -= 32) {
      w = w.ShiftedLeft(32) + Wide::FromUint64(static_cast<std::uint32_t>(u >> shift));
    }
    const std::uint32_t remainder = w.DivideInPlace(divisor);
    ASSERT_EQ(static_cast<U128>(Low128(w)), u / divisor);
    ASSERT_EQ(remainder, static_cast<std::uint32_t>(u % divisor));
  }
}

TEST(WideInt, ShiftRightAndMulInt64MatchNative) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20000; ++trial) {
    const I128 a = RandomI128(rng, 1 + static_cast<int>(rng() % 62));
    const std::int64_t b = static_cast<std::int64_t>(rng()) >> (rng() % 63);
    const Wide wa = Wide::FromInt64(static_cast<std::int64_t>(a));
    ASSERT_EQ(Low128(wa.MulInt64(b)), a * b);
    if (a >= 0) {
      const int bits = 1 + static_cast<int>(rng() % 31);
      Wide shifted = wa;
      const std::uint32_t removed = shifted.ShiftRightInPlace(bits);
      ASSERT_EQ(Low128(shifted), a >> bits);
      ASSERT_EQ(removed, static_cast<std::uint32_t>(a & ((I128{1} << bits) - 1)));
    }
  }
}

TEST(WideInt, HoldsProductsBeyond128Bits) {
  // (2^100 + 1)·(2^100 − 1) = 2^200 − 1.
  const Wide a = Wide::PowerOfTwo(100) + Wide::FromInt64(1);
  const Wide b = Wide::PowerOfTwo(100) - Wide::FromInt64(1);
  EXPECT_EQ(a * b, Wide::PowerOfTwo(200) - Wide::FromInt64(1));
  EXPECT_EQ((a * b).MagnitudeBits(), 200);
  EXPECT_EQ((-(a * b)).MagnitudeBits(), 200);
}

}  // namespace
}  // namespace fdsurf
