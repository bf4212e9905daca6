// SPDX-License-Identifier: MIT
// An exact rational reference for tests: integer geometry (in quanta), grid
// parameters s = i/n, t = j/m, evaluated with native __int128 arithmetic and
// the basis matrices typed in again here, so it shares nothing with the
// engine's set-up or the host's double reference.
#pragma once

#include <array>
#include <cstdint>

namespace fdsurf::testing {

__extension__ typedef __int128 I128;

struct TestBasis {
  int denominator;
  int m[4][4];
};

// Indexed like fdsurf::Basis: power, hermite, bezier, bspline, catmull-rom.
inline const TestBasis& TestBasisFor(int basis) {
  static const TestBasis kBases[5] = {
      {1, {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}},
      {1, {{2, -2, 1, 1}, {-3, 3, -2, -1}, {0, 0, 1, 0}, {1, 0, 0, 0}}},
      {1, {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}}},
      {6, {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 0, 3, 0}, {1, 4, 1, 0}}},
      {2, {{-1, 3, -3, 1}, {2, -5, 4, -1}, {-1, 0, 1, 0}, {0, 2, 0, 0}}},
  };
  return kBases[basis];
}

// Blending weights of parameter i/n scaled by d·n³: w[r] = Σ_k i^(3-k)·n^k·(dM)[k][r].
inline std::array<I128, 4> ScaledWeights(const TestBasis& b, std::int64_t i, std::int64_t n) {
  const I128 powers[4] = {I128(i) * i * i, I128(i) * i * n, I128(i) * n * n, I128(n) * n * n};
  std::array<I128, 4> w{};
  for (int r = 0; r < 4; ++r) {
    for (int k = 0; k < 4; ++k) w[r] += powers[k] * b.m[k][r];
  }
  return w;
}

/// x(i/n, j/m) = numerator / denominator exactly, for integer geometry g.
struct Rational {
  I128 numerator;
  I128 denominator;
};

inline Rational ExactPatchPoint(int basis, const std::int64_t (&g)[4][4], std::int64_t i,
                                std::int64_t n, std::int64_t j, std::int64_t m) {
  const TestBasis& b = TestBasisFor(basis);
  const auto ws = ScaledWeights(b, i, n);
  const auto wt = ScaledWeights(b, j, m);
  I128 sum = 0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) sum += ws[r] * g[r][c] * wt[c];
  }
  const I128 den = I128(b.denominator) * b.denominator * n * n * n * m * m * m;
  return {sum, den};
}

inline Rational ExactCurvePoint(int basis, const std::int64_t (&g)[4], std::int64_t i,
                                std::int64_t n) {
  const TestBasis& b = TestBasisFor(basis);
  const auto w = ScaledWeights(b, i, n);
  I128 sum = 0;
  for (int r = 0; r < 4; ++r) sum += w[r] * g[r];
  return {sum, I128(b.denominator) * n * n * n};
}

/// |k − x| ≤ 0.51, decided exactly.
inline bool WithinBound(std::int64_t k, const Rational& x) {
  I128 diff = I128(k) * x.denominator - x.numerator;
  if (diff < 0) diff = -diff;
  return diff * 100 <= x.denominator * 51;
}

/// k is the nearest integer to x (halves rounded up), decided exactly.
inline bool IsRoundedValue(std::int64_t k, const Rational& x) {
  // k − 1/2 ≤ x < k + 1/2  ⇔  (2k − 1)·den ≤ 2·num < (2k + 1)·den.
  const I128 twice = 2 * x.numerator;
  return (2 * I128(k) - 1) * x.denominator <= twice && twice < (2 * I128(k) + 1) * x.denominator;
}

inline double ToDouble(const Rational& x) {
  return static_cast<double>(x.numerator) / static_cast<double>(x.denominator);
}

}  // namespace fdsurf::testing
