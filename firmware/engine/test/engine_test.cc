// SPDX-License-Identifier: MIT
// The fixed-point engine against the exact rational reference
// (exact_reference.h): every emitted point within 0.51 quanta, for every
// basis, many grids, and geometry at the edge of the supported range.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "exact_reference.h"
#include "fdsurf/forward_difference.h"

namespace fdsurf {
namespace {

using testing::ExactCurvePoint;
using testing::ExactPatchPoint;
using testing::I128;
using testing::IsRoundedValue;
using testing::Rational;
using testing::WithinBound;

constexpr std::int64_t kOneQuantumRaw = std::int64_t{1} << kGeometryFracBits;
const Basis kAllBases[] = {Basis::kPower, Basis::kHermite, Basis::kBezier, Basis::kBSpline,
                           Basis::kCatmullRom};

// Raw geometry (units of 2^-16 quanta) of one patch, per coordinate.
struct RawPatch {
  std::int64_t g[3][4][4];
};

// Random geometry whose surface stays within about ±range quanta: power
// coefficients are scaled down so that their sum stays in range, Hermite
// tangents may be a few times larger than the points (as real tangents are).
RawPatch RandomPatch(std::mt19937_64& rng, Basis basis, double range_quanta) {
  RawPatch patch;
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        double limit = range_quanta;
        if (basis == Basis::kPower) limit /= 16;
        if (basis == Basis::kHermite && (i >= 2 || j >= 2)) limit *= 2;
        std::uniform_real_distribution<double> dist(-limit, limit);
        patch.g[c][i][j] = static_cast<std::int64_t>(dist(rng) * kOneQuantumRaw);
      }
    }
  }
  return patch;
}

Rational ExactPoint(Basis basis, const std::int64_t (&g)[4][4], int i, int n, int j, int m) {
  Rational x = ExactPatchPoint(static_cast<int>(basis), g, i, n, j, m);
  x.denominator *= kOneQuantumRaw;  // geometry carries 16 fractional bits
  return x;
}

Status Prepare(const RawPatch& raw, Basis basis, int n, int m, PreparedPatch<3>* out,
               PrepareOptions options = {}) {
  PatchGeometry1 geometry[3];
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) geometry[c].g[i][j] = GeometryFixed::FromRaw(raw.g[c][i][j]);
    }
  }
  return PreparePatch(geometry, basis, static_cast<std::uint16_t>(n), static_cast<std::uint16_t>(m),
                      options, out);
}

struct GridPoints {
  int n;
  int m;
  std::vector<std::int32_t> xyz;  // 3 per point, i-major
  void Put(std::uint32_t i, std::uint32_t j, const std::int32_t (&p)[3]) {
    const std::size_t at = 3 * (static_cast<std::size_t>(i) * (m + 1) + j);
    for (int c = 0; c < 3; ++c) xyz[at + c] = p[c];
  }
};

template <typename Acc>
void Step(const PreparedPatch<3>& prepared, GridPoints* s_lines, GridPoints* t_lines) {
  std::size_t count = 0;
  PatchStepper<Acc, 3>(prepared).ForEachSLinePoint(
      [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&p)[3]) {
        s_lines->Put(i, j, p);
        ++count;
      });
  PatchStepper<Acc, 3>(prepared).ForEachTLinePoint(
      [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&p)[3]) {
        t_lines->Put(i, j, p);
        ++count;
      });
  EXPECT_EQ(count, 2 * static_cast<std::size_t>(s_lines->n + 1) * (s_lines->m + 1));
}

// One stepping of the whole grid, to be checked point by point.
struct SteppedGrid {
  const char* how;
  GridPoints points;
};

