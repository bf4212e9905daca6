// SPDX-License-Identifier: MIT
// Adaptive forward differencing and the isoline walker against exact and
// independent references: every point is the exactly rounded value of the
// prepared curve, every chord is within the tolerance of the original curve
// (measured densely in long double), step-exact paths move at most one
// quantum per axis, and the walker's line coefficients are exact.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "exact_reference.h"
#include "fdsurf/adaptive.h"

namespace fdsurf {
namespace {

using testing::I128;

constexpr double kOneQuantumRaw = 65536.0;

struct Emitted {
  std::uint32_t position;
  std::array<std::int32_t, 3> point;
};

template <typename Acc>
std::vector<Emitted> StepAll(const PreparedAdaptiveCurve<3>& curve) {
  std::vector<Emitted> out;
  AdaptiveCurveStepper<Acc, 3>(curve).ForEachPoint(
      [&out](std::uint32_t position, const std::int32_t(&p)[3]) {
        out.push_back({position, {p[0], p[1], p[2]}});
      });
  return out;
}

std::vector<Emitted> StepAll(const PreparedAdaptiveCurve<3>& curve) {
  return curve.format.acc_bits == 64 ? StepAll<std::int64_t>(curve) : StepAll<Int128>(curve);
}

// A random cubic in quanta whose values stay within about ±range.
struct DoubleCubic {
  double c[3][4];  // per axis a, b, c, d
};

DoubleCubic RandomCubic(std::mt19937_64& rng, double range) {
  std::uniform_real_distribution<double> dist(-range, range);
  DoubleCubic cubic;
  for (auto& axis : cubic.c) {
    // From 4 random values at t = 0, 1/3, 2/3, 1 (a Lagrange cubic): realistic
    // curves, with coefficients up to ~20× the range.
    const double y0 = dist(rng), y1 = dist(rng), y2 = dist(rng), y3 = dist(rng);
    axis[0] = 4.5 * (-y0 + 3 * y1 - 3 * y2 + y3);
    axis[1] = 4.5 * (2 * y0 - 5 * y1 + 4 * y2 - y3);
    axis[2] = -5.5 * y0 + 9 * y1 - 4.5 * y2 + y3;
    axis[3] = y0;
  }
  return cubic;
}

void ToRaw(const DoubleCubic& cubic, PowerCurve1 (&raw)[3]) {
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 4; ++k) {
      raw[c].c[k] = static_cast<std::int64_t>(std::nearbyint(cubic.c[c][k] * kOneQuantumRaw));
    }
  }
}

long double Evaluate(const double (&axis)[4], long double t) {
  return ((axis[0] * t + axis[1]) * t + axis[2]) * t + axis[3];
}

// Euclidean distance from p to the segment [a, b].
long double DistanceToSegment(const std::array<long double, 3>& p,
                              const std::array<long double, 3>& a,
                              const std::array<long double, 3>& b) {
  long double ab2 = 0, ap_ab = 0;
  for (int c = 0; c < 3; ++c) {
    ab2 += (b[c] - a[c]) * (b[c] - a[c]);
    ap_ab += (p[c] - a[c]) * (b[c] - a[c]);
  }
  const long double u = ab2 > 0 ? std::clamp(ap_ab / ab2, 0.0L, 1.0L) : 0.0L;
  long double d2 = 0;
  for (int c = 0; c < 3; ++c) {
    const long double q = a[c] + u * (b[c] - a[c]);
    d2 += (p[c] - q) * (p[c] - q);
  }
  return std::sqrt(d2);
}

// The largest distance of the original curve from the emitted polyline, per
// chord, sampled densely in the chord's parameter interval; and of each
// emitted point from the curve at its parameter.
long double WorstDeviation(const DoubleCubic& cubic, const std::vector<Emitted>& points,
                           int level) {
  long double worst = 0;
  const long double scale = std::ldexp(1.0L, -level);
  for (size_t k = 0; k < points.size(); ++k) {
    std::array<long double, 3> a{};
    for (int c = 0; c < 3; ++c) a[c] = points[k].point[c];
    const long double ta = points[k].position * scale;
    long double d2 = 0;
    for (int c = 0; c < 3; ++c) d2 += std::pow(Evaluate(cubic.c[c], ta) - a[c], 2);
    worst = std::max(worst, std::sqrt(d2));
    if (k + 1 == points.size()) break;
    std::array<long double, 3> b{};
    for (int c = 0; c < 3; ++c) b[c] = points[k + 1].point[c];
    const long double tb = points[k + 1].position * scale;
    constexpr int kSamples = 24;
    for (int i = 1; i < kSamples; ++i) {
      const long double t = ta + (tb - ta) * i / kSamples;
      std::array<long double, 3> p{};
      for (int c = 0; c < 3; ++c) p[c] = Evaluate(cubic.c[c], t);
      worst = std::max(worst, DistanceToSegment(p, a, b));
    }
  }
  return worst;
}