// The per-line stepper (LinePatchStepper), both families, where the plan has
// their formats. The two families round different lines, so they need not
// agree bit for bit: each is checked against the exact patch on its own.
void StepLines(const PreparedPatch<3>& prepared, std::vector<SteppedGrid>* grids) {
  const int n = prepared.steps_s;
  const int m = prepared.steps_t;
  const std::size_t points = static_cast<std::size_t>(n + 1) * (m + 1);
  // Each point once, in order along the line (a segment's end is the next
  // one's start and must not be emitted twice).
  std::uint32_t calls = 0;
  std::uint32_t last_along = 0;
  bool in_order = true;
  const auto visit = [&](std::uint32_t along) {
    in_order = in_order && (along == 0 ? calls == 0 || last_along != 0 : along == last_along + 1);
    last_along = along;
    ++calls;
  };
  if (prepared.s_line_frac_bits != 0) {
    grids->push_back({"per-line s-lines", {n, m, std::vector<std::int32_t>(3 * points)}});
    GridPoints& grid = grids->back().points;
    LinePatchStepper<3>(prepared).ForEachSLinePoint(
        [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&p)[3]) {
          visit(j);
          grid.Put(i, j, p);
        });
    EXPECT_EQ(calls, points);
    EXPECT_TRUE(in_order);
  }
  calls = 0;
  if (prepared.t_line_frac_bits != 0) {
    grids->push_back({"per-line t-lines", {n, m, std::vector<std::int32_t>(3 * points)}});
    GridPoints& grid = grids->back().points;
    LinePatchStepper<3>(prepared).ForEachTLinePoint(
        [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&p)[3]) {
          visit(i);
          grid.Put(i, j, p);
        });
    EXPECT_EQ(calls, points);
    EXPECT_TRUE(in_order);
  }
}

// Steps the patch both ways (and per line, where planned) and checks every
// point against the exact value, computed once per point. Returns the number
// of points that broke the bound.
int CheckPatch(const RawPatch& raw, Basis basis, int n, int m, PrepareOptions options = {},
               bool expect_rounded = false) {
  PreparedPatch<3> prepared;
  const Status status = Prepare(raw, basis, n, m, &prepared, options);
  EXPECT_EQ(status, Status::kOk) << StatusMessage(status);
  if (status != Status::kOk) return 1;
  const std::size_t points = static_cast<std::size_t>(n + 1) * (m + 1);
  std::vector<SteppedGrid> grids;
  grids.push_back({"table", {n, m, std::vector<std::int32_t>(3 * points)}});
  GridPoints t_lines{n, m, std::vector<std::int32_t>(3 * points)};
  if (prepared.format.acc_bits == 64) {
    Step<std::int64_t>(prepared, &grids[0].points, &t_lines);
  } else {
    Step<Int128>(prepared, &grids[0].points, &t_lines);
  }
  // Both families visit the same sum of the same integers at (i, j).
  EXPECT_EQ(grids[0].points.xyz, t_lines.xyz) << "s-lines and t-lines disagree";
  StepLines(prepared, &grids);
  const bool report =
      options.test_only_frac_bits_removed == 0 && options.test_only_line_frac_bits_removed == 0;
  int violations = 0;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= m; ++j) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t at = 3 * (static_cast<std::size_t>(i) * (m + 1) + j) + c;
        const Rational exact = ExactPoint(basis, raw.g[c], i, n, j, m);
        for (const SteppedGrid& grid : grids) {
          const std::int32_t k = grid.points.xyz[at];
          if (!WithinBound(k, exact) && ++violations <= 3 && report) {
            ADD_FAILURE() << BasisName(basis) << " " << n << "x" << m << " " << grid.how
                          << " point (" << i << "," << j << ") coordinate " << c << ": got " << k
                          << ", exact " << testing::ToDouble(exact);
          }
        }
        if (expect_rounded) {
          EXPECT_TRUE(IsRoundedValue(grids[0].points.xyz[at], exact))
              << "(" << i << "," << j << ") " << c;
        }
      }
    }
  }
  return violations;
}

TEST(PatchEngine, RandomPatchesOfEveryBasisOnManyGrids) {
  std::mt19937_64 rng(20261122);
  const int grids[][2] = {{1, 1},   {1, 7},    {2, 3},   {3, 3},   {5, 8},   {7, 13},
                          {16, 16}, {10, 100}, {33, 64}, {100, 1}, {63, 65}, {127, 3}};
  for (Basis basis : kAllBases) {
    for (const auto& grid : grids) {
      for (int trial = 0; trial < 6; ++trial) {
        const RawPatch patch = RandomPatch(rng, basis, 1 << 16);
        EXPECT_EQ(CheckPatch(patch, basis, grid[0], grid[1]), 0);
      }
    }
  }
}

TEST(PatchEngine, LargestGridsAtTheEdgeOfTheRange) {
  std::mt19937_64 rng(7);
  const int grids[][2] = {{1024, 1024}, {1023, 1021}, {1024, 3}, {997, 1024}};
  for (Basis basis : kAllBases) {
    for (const auto& grid : grids) {
      const RawPatch patch = RandomPatch(rng, basis, 1 << 20);
      EXPECT_EQ(CheckPatch(patch, basis, grid[0], grid[1]), 0);
    }
  }
}

TEST(PatchEngine, ExtremeControlPointsAtPlusMinusTwoToTheTwenty) {
  // Alternating ±2^20 quanta: the largest differences a Bézier or B-spline
  // net of that range can produce.
  for (Basis basis : {Basis::kBezier, Basis::kBSpline, Basis::kCatmullRom}) {
    RawPatch patch;
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
          const int sign = ((i + j + c) % 2 == 0) ? 1 : -1;
          patch.g[c][i][j] = sign * (std::int64_t{1} << 20) * kOneQuantumRaw;
        }
      }
    }
    EXPECT_EQ(CheckPatch(patch, basis, 1024, 1024), 0);
    EXPECT_EQ(CheckPatch(patch, basis, 1, 1), 0);
    EXPECT_EQ(CheckPatch(patch, basis, 3, 1000), 0);
  }
}

TEST(PrecisionPlanner, ServesEveryBasisAtPlusMinusTwoToTheTwentyOnEveryGrid) {
  // The documented promise: geometry within ±2^20 quanta is always served.
  std::mt19937_64 rng(37);
  for (Basis basis : kAllBases) {
    for (int trial = 0; trial < 50; ++trial) {
      RawPatch patch;
      for (auto& plane : patch.g) {
        for (auto& row : plane) {
          for (auto& v : row)
            v = ((rng() & 1) != 0 ? 1 : -1) * (std::int64_t{1} << 20) * kOneQuantumRaw;
        }
      }
      for (int n : {1, 2, 1000, 1024}) {
        PreparedPatch<3> prepared;
        EXPECT_EQ(Prepare(patch, basis, n, 1024, &prepared), Status::kOk) << BasisName(basis);
      }
    }
  }
}

TEST(PatchEngine, PowerOfTwoGridsWithWholeQuantaAreExact) {
  // Integer-matrix bases, whole-quantum geometry, power-of-two steps: the
  // table is exact, so every point is the correctly rounded exact value.
  std::mt19937_64 rng(3);
  for (Basis basis : {Basis::kBezier, Basis::kHermite, Basis::kPower}) {
    for (int n : {1, 2, 8, 64, 256}) {
      RawPatch patch = RandomPatch(rng, basis, 1 << 18);
      for (auto& plane : patch.g) {
        for (auto& row : plane) {
          for (auto& v : row) v = (v / kOneQuantumRaw) * kOneQuantumRaw;
        }
      }
      PreparedPatch<3> prepared;
      ASSERT_EQ(Prepare(patch, basis, n, n, &prepared), Status::kOk);
      EXPECT_TRUE(prepared.exact) << BasisName(basis) << " " << n;
      EXPECT_EQ(CheckPatch(patch, basis, n, n, {}, /*expect_rounded=*/true), 0);
    }
  }
}

TEST(PatchEngine, NonDyadicStepsAreNotExact) {
  std::mt19937_64 rng(5);
  const RawPatch patch = RandomPatch(rng, Basis::kBezier, 1000);
  PreparedPatch<3> prepared;
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 3, 3, &prepared), Status::kOk);
  EXPECT_FALSE(prepared.exact);
}

TEST(PatchEngine, TheBoundFailsWithoutThePlannedFractionalBits) {
  // The tests above would catch a planner that kept too few bits: with 16
  // bits fewer, a 1024×1024 B-spline patch (non-dyadic 1/6) breaks the bound.
  std::mt19937_64 rng(11);
  const RawPatch patch = RandomPatch(rng, Basis::kBSpline, 1 << 20);
  PrepareOptions weakened;
  weakened.test_only_frac_bits_removed = 16;
  EXPECT_GT(CheckPatch(patch, Basis::kBSpline, 1024, 1024, weakened), 0);
}