// Exact value of the prepared (rounded-coefficient) curve at position/2^L is
// rounded to `k`: |k − x| ≤ 1/2 with x = Σ coef·pos^(3-j)·2^(jL) / 2^(3L+16).
bool IsExactlyRounded(const PowerCurve1& raw, std::uint32_t position, int level, std::int32_t k) {
  const I128 p = position;
  const I128 num = raw.c[0] * p * p * p + (raw.c[1] * p * p << level) +
                   (raw.c[2] * p << (2 * level)) + (I128(raw.c[3]) << (3 * level));
  const I128 den = I128(1) << (3 * level + 16);
  I128 diff = I128(k) * den - num;
  if (diff < 0) diff = -diff;
  return 2 * diff <= den;
}

TEST(AdaptiveCurve, EveryPointIsTheExactlyRoundedValueAndEveryChordIsWithinTolerance) {
  std::mt19937_64 rng(20261122);
  const double tolerances[] = {1.0, 2.5, 10.0, 200.0};
  for (int trial = 0; trial < 400; ++trial) {
    const double range = std::ldexp(1.0, 4 + trial % 16);  // up to 2^19 quanta
    const DoubleCubic cubic = RandomCubic(rng, range);
    PowerCurve1 raw[3];
    ToRaw(cubic, raw);
    const double tolerance = tolerances[trial % 4];
    AdaptiveSettings settings;
    settings.tolerance_q8 = static_cast<std::uint32_t>(tolerance * 256);
    PreparedAdaptiveCurve<3> curve;
    ASSERT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk) << trial;
    const auto points = StepAll(curve);
    ASSERT_GE(points.size(), 2u);
    EXPECT_EQ(points.front().position, 0u);
    EXPECT_EQ(points.back().position, std::uint32_t{1} << curve.finest_level);
    for (size_t k = 0; k < points.size(); ++k) {
      if (k > 0) {
        ASSERT_GT(points[k].position, points[k - 1].position);
      }
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(
            IsExactlyRounded(raw[c], points[k].position, curve.finest_level, points[k].point[c]))
            << "trial " << trial << " point " << k << " axis " << c;
      }
    }
    EXPECT_LE(WorstDeviation(cubic, points, curve.finest_level), tolerance)
        << "trial " << trial << " tolerance " << tolerance;
  }
}

TEST(AdaptiveCurve, BothAccumulatorsEmitTheSameBits) {
  std::mt19937_64 rng(7);
  int compared = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const DoubleCubic cubic = RandomCubic(rng, std::ldexp(1.0, 6 + trial % 12));
    PowerCurve1 raw[3];
    ToRaw(cubic, raw);
    AdaptiveSettings settings;
    settings.tolerance_q8 = 3 * 256;
    settings.mode = trial % 2 == 0 ? AdaptiveMode::kTolerance : AdaptiveMode::kStepExact;
    PreparedAdaptiveCurve<3> curve;
    ASSERT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk);
    if (curve.format.acc_bits != 64) continue;
    ++compared;
    const auto narrow = StepAll<std::int64_t>(curve);
    const auto wide = StepAll<Int128>(curve);
    ASSERT_EQ(narrow.size(), wide.size());
    for (size_t k = 0; k < narrow.size(); ++k) {
      EXPECT_EQ(narrow[k].position, wide[k].position);
      EXPECT_EQ(narrow[k].point, wide[k].point);
    }
  }
  EXPECT_GT(compared, 20);
}

TEST(AdaptiveCurve, StepExactPathsMoveAtMostOneQuantumPerAxisAndNeverRepeat) {
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 60; ++trial) {
    const DoubleCubic cubic = RandomCubic(rng, std::ldexp(1.0, 3 + trial % 10));
    PowerCurve1 raw[3];
    ToRaw(cubic, raw);
    AdaptiveSettings settings;
    settings.tolerance_q8 = 2 * 256;
    settings.mode = AdaptiveMode::kStepExact;
    PreparedAdaptiveCurve<3> curve;
    ASSERT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk);
    const auto points = StepAll(curve);
    for (size_t k = 1; k < points.size(); ++k) {
      int moved = 0;
      for (int c = 0; c < 3; ++c) {
        const int delta = points[k].point[c] - points[k - 1].point[c];
        ASSERT_LE(std::abs(delta), 1) << "trial " << trial << " point " << k;
        moved += delta != 0;
      }
      ASSERT_GT(moved, 0) << "repeated point, trial " << trial;
    }
    EXPECT_LE(WorstDeviation(cubic, points, curve.finest_level), 2.0) << trial;
  }
}

TEST(AdaptiveCurve, AStraightLineIsOneChord) {
  const DoubleCubic line{{{0, 0, 1000, -3}, {0, 0, -250.5, 7}, {0, 0, 0, 1}}};
  PowerCurve1 raw[3];
  ToRaw(line, raw);
  AdaptiveSettings settings;
  settings.tolerance_q8 = 256;
  PreparedAdaptiveCurve<3> curve;
  ASSERT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk);
  EXPECT_EQ(StepAll(curve).size(), 2u);
}