// Per-line rounding (docs/precision.md): every grid whose table needs the
// 128-bit accumulator gets 64-bit lines for geometry within ±2^19 quanta,
// with the line formats of the derivation, and every point of both
// families is within the bound (CheckPatch steps them; the tests at ±2^20
// above step them too wherever the planner could give the lines 64 bits).
TEST(PatchEngine, PerLineRoundingSteps128BitTablesIn64BitLines) {
  std::mt19937_64 rng(17);
  const int grids[][2] = {{1024, 1024}, {997, 1024}, {256, 256}, {1024, 40}};
  for (Basis basis : kAllBases) {
    for (const auto& grid : grids) {
      const RawPatch patch = RandomPatch(rng, basis, 1 << 19);
      PreparedPatch<3> prepared;
      ASSERT_EQ(Prepare(patch, basis, grid[0], grid[1], &prepared), Status::kOk);
      ASSERT_EQ(prepared.format.acc_bits, 128) << grid[0] << "x" << grid[1];
      // Exactly 32 bits (a point is then the position's high word); lines
      // whose derivation asks for more are stepped in segments that ask for
      // 32 or fewer: 1024 and 997 steps in 2 of at most 512 and 499.
      const auto segment = [](int steps) {
        return steps == 1024 ? 512 : steps == 997 ? 499 : steps;
      };
      EXPECT_EQ(prepared.s_line_frac_bits, 32)
          << BasisName(basis) << " " << grid[0] << "x" << grid[1];
      EXPECT_EQ(prepared.t_line_frac_bits, 32)
          << BasisName(basis) << " " << grid[0] << "x" << grid[1];
      EXPECT_EQ(prepared.s_line_segment_steps, segment(grid[1]));
      EXPECT_EQ(prepared.t_line_segment_steps, segment(grid[0]));
      EXPECT_EQ(CheckPatch(patch, basis, grid[0], grid[1]), 0);
    }
  }
}

// The check above would catch a planner that gave the lines too few bits:
// with 12 fewer, a 1024×1024 B-spline patch breaks the bound on its lines.
TEST(PatchEngine, PerLineRoundingFailsWithoutItsPlannedBits) {
  std::mt19937_64 rng(19);
  const RawPatch patch = RandomPatch(rng, Basis::kBSpline, 1 << 20);
  PrepareOptions weakened;
  weakened.test_only_line_frac_bits_removed = 12;
  EXPECT_GT(CheckPatch(patch, Basis::kBSpline, 1024, 1024, weakened), 0);
}

TEST(PatchEngine, ChoosesTheNarrowestAccumulator) {
  std::mt19937_64 rng(13);
  const RawPatch patch = RandomPatch(rng, Basis::kBezier, 2000);
  PreparedPatch<3> prepared;
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 64, 64, &prepared), Status::kOk);
  EXPECT_EQ(prepared.format.acc_bits, 64);
  EXPECT_EQ(prepared.format.frac_bits, RequiredFracBits(64, 64));
  // F = 40 > 32: its lines get 32 bits (a point is the high word), in one
  // segment each.
  EXPECT_EQ(prepared.s_line_frac_bits, 32);
  EXPECT_EQ(prepared.t_line_frac_bits, 32);
  EXPECT_EQ(prepared.s_line_segment_steps, 64);
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 1024, 1024, &prepared), Status::kOk);
  EXPECT_EQ(prepared.format.acc_bits, 128);
  // A word-aligned table's own points are the high word already: no lines.
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 16, 16, &prepared), Status::kOk);
  EXPECT_EQ(prepared.format.word_aligned, 1);
  EXPECT_EQ(prepared.s_line_frac_bits, 0);
  EXPECT_EQ(prepared.t_line_frac_bits, 0);
}

// Word-aligned stepping (docs/precision.md): a 64-bit table with F <= 32
// is stepped with 32 fractional bits and the rounding half in the position,
// and a point is the position's high word. It must give exactly the bits of
// the table as planned, stepped by the independent 128-bit stepper, which
// ignores the alignment and rounds every point with RoundToQuanta.
TEST(PatchEngine, WordAlignedSteppingGivesTheBitsOfThePlannedTable) {
  std::mt19937_64 rng(23);
  const int grids[][2] = {{1, 1}, {3, 5}, {16, 16}, {17, 17}, {25, 25}, {40, 7}, {1, 60}};
  int aligned = 0;
  for (Basis basis : kAllBases) {
    for (const auto& grid : grids) {
      // ±2^17 quanta: 131 mm at 1 µm. At ±2^20 a 1×1 grid's differences
      // (bounded over [0, 4]²) can pass 2^31 quanta, and the table is then
      // not aligned (PrecisionPlanner.WordAlignsOnlyWhatFits).
      const RawPatch patch = RandomPatch(rng, basis, 1 << 17);
      PreparedPatch<3> prepared;
      ASSERT_EQ(Prepare(patch, basis, grid[0], grid[1], &prepared), Status::kOk);
      ASSERT_EQ(prepared.format.acc_bits, 64);
      ASSERT_LE(prepared.format.frac_bits, 32) << grid[0] << "x" << grid[1];
      ASSERT_EQ(prepared.format.word_aligned, 1) << BasisName(basis) << " " << grid[0];
      ++aligned;
      const std::size_t points = static_cast<std::size_t>(grid[0] + 1) * (grid[1] + 1);
      GridPoints word_s{grid[0], grid[1], std::vector<std::int32_t>(3 * points)};
      GridPoints word_t = word_s;
      GridPoints wide_s = word_s;
      GridPoints wide_t = word_s;
      Step<std::int64_t>(prepared, &word_s, &word_t);
      Step<Int128>(prepared, &wide_s, &wide_t);
      EXPECT_EQ(word_s.xyz, wide_s.xyz) << BasisName(basis) << " " << grid[0] << "x" << grid[1];
      EXPECT_EQ(word_t.xyz, wide_t.xyz) << BasisName(basis) << " " << grid[0] << "x" << grid[1];
    }
  }
  EXPECT_EQ(aligned, 35);
}

TEST(CurveEngine, WordAlignedSteppingGivesTheBitsOfThePlannedTable) {
  std::mt19937_64 rng(29);
  for (Basis basis : kAllBases) {
    for (int n : {1, 2, 7, 256, 300, 369}) {
      CurveGeometry1 geometry[3];
      std::uniform_real_distribution<double> dist(-(1 << 20), 1 << 20);
      for (auto& coordinate : geometry) {
        for (auto& g : coordinate.g) {
          g = GeometryFixed::FromRaw(static_cast<std::int64_t>(dist(rng) * kOneQuantumRaw));
        }
      }
      PreparedCurve<3> curve;
      ASSERT_EQ(PrepareCurve(geometry, basis, static_cast<std::uint16_t>(n), {}, &curve),
                Status::kOk);
      ASSERT_EQ(curve.format.word_aligned, 1) << BasisName(basis) << " n=" << n;
      std::vector<std::int32_t> word;
      std::vector<std::int32_t> wide;
      CurveStepper<std::int64_t, 3>(curve).ForEachPoint(
          [&](std::uint32_t, const std::int32_t(&p)[3]) { word.insert(word.end(), p, p + 3); });
      CurveStepper<Int128, 3>(curve).ForEachPoint(
          [&](std::uint32_t, const std::int32_t(&p)[3]) { wide.insert(wide.end(), p, p + 3); });
      EXPECT_EQ(word, wide) << BasisName(basis) << " n=" << n;
    }
  }
}

// The planner aligns only what fits: not when F > 32 (the high word would
// drop fractional bits), not when a difference comes within 2 quanta of
// 2^31 (the moved table would not fit 64 bits).
TEST(PrecisionPlanner, WordAlignsOnlyWhatFits) {
  std::mt19937_64 rng(31);
  const RawPatch patch = RandomPatch(rng, Basis::kBezier, 2000);
  PreparedPatch<3> prepared;
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 25, 25, &prepared), Status::kOk);
  EXPECT_EQ(prepared.format.frac_bits, 32);
  EXPECT_EQ(prepared.format.word_aligned, 1);
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 26, 26, &prepared), Status::kOk);
  EXPECT_EQ(prepared.format.frac_bits, 33);
  EXPECT_EQ(prepared.format.acc_bits, 64);
  EXPECT_EQ(prepared.format.word_aligned, 0);

  // x(t) = a·t³, one step: the position stays within a, but the second
  // difference's bound over [0, 3] is 18·a (docs/precision.md, step 5). It
  // aligns while 18·a + 2 < 2^31, that is up to a = 119 304 646 quanta.
  const auto one_step_power_curve = [](std::int64_t a_quanta, PreparedCurve<1>* curve) {
    CurveGeometry1 geometry[1];
    geometry[0].g[0] = GeometryFixed::FromRaw(a_quanta * kOneQuantumRaw);
    for (int k = 1; k < 4; ++k) geometry[0].g[k] = GeometryFixed::FromRaw(0);
    return PrepareCurve(geometry, Basis::kPower, 1, {}, curve);
  };
  PreparedCurve<1> curve;
  ASSERT_EQ(one_step_power_curve(119304646, &curve), Status::kOk);
  EXPECT_EQ(curve.format.acc_bits, 64);
  EXPECT_EQ(curve.format.word_aligned, 1);
  ASSERT_EQ(one_step_power_curve(119304647, &curve), Status::kOk);
  EXPECT_EQ(curve.format.acc_bits, 64);
  EXPECT_EQ(curve.format.word_aligned, 0);
}