// For y = b·t² the chord deviation at step h is b·h²/4 exactly, so the fewest
// uniform steps are N = ceil(sqrt(b/(4·budget))); power-of-two adaptation may
// need up to twice that, never more.
TEST(AdaptiveCurve, PointCountIsWithinTwiceTheUniformOptimumOnAParabola) {
  for (double b : {50.0, 1e3, 3e4, 1e6}) {
    const DoubleCubic parabola{{{0, 0, 100, 0}, {0, b, 0, 0}, {0, 0, 0, 0}}};
    PowerCurve1 raw[3];
    ToRaw(parabola, raw);
    AdaptiveSettings settings;
    settings.tolerance_q8 = 4 * 256;
    PreparedAdaptiveCurve<3> curve;
    ASSERT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk);
    const double budget = 4.0 / std::sqrt(3.0) - 0.5 - 1.0 / 1024;
    const double optimum = std::ceil(std::sqrt(b / (4 * budget)));
    const auto steps = static_cast<double>(StepAll(curve).size() - 1);
    EXPECT_LE(steps, 2 * optimum) << b;
    EXPECT_GE(steps, optimum / 1.3) << b;  // the √3 norm factor costs at most √(√3)
  }
}

TEST(AdaptiveCurve, RefusesWhatItCannotServe) {
  PowerCurve1 raw[3] = {{{1 << 20, 5, 6, 7}}, {{0, 0, 0, 0}}, {{0, 0, 0, 0}}};
  PreparedAdaptiveCurve<3> curve;
  AdaptiveSettings settings;
  settings.tolerance_q8 = 222;  // 0.867 quanta < √3·(0.5 + 2^-10) = 0.8677
  EXPECT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kToleranceUnreachable);
  settings.tolerance_q8 = 224;  // 0.875 quanta: enough with the rounded-down 1/√3
  EXPECT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk);

  PowerCurve1 huge[3] = {{{std::int64_t{1} << 46, std::int64_t{1} << 46, 0, 0}}, {}, {}};
  settings.tolerance_q8 = 256;
  EXPECT_EQ(PrepareAdaptiveCurve(huge, settings, &curve), Status::kGeometryOutOfRange);

  // A step-exact path over ±2^30 quanta would need steps below 2^-30.
  PowerCurve1 fast[3] = {{{0, 0, std::int64_t{1} << 46, 0}}, {}, {}};
  settings.mode = AdaptiveMode::kStepExact;
  EXPECT_EQ(PrepareAdaptiveCurve(fast, settings, &curve), Status::kPrecisionUnreachable);
  // ... and over ±2^20 quanta it needs the 128-bit accumulator.
  PowerCurve1 medium[3] = {{{0, 0, std::int64_t{1} << 36, 0}}, {}, {}};
  settings.max_acc_bits = 64;
  EXPECT_EQ(PrepareAdaptiveCurve(medium, settings, &curve), Status::kPrecisionUnreachable);
  settings.max_acc_bits = 128;
  ASSERT_EQ(PrepareAdaptiveCurve(medium, settings, &curve), Status::kOk);
  EXPECT_EQ(curve.format.acc_bits, 128);
}

I128 FromInt128(const Int128& v) {
  return I128(static_cast<std::int64_t>(v.hi)) * (I128(1) << 64) + I128(v.lo);
}