TEST(PrecisionPlanner, RequiredLineFracBitsMatchTheDerivation) {
  // bitlength(S(n)) + 7: S(1024) = 178 957 825 < 2^28, S(256) = 2 796 417 < 2^22,
  // S(40) = 10 701 < 2^14.
  EXPECT_EQ(RequiredLineFracBits(1024), 28 + 7);
  EXPECT_EQ(RequiredLineFracBits(256), 22 + 7);
  EXPECT_EQ(RequiredLineFracBits(40), 14 + 7);
  EXPECT_EQ(RequiredLineFracBits(1), 2 + 7);
}

// Segments are the fewest of equal length (rounded up) whose lines need 32
// fractional bits or fewer: bitlength(S(n)) + 7 ≤ 32 up to n = 586.
TEST(PrecisionPlanner, LineSegmentsAreTheFewestThatNeed32Bits) {
  EXPECT_EQ(RequiredLineFracBits(586), 32);
  EXPECT_EQ(RequiredLineFracBits(587), 33);
  EXPECT_EQ(LineSegmentSteps(586), 586);
  EXPECT_EQ(LineSegmentSteps(587), 294);
  EXPECT_EQ(LineSegmentSteps(1024), 512);
  EXPECT_EQ(LineSegmentSteps(2000), 500);
  EXPECT_EQ(LineSegmentSteps(65535), 586);  // 112 segments
  for (std::uint32_t steps = 1; steps <= 4000; ++steps) {
    const std::uint32_t length = LineSegmentSteps(static_cast<std::uint16_t>(steps));
    const std::uint32_t segments = (steps + length - 1) / length;
    ASSERT_LE(RequiredLineFracBits(length), 32) << steps;
    if (segments > 1) {
      const std::uint32_t fewer = (steps + segments - 2) / (segments - 1);
      ASSERT_GT(RequiredLineFracBits(fewer), 32) << steps;
    }
  }
}

// Advancing a vector m steps at once is m row-add updates, negative and
// wrapping values included (the stepper's own update is the reference).
TEST(PatchEngine, AdvanceExactlyIsThatManySteps) {
  std::mt19937_64 rng(23);
  for (std::uint32_t steps : {0u, 1u, 2u, 3u, 17u, 499u, 512u, 586u, 2000u}) {
    for (int trial = 0; trial < 20; ++trial) {
      Int128 advanced[4];
      for (Int128& entry : advanced) entry = Int128{rng(), trial < 10 ? rng() : ~std::uint64_t{0}};
      Int128 stepped[4];
      for (int k = 0; k < 4; ++k) stepped[k] = advanced[k];
      for (std::uint32_t i = 0; i < steps; ++i) internal::Step(stepped);
      internal::AdvanceExactly(advanced, steps);
      for (int k = 0; k < 4; ++k) {
        EXPECT_TRUE(advanced[k] == stepped[k]) << steps << " steps, entry " << k;
      }
    }
  }
}

// A table built by hand with no segment length (0) steps each line whole:
// at 256 steps, one segment by plan, the points are the planned ones.
TEST(PatchEngine, NoSegmentLengthStepsWholeLines) {
  std::mt19937_64 rng(29);
  const RawPatch patch = RandomPatch(rng, Basis::kBezier, 1 << 17);
  PreparedPatch<3> planned;
  ASSERT_EQ(Prepare(patch, Basis::kBezier, 256, 256, &planned), Status::kOk);
  ASSERT_EQ(planned.s_line_segment_steps, 256);
  PreparedPatch<3> by_hand = planned;
  by_hand.s_line_segment_steps = 0;
  std::vector<std::int32_t> expected;
  std::vector<std::int32_t> actual;
  const auto into = [](std::vector<std::int32_t>* out) {
    return [out](std::uint32_t, std::uint32_t, const std::int32_t(&p)[3]) {
      out->insert(out->end(), p, p + 3);
    };
  };
  LinePatchStepper<3>(planned).ForEachSLinePoint(into(&expected));
  LinePatchStepper<3>(by_hand).ForEachSLinePoint(into(&actual));
  EXPECT_EQ(actual.size(), 3u * 257 * 257);
  EXPECT_TRUE(actual == expected);
}