// The prepared curve against the formulas of docs/toolpaths.md, evaluated
// here in __int128 and long double: the table Δ⁰..Δ³ at step 2^-L, the step
// limit 2^F, the chord limit min(budget·2^(3+3L), 2^(acc−2)), and the
// accumulator the bound 8·(22|a| + 5|b| + 2|c| + |d|)·2^(3L) + 2^F calls for
// (64-bit below 2^62 with F ≤ 62; not decided here within 10^-9 of 2^62).
void ExpectTheDocumentedTable(const PowerCurve1 (&raw)[3], const AdaptiveSettings& settings,
                              const PreparedAdaptiveCurve<3>& curve, int trial) {
  const int level = curve.finest_level;
  const int frac_bits = 16 + 3 * level;
  ASSERT_EQ(curve.format.frac_bits, frac_bits) << trial;
  long double bound = 0;
  for (int c = 0; c < 3; ++c) {
    const I128 a = raw[c].c[0], b = raw[c].c[1], cc = raw[c].c[2], d = raw[c].c[3];
    ASSERT_TRUE(FromInt128(curve.d[c][0]) == d * (I128(1) << (3 * level))) << trial;
    ASSERT_TRUE(FromInt128(curve.d[c][1]) ==
                a + b * (I128(1) << level) + cc * (I128(1) << (2 * level)))
        << trial;
    ASSERT_TRUE(FromInt128(curve.d[c][2]) == 6 * a + 2 * b * (I128(1) << level)) << trial;
    ASSERT_TRUE(FromInt128(curve.d[c][3]) == 6 * a) << trial;
    const long double sum = 22.0L * std::fabs(static_cast<long double>(raw[c].c[0])) +
                            5.0L * std::fabs(static_cast<long double>(raw[c].c[1])) +
                            2.0L * std::fabs(static_cast<long double>(raw[c].c[2])) +
                            std::fabs(static_cast<long double>(raw[c].c[3]));
    bound = std::max(bound, std::ldexp(8 * sum, 3 * level) + std::ldexp(1.0L, frac_bits));
  }
  const long double limit64 = std::ldexp(1.0L, 62);
  if (std::fabs(bound / limit64 - 1) > 1e-9L) {
    const bool fits64 = frac_bits <= 62 && bound < limit64 && settings.max_acc_bits >= 64;
    EXPECT_EQ(curve.format.acc_bits, fits64 ? 64 : 128) << trial;
  }
  EXPECT_TRUE(FromInt128(curve.step_limit) == I128(1) << frac_bits) << trial;
  // The tolerance per axis (256/√3 rounded down: 147) less half a quantum
  // and 2^-10 quanta, in 2^-16 quanta.
  const std::int64_t budget16 =
      static_cast<std::int64_t>(settings.tolerance_q8) * 147 - (1 << 15) - 64;
  const long double chord = std::ldexp(static_cast<long double>(budget16), 3 + 3 * level);
  const long double clamp = std::ldexp(1.0L, curve.format.acc_bits - 2);
  if (chord < clamp) {
    EXPECT_TRUE(FromInt128(curve.chord_limit) == I128(budget16) << (3 + 3 * level)) << trial;
  } else {
    EXPECT_TRUE(FromInt128(curve.chord_limit) == I128(1) << (curve.format.acc_bits - 2)) << trial;
  }
}

// The host plans, the device checks the level it is given with shifts and
// additions only. The planner searches for the level in WideInt arithmetic
// and forms the table with the check: at the planner's level the check
// accepts and the table is the documented one; below it the check refuses
// (the planner's level is the smallest that passes), and above it the check
// accepts while the accumulator still holds the values. The curves span 2^2..2^27 quanta, in both
// modes and at tolerances from the smallest reachable one, so both accumulators and every refusal
// are met.
TEST(AdaptiveCurve, ALevelChosenElsewhereIsCheckedAsThePlannerChecksIt) {
  std::mt19937_64 rng(20261206);
  const double tolerances[] = {0.875, 1.0, 4.0, 200.0};
  int planned[2] = {0, 0};  // 64-bit, 128-bit
  int refused_below = 0;
  int accepted_above = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double range = std::ldexp(1.0, 2 + trial % 26);
    const DoubleCubic cubic = RandomCubic(rng, range);
    PowerCurve1 raw[3];
    ToRaw(cubic, raw);
    AdaptiveSettings settings;
    settings.tolerance_q8 = static_cast<std::uint32_t>(tolerances[trial % 4] * 256);
    settings.mode = (trial / 4) % 2 == 0 ? AdaptiveMode::kStepExact : AdaptiveMode::kTolerance;
    settings.max_acc_bits = (trial / 8) % 3 == 0 ? 64 : 128;
    PreparedAdaptiveCurve<3> by_planner;
    const Status planned_status = PrepareAdaptiveCurve(raw, settings, &by_planner);
    PreparedAdaptiveCurve<3> at_level;
    if (planned_status != Status::kOk) {
      // Refused at every level the planner could have chosen.
      for (int level = 0; level <= kMaxAdaptiveLevel; ++level) {
        ASSERT_NE(PrepareAdaptiveCurveAtLevel(raw, level, settings, &at_level), Status::kOk)
            << trial << " level " << level;
      }
      continue;
    }
    ++planned[by_planner.format.acc_bits == 64 ? 0 : 1];
    ExpectTheDocumentedTable(raw, settings, by_planner, trial);
    const int level = by_planner.finest_level;
    ASSERT_EQ(PrepareAdaptiveCurveAtLevel(raw, level, settings, &at_level), Status::kOk) << trial;
    if (level > 0) {
      ASSERT_EQ(PrepareAdaptiveCurveAtLevel(raw, level - 1, settings, &at_level),
                Status::kPrecisionUnreachable)
          << trial;
      ++refused_below;
    }
    // One level finer: the same curve, accepted unless its values outgrow
    // the accumulators allowed; then its points are the planner's points of
    // that finer grid, and the path stays within the tolerance.
    if (PrepareAdaptiveCurveAtLevel(raw, level + 1, settings, &at_level) == Status::kOk) {
      ++accepted_above;
      ASSERT_EQ(at_level.finest_level, level + 1);
      if (range <= 1024) {  // stepped where that is quick
        const auto points = StepAll(at_level);
        EXPECT_LE(WorstDeviation(cubic, points, at_level.finest_level), tolerances[trial % 4])
            << trial;
      }
    }
  }
  EXPECT_GT(planned[0], 500);
  EXPECT_GT(planned[1], 300);
  EXPECT_GT(refused_below, 1000);
  EXPECT_GT(accepted_above, 1000);
}

// A device without Int128 code sets a host's level up in 64-bit arithmetic
// (the Arduino Uno, issue 17). At every level it must accept exactly what the
// Int128 form accepts for the 64-bit accumulator, with the same table, and
// each table it accepts must have B = 8·(22|a| + 5|b| + 2|c| + |d|)·2^(3L) +
// 2^F below 2^62, computed here exactly.
TEST(AdaptiveCurve, TheSixtyFourBitSetUpAcceptsWhatTheWideOneAcceptsForThatAccumulator) {
  std::mt19937_64 rng(20261207);
  const double tolerances[] = {0.875, 1.0, 4.0, 200.0};
  int accepted = 0;
  int needs_wide = 0;  // refused here, taken by the Int128 accumulator
  for (int trial = 0; trial < 1500; ++trial) {
    const DoubleCubic cubic = RandomCubic(rng, std::ldexp(1.0, 2 + trial % 26));
    PowerCurve1 raw[3];
    ToRaw(cubic, raw);
    AdaptiveSettings settings;
    settings.tolerance_q8 = static_cast<std::uint32_t>(tolerances[trial % 4] * 256);
    settings.mode = (trial / 4) % 2 == 0 ? AdaptiveMode::kStepExact : AdaptiveMode::kTolerance;
    for (int level = -1; level <= kMaxAdaptiveLevel + 1; ++level) {
      settings.max_acc_bits = 64;
      PreparedAdaptiveCurve<3> wide;
      const Status wide_status = PrepareAdaptiveCurveAtLevel(raw, level, settings, &wide);
      PreparedAdaptiveCurve<3, std::int64_t> narrow;
      const Status narrow_status = PrepareAdaptiveCurveAtLevel(raw, level, settings, &narrow);
      ASSERT_EQ(narrow_status, wide_status) << trial << " level " << level;
      if (narrow_status != Status::kOk) {
        settings.max_acc_bits = 128;
        needs_wide += PrepareAdaptiveCurveAtLevel(raw, level, settings, &wide) == Status::kOk;
        continue;
      }
      ++accepted;
      ASSERT_EQ(narrow.format.acc_bits, 64);
      ASSERT_EQ(narrow.format.frac_bits, wide.format.frac_bits);
      ASSERT_EQ(narrow.finest_level, level);
      ASSERT_EQ(narrow.mode, settings.mode);
      I128 bound = 0;
      for (int c = 0; c < 3; ++c) {
        for (int k = 0; k < 4; ++k) {
          ASSERT_TRUE(I128(narrow.d[c][k]) == FromInt128(wide.d[c][k])) << trial << " " << c;
        }
        I128 sum = 0;
        for (int k = 0; k < 4; ++k) {
          const I128 value = raw[c].c[k];
          sum += (k == 0 ? 22 : k == 1 ? 5 : k == 2 ? 2 : 1) * (value < 0 ? -value : value);
        }
        bound = std::max(bound, ((8 * sum) << (3 * level)) + (I128(1) << (16 + 3 * level)));
      }
      ASSERT_TRUE(bound < I128(1) << 62) << trial << " level " << level;
      ASSERT_TRUE(I128(narrow.chord_limit) == FromInt128(wide.chord_limit)) << trial;
      ASSERT_TRUE(I128(narrow.step_limit) == FromInt128(wide.step_limit)) << trial;
    }
  }
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(needs_wide, 10000);
}

// The same agreement exactly at the edges of the 64-bit tests, where random
// curves seldom fall: the range (the largest |d| with B < 2^62, and one more)
// and the chord limit (|b| with (2|b|)·2^L equal to it, and one more).
TEST(AdaptiveCurve, TheSixtyFourBitSetUpDrawsItsEdgesWhereTheWideOneDoes) {
  AdaptiveSettings settings;
  settings.tolerance_q8 = 256;
  settings.max_acc_bits = 64;
  const std::int64_t budget16 = 256 * 147 - (1 << 15) - 64;
  for (int level = 5; level <= 15; ++level) {
    const I128 room = (I128(1) << 62) - (I128(1) << (16 + 3 * level)) - 1;
    const auto largest_d = static_cast<std::int64_t>(room >> (3 * level + 3));
    const std::int64_t largest_b = budget16 << (2 + 2 * level);
    const std::int64_t cases[4][2] = {
        {0, largest_d}, {0, largest_d + 1}, {largest_b, 0}, {largest_b + 1, 0}};
    for (int k = 0; k < 4; ++k) {
      const PowerCurve1 raw[3] = {{{0, cases[k][0], 0, cases[k][1]}}, {}, {}};
      PreparedAdaptiveCurve<3> wide;
      PreparedAdaptiveCurve<3, std::int64_t> narrow;
      const Status expected = k % 2 == 0 ? Status::kOk : Status::kPrecisionUnreachable;
      if (cases[k][0] != 0 && (cases[k][0] * 5 * 8) >> (62 - 3 * level) != 0) continue;
      EXPECT_EQ(PrepareAdaptiveCurveAtLevel(raw, level, settings, &wide), expected)
          << "level " << level << " case " << k;
      EXPECT_EQ(PrepareAdaptiveCurveAtLevel(raw, level, settings, &narrow), expected)
          << "level " << level << " case " << k;
    }
  }
}