TEST(PrecisionPlanner, RequiredFracBitsMatchTheDerivation) {
  // S(n) = Σ_{k≤3} C(n,k); F = bitlength(S(n)·S(m)) + 9 (docs/precision.md).
  const auto s = [](std::uint64_t n) {
    return 1 + n + n * (n - 1) / 2 + n * (n - 1) * (n - 2) / 6;
  };
  for (std::uint32_t n : {1u, 2u, 3u, 64u, 100u, 1024u}) {
    for (std::uint32_t m : {1u, 7u, 1024u}) {
      const std::uint64_t product = s(n) * s(m);
      int bits = 0;
      while ((product >> bits) != 0) ++bits;
      EXPECT_EQ(RequiredFracBits(n, m), bits + 9);
      // The stepping error bound 2^-(F+1)·S(n)·S(m) is at most 2^-10 quanta.
      EXPECT_LE(static_cast<double>(product) / std::ldexp(1.0, RequiredFracBits(n, m) + 1),
                std::ldexp(1.0, -10));
    }
  }
  EXPECT_EQ(RequiredFracBits(1024, 1024), 64);
}

// A Hermite tangent may be three times the curve it shapes: x(s) = (V/3)·s³
// has P1 = V/3 and T1 = V. With V at 2^31 quanta the surface (below 2^31/3
// quanta) fits the output, so only the geometry range (GeometryInRange)
// refuses it; just below the limit it is accepted.
TEST(PrecisionPlanner, RefusesGeometryAtTheLimitEvenWhenTheSurfaceFits) {
  for (const std::int64_t v :
       {kGeometryLimitRaw - 1, kGeometryLimitRaw, -(kGeometryLimitRaw - 1), -kGeometryLimitRaw}) {
    RawPatch patch = {};
    for (int j = 0; j < 2; ++j) {  // P0 = P1 = 1, no tangents along t: constant in t
      patch.g[0][1][j] = v / 3;    // P1 along s
      patch.g[0][3][j] = v;        // T1 along s
    }
    PreparedPatch<3> prepared;
    const bool inside = v > -kGeometryLimitRaw && v < kGeometryLimitRaw;
    EXPECT_EQ(Prepare(patch, Basis::kHermite, 4, 4, &prepared),
              inside ? Status::kOk : Status::kGeometryOutOfRange)
        << v;
  }
}

TEST(PrecisionPlanner, RefusesWhatItCannotServe) {
  std::mt19937_64 rng(17);
  RawPatch patch = RandomPatch(rng, Basis::kBezier, 1000);
  PreparedPatch<3> prepared;
  prepared.format = {0, 0, 0};
  EXPECT_EQ(Prepare(patch, Basis::kBezier, 0, 4, &prepared), Status::kGridOutOfRange);
  EXPECT_EQ(Prepare(patch, Basis::kBezier, 4, 1025, &prepared), Status::kGridOutOfRange);
  EXPECT_EQ(Prepare(patch, static_cast<Basis>(9), 4, 4, &prepared), Status::kInvalidArgument);

  // Geometry at 2^31 quanta is outside the geometry format.
  RawPatch huge = patch;
  huge.g[1][2][3] = kGeometryLimitRaw;
  EXPECT_EQ(Prepare(huge, Basis::kBezier, 4, 4, &prepared), Status::kGeometryOutOfRange);
  huge.g[1][2][3] = -kGeometryLimitRaw;
  EXPECT_EQ(Prepare(huge, Basis::kBezier, 4, 4, &prepared), Status::kGeometryOutOfRange);

  // Power coefficients inside the format whose sum leaves the int32 output.
  RawPatch sum = patch;
  for (auto& row : sum.g[0]) {
    for (auto& v : row) v = (std::int64_t{1} << 29) * kOneQuantumRaw;
  }
  EXPECT_EQ(Prepare(sum, Basis::kPower, 4, 4, &prepared), Status::kGeometryOutOfRange);

  // A caller limited to 64-bit accumulators: a 1024×1024 grid needs F = 64.
  PrepareOptions narrow;
  narrow.max_acc_bits = 64;
  EXPECT_EQ(Prepare(patch, Basis::kBezier, 1024, 1024, &prepared, narrow),
            Status::kPrecisionUnreachable);
  // Refusals leave the output untouched.
  EXPECT_EQ(prepared.format.acc_bits, 0);
  // The same caller is served on a grid that fits.
  EXPECT_EQ(Prepare(patch, Basis::kBezier, 64, 64, &prepared, narrow), Status::kOk);
}

// ---- Curves ------------------------------------------------------------------

TEST(CurveEngine, SeedHermiteExampleFirstSegment) {
  // Seed 002, example 94: from A(1,1) to B(3,1), start direction v = (0,1),
  // end direction w = (0,-1). The first segment is x(u) = 1 + 6u² − 4u³ and
  // y(u) = 1 + u − u². Quantum 0.001: geometry in thousandths.
  const std::int64_t q = 1000 * kOneQuantumRaw;
  CurveGeometry1 geometry[2];
  const std::int64_t x[4] = {1 * q, 3 * q, 0, 0};
  const std::int64_t y[4] = {1 * q, 1 * q, 1 * q, -1 * q};
  for (int k = 0; k < 4; ++k) {
    geometry[0].g[k] = GeometryFixed::FromRaw(x[k]);
    geometry[1].g[k] = GeometryFixed::FromRaw(y[k]);
  }
  for (int n : {4, 10, 1000}) {
    PreparedCurve<2> curve;
    ASSERT_EQ(PrepareCurve(geometry, Basis::kHermite, static_cast<std::uint16_t>(n), {}, &curve),
              Status::kOk);
    int count = 0;
    CurveStepper<Int128, 2>(curve).ForEachPoint([&](std::uint32_t i, const std::int32_t(&p)[2]) {
      // x·1000 at u = i/n, exactly: (1000n³ + 6000·i²·n − 4000·i³) / n³.
      const I128 n3 = I128(n) * n * n;
      const Rational exact_x{1000 * n3 + 6000 * I128(i) * i * n - 4000 * I128(i) * i * i, n3};
      const Rational exact_y{1000 * n3 + 1000 * I128(i) * n * n - 1000 * I128(i) * i * n, n3};
      EXPECT_TRUE(WithinBound(p[0], exact_x)) << i << "/" << n;
      EXPECT_TRUE(WithinBound(p[1], exact_y)) << i << "/" << n;
      ++count;
    });
    EXPECT_EQ(count, n + 1);
  }
}

TEST(CurveEngine, RandomCurvesOfEveryBasisUpToTheLargestStepCount) {
  std::mt19937_64 rng(19);
  for (Basis basis : kAllBases) {
    for (int n : {1, 2, 3, 10, 1000, 4096, 65535}) {
      CurveGeometry1 geometry[3];
      std::int64_t raw[3][4];
      std::uniform_real_distribution<double> dist(-(1 << 20), 1 << 20);
      for (int c = 0; c < 3; ++c) {
        for (int k = 0; k < 4; ++k) {
          double v = dist(rng);
          if (basis == Basis::kPower) v /= 4;
          raw[c][k] = static_cast<std::int64_t>(v * kOneQuantumRaw);
          geometry[c].g[k] = GeometryFixed::FromRaw(raw[c][k]);
        }
      }
      PreparedCurve<3> curve;
      ASSERT_EQ(PrepareCurve(geometry, basis, static_cast<std::uint16_t>(n), {}, &curve),
                Status::kOk);
      int bad = 0;
      const auto check = [&](std::uint32_t i, const std::int32_t(&p)[3]) {
        for (int c = 0; c < 3; ++c) {
          Rational exact = ExactCurvePoint(static_cast<int>(basis), raw[c], i, n);
          exact.denominator *= kOneQuantumRaw;
          if (!WithinBound(p[c], exact)) ++bad;
        }
      };
      if (curve.format.acc_bits == 64) {
        CurveStepper<std::int64_t, 3>(curve).ForEachPoint(check);
      } else {
        CurveStepper<Int128, 3>(curve).ForEachPoint(check);
      }
      EXPECT_EQ(bad, 0) << BasisName(basis) << " n=" << n;
    }
  }
}

}  // namespace
}  // namespace fdsurf