TEST(AdaptiveCurve, ALevelChosenElsewhereIsRefusedOutsideItsRange) {
  PowerCurve1 raw[3] = {{{1 << 20, 5, 6, 7}}, {{0, 0, 0, 0}}, {{0, 0, 0, 0}}};
  AdaptiveSettings settings;
  settings.tolerance_q8 = 256;
  PreparedAdaptiveCurve<3> curve;
  EXPECT_EQ(PrepareAdaptiveCurveAtLevel(raw, -1, settings, &curve), Status::kPrecisionUnreachable);
  EXPECT_EQ(PrepareAdaptiveCurveAtLevel(raw, kMaxAdaptiveLevel + 1, settings, &curve),
            Status::kPrecisionUnreachable);
  settings.tolerance_q8 = 222;
  EXPECT_EQ(PrepareAdaptiveCurveAtLevel(raw, 5, settings, &curve), Status::kToleranceUnreachable);
  PowerCurve1 huge[3] = {{{std::int64_t{1} << 46, std::int64_t{1} << 46, 0, 0}}, {}, {}};
  settings.tolerance_q8 = 256;
  EXPECT_EQ(PrepareAdaptiveCurveAtLevel(huge, 5, settings, &curve), Status::kGeometryOutOfRange);
}

// Walker coefficients against the exact rational line: for an s-line at
// s = i/n, coefficient l of t^(3-l) is Σ_r Σ_c w_s[r]·g[r][c]·(dM)[l][c] / (d²n³).
// floor(n / d) for d > 0.
I128 FloorDivide(I128 n, I128 d) {
  const I128 q = n / d;
  return (n % d != 0 && n < 0) ? q - 1 : q;
}

// floor((x + 1/2)·2^8) of the prepared (rounded-coefficient) curve at
// position/2^L, exactly: the chord cursor's point before it wraps.
I128 ExactFine(const PowerCurve1& raw, std::uint32_t position, int level) {
  const I128 p = position;
  const I128 num = raw.c[0] * p * p * p + (raw.c[1] * p * p << level) +
                   (raw.c[2] * p << (2 * level)) + (I128(raw.c[3]) << (3 * level));
  const I128 den = I128(1) << (3 * level + 16);
  return FloorDivide(num * 256 + den * 128, den);
}

long double ExactValue(const PowerCurve1& raw, long double t) {
  return (((raw.c[0] * t + raw.c[1]) * t + raw.c[2]) * t + raw.c[3]) / kOneQuantumRaw;
}

struct Chord {
  std::uint32_t position;
  std::array<std::int32_t, 3> fine;
  bool finest;
};

template <typename Acc>
std::vector<Chord> ChordsOf(const PreparedAdaptiveCurve<3>& curve, int budget_bits) {
  AdaptiveChordCursor<Acc, 3> cursor;
  cursor.Reset(curve, budget_bits);
  std::vector<Chord> out;
  std::int32_t fine[3];
  bool finest = false;
  while (cursor.Next(fine, &finest))
    out.push_back({cursor.position(), {fine[0], fine[1], fine[2]}, finest});
  return out;
}

// The chord cursor on step-exact tables (what the device steps), checked
// against the exact rounded-coefficient curve: every end is its exact fine
// value (mod 2^32), every chord that is not one finest step is within its
// budget (2^-6, 2^-9 or 2^-13 quanta per axis) of the curve at the same
// parameter (sampled), a finest step moves at most one quantum, no chord
// more than 2^8; with kFinestStepsOnly every chord is one finest step; both
// accumulators give the same chords.
TEST(AdaptiveChordCursor, EndsAreExactAndChordsWithinTheirBudget) {
  std::mt19937_64 rng(20261207);
  const double tolerances[] = {1.0, 2.5, 10.0};
  const int budgets[] = {6, 9, 13, kFinestStepsOnly};
  int long_chords = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int budget_bits = budgets[trial % 4];
    const double range = std::ldexp(1.0, trial % 17);  // 1 to 2^16 quanta
    const DoubleCubic cubic = RandomCubic(rng, range);
    PowerCurve1 raw[3];
    ToRaw(cubic, raw);
    AdaptiveSettings settings;
    settings.mode = AdaptiveMode::kStepExact;
    settings.tolerance_q8 = static_cast<std::uint32_t>(tolerances[trial % 3] * 256);
    PreparedAdaptiveCurve<3> curve;
    ASSERT_EQ(PrepareAdaptiveCurve(raw, settings, &curve), Status::kOk) << trial;
    const int level = curve.finest_level;
    const std::vector<Chord> chords = curve.format.acc_bits == 64
                                          ? ChordsOf<std::int64_t>(curve, budget_bits)
                                          : ChordsOf<Int128>(curve, budget_bits);
    if (curve.format.acc_bits == 64) {
      const std::vector<Chord> wide = ChordsOf<Int128>(curve, budget_bits);
      ASSERT_EQ(wide.size(), chords.size()) << trial;
      for (std::size_t k = 0; k < chords.size(); ++k) ASSERT_EQ(wide[k].fine, chords[k].fine);
    }
    ASSERT_GE(chords.size(), 2u);
    EXPECT_EQ(chords.front().position, 0u);
    EXPECT_EQ(chords.back().position, std::uint32_t{1} << level);
    const long double scale = std::ldexp(1.0L, -level);
    for (std::size_t k = 0; k < chords.size(); ++k) {
      for (int c = 0; c < 3; ++c) {
        const I128 exact = ExactFine(raw[c], chords[k].position, level);
        ASSERT_EQ(chords[k].fine[c], static_cast<std::int32_t>(static_cast<std::uint32_t>(exact)))
            << "trial " << trial << " chord end " << k << " axis " << c;
      }
      if (k == 0) continue;
      ASSERT_GT(chords[k].position, chords[k - 1].position);
      if (budget_bits == kFinestStepsOnly) {
        ASSERT_TRUE(chords[k].finest);
        ASSERT_EQ(chords[k].position, chords[k - 1].position + 1);
      }
      const long double budget = std::ldexp(1.0L, -budget_bits);
      const long double ta = chords[k - 1].position * scale;
      const long double tb = chords[k].position * scale;
      for (int c = 0; c < 3; ++c) {
        const long double a = ExactValue(raw[c], ta);
        const long double b = ExactValue(raw[c], tb);
        EXPECT_LE(std::fabs(b - a), 256.0L) << "trial " << trial << " chord " << k;
        if (chords[k].finest) {
          EXPECT_LE(std::fabs(b - a), 1.0L + 1e-9L) << "trial " << trial << " chord " << k;
          continue;
        }
        for (int i = 1; i < 32; ++i) {
          const long double v = i / 32.0L;
          const long double on_curve = ExactValue(raw[c], ta + (tb - ta) * v);
          EXPECT_LE(std::fabs(on_curve - (a + (b - a) * v)), budget + 1e-9L)
              << "trial " << trial << " chord " << k << " axis " << c;
        }
      }
      if (!chords[k].finest && chords[k].position - chords[k - 1].position >= 4) ++long_chords;
    }
  }
  // Chords of many finest steps are the rule. (A finest step whose chord
  // exceeds the budget needs a turn of a few quanta's radius, which a
  // step-exact level rarely leaves; ChordDda.AFinestStepIsOneEventToItsEnd
  // tests what is done with one.)
  EXPECT_GT(long_chords, 10000);
}

// The budget a tolerance leaves: a point rounded from a chord within it is
// within the tolerance, √d·(1/2 + 2^-10 + 2^-8 + 2^-b) ≤ tol, and the budget
// is the largest power of two (from 2^-6) that the integer test allows.
TEST(ChordBudgetBits, LeavesEveryChordPointWithinTheTolerance) {
  int finest_only = 0;
  for (int dims = 1; dims <= 3; ++dims) {
    const long double root = std::sqrt(static_cast<long double>(dims));
    int last = kFinestStepsOnly;
    for (std::uint32_t q8 = 1; q8 <= 4 * 256; ++q8) {
      const long double tolerance = q8 / 256.0L;
      if (tolerance <= root * (0.5L + std::ldexp(1.0L, -10))) continue;  // refused
      const int bits = ChordBudgetBits(q8, dims);
      if (bits == kFinestStepsOnly) {
        ++finest_only;
        EXPECT_EQ(last, kFinestStepsOnly) << q8;  // only at the smallest tolerances
        continue;
      }
      ASSERT_GE(bits, kLargestChordBudgetBits);
      ASSERT_LE(bits, kSmallestChordBudgetBits);
      const long double reach =
          0.5L + std::ldexp(1.0L, -10) + std::ldexp(1.0L, -8) + std::ldexp(1.0L, -bits);
      EXPECT_LE(root * reach, tolerance) << "dims " << dims << " q8 " << q8;
      if (last != kFinestStepsOnly) EXPECT_LE(bits, last) << q8;  // never tighter as tol grows
      last = bits;
    }
    EXPECT_EQ(last, kLargestChordBudgetBits) << dims;  // 4 steps leave the largest
  }
  EXPECT_GT(finest_only, 0);
}

TEST(IsolineWalker, LineCoefficientsAreTheExactlyRoundedOnes) {
  std::mt19937_64 rng(5);
  const Basis bases[] = {Basis::kPower, Basis::kHermite, Basis::kBezier, Basis::kBSpline,
                         Basis::kCatmullRom};
  std::uniform_int_distribution<std::int64_t> dist(-(std::int64_t{1} << 36), std::int64_t{1} << 36);
  for (int trial = 0; trial < 60; ++trial) {
    const Basis basis = bases[trial % 5];
    const auto& b = testing::TestBasisFor(static_cast<int>(basis));
    PatchGeometry1 geometry[3];
    std::int64_t g[3][4][4];
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
          g[c][i][j] = dist(rng);
          geometry[c].g[i][j] = GeometryFixed::FromRaw(g[c][i][j]);
        }
      }
    }
    const int lines = 2 + trial * 17 % 40;
    const int n = lines - 1;
    for (IsolineFamily family : {IsolineFamily::kSLines, IsolineFamily::kTLines}) {
      IsolineWalker<3> walker;
      ASSERT_EQ(IsolineWalker<3>::Create(geometry, basis, family, static_cast<std::uint16_t>(lines),
                                         &walker),
                Status::kOk);
      PowerCurve1 curve[3];
      for (int i = 0; i < lines; ++i) {
        ASSERT_TRUE(walker.Next(curve));
        const auto w = testing::ScaledWeights(b, i, n);
        for (int c = 0; c < 3; ++c) {
          for (int l = 0; l < 4; ++l) {
            I128 num = 0;
            for (int r = 0; r < 4; ++r) {
              for (int q = 0; q < 4; ++q) {
                num += family == IsolineFamily::kSLines ? w[r] * g[c][r][q] * b.m[l][q]
                                                        : w[q] * g[c][r][q] * b.m[l][r];
              }
            }
            const I128 den = I128(b.denominator) * b.denominator * n * n * n;
            I128 diff = I128(curve[c].c[l]) * den - num;
            if (diff < 0) diff = -diff;
            ASSERT_LE(2 * diff, den) << "trial " << trial << " line " << i << " coef " << l;
          }
        }
      }
      EXPECT_FALSE(walker.Next(curve));
    }
  }
}

// Each entry point applies GeometryInRange (fixed.h): |raw| < 2^31 quanta.
TEST(GeometryRange, EveryEntryPointRefusesTheLimitAndAcceptsJustBelowIt) {
  for (const std::int64_t sign : {1, -1}) {
    const GeometryFixed inside = GeometryFixed::FromRaw(sign * (kGeometryLimitRaw - 1));
    const GeometryFixed limit = GeometryFixed::FromRaw(sign * kGeometryLimitRaw);

    // Curve geometry to power coefficients (a constant curve at the value).
    CurveGeometry1 curve[1] = {{{inside, inside, inside, inside}}};
    PowerCurve1 power[1];
    EXPECT_EQ(CurvePowerCoefficients(curve, Basis::kBezier, power), Status::kOk);
    curve[0].g[2] = limit;
    EXPECT_EQ(CurvePowerCoefficients(curve, Basis::kBezier, power), Status::kGeometryOutOfRange);

    // The isoline walker: one control value of the patch at the limit.
    PatchGeometry1 patch[2] = {};
    IsolineWalker<2> walker;
    patch[1].g[1][2] = inside;
    EXPECT_EQ(IsolineWalker<2>::Create(patch, Basis::kBezier, IsolineFamily::kSLines, 4, &walker),
              Status::kOk);
    patch[1].g[1][2] = limit;
    EXPECT_EQ(IsolineWalker<2>::Create(patch, Basis::kBezier, IsolineFamily::kTLines, 4, &walker),
              Status::kGeometryOutOfRange);
  }

  // Power coefficients far outside: each magnitude is checked on its own, so
  // a sum of magnitudes that wraps around in 64 bits cannot pass for small.
  const std::int64_t most_negative = std::numeric_limits<std::int64_t>::min();
  PowerCurve1 wrapped[1] = {{{most_negative, most_negative, 0, 0}}};
  PreparedAdaptiveCurve<1> prepared;
  AdaptiveSettings settings;
  settings.tolerance_q8 = 256;
  EXPECT_EQ(PrepareAdaptiveCurve(wrapped, settings, &prepared), Status::kGeometryOutOfRange);
}

TEST(IsolineWalker, RefusesBadLineCounts) {
  PatchGeometry1 geometry[2] = {};
  IsolineWalker<2> walker;
  EXPECT_EQ(IsolineWalker<2>::Create(geometry, Basis::kBezier, IsolineFamily::kSLines, 1, &walker),
            Status::kGridOutOfRange);
  EXPECT_EQ(IsolineWalker<2>::Create(geometry, Basis::kBezier, IsolineFamily::kSLines,
                                     kMaxPatchSteps + 2, &walker),
            Status::kGridOutOfRange);
  EXPECT_EQ(
      IsolineWalker<2>::Create(geometry, static_cast<Basis>(9), IsolineFamily::kSLines, 4, &walker),
      Status::kInvalidArgument);
}

}  // namespace
}  // namespace fdsurf
