// SPDX-License-Identifier: MIT
// Set-up of adaptive curves and of the isoline walker. docs/toolpaths.md
// derives the level choice, the range bound and the chord test used here.
#include "fdsurf/adaptive.h"

#include "fdsurf/fixed.h"
#include "fdsurf/internal/wide_int.h"

namespace fdsurf {
namespace {

using Wide = internal::WideInt<8>;

// Coordinates of the √dims factor: 256/√dims rounded down, so that a limit
// computed with it is never looser than the exact one.
const int64_t kInverseSqrtDims256[4] = {0, 256, 181, 147};

// Allowance, in 2^-16 quanta, for the errors made before stepping: the
// rounding of the geometry to 2^-16 quanta (≤ 16·(2^-17 + 2^-20) for the power
// basis, less for the others) and of the 4 power coefficients (≤ 4·2^-17).
constexpr int64_t kPreStepAllowance16 = 64;  // 2^-10 quanta

// The chord error each step may have, in 2^-16 quanta: the tolerance per
// axis (tolerance/√dims) less the output rounding (1/2 quantum) and the
// errors made before stepping. At most 2^32·256 < 2^40; ≤ 0 when the
// tolerance cannot be met with whole-quantum output.
int64_t ChordBudget16(uint32_t tolerance_q8, int dims) {
  return static_cast<int64_t>(tolerance_q8) * kInverseSqrtDims256[dims] - (int64_t{1} << 15) -
         kPreStepAllowance16;
}

}  // namespace

int ChordBudgetBits(uint32_t tolerance_q8, int dims) {
  // In 2^-16 quanta: what the tolerance leaves per axis after the rounding
  // of the points and the errors before stepping (ChordBudget16), less the
  // 2^-8 of a chord end's fine value.
  const int64_t room = ChordBudget16(tolerance_q8, dims) - (int64_t{1} << 8);
  for (int bits = kLargestChordBudgetBits; bits <= kSmallestChordBudgetBits; ++bits) {
    if ((int64_t{1} << (16 - bits)) <= room) return bits;
  }
  return kFinestStepsOnly;
}

namespace {

// round(x / (a·b)), halves away from zero, for |x| < 2^125 and a, b ≥ 1:
// floor((2|x| + ab) / 2ab) by successive floor divisions, which compose.
int64_t RoundedQuotient(const internal::WideInt<4>& x, uint32_t a, uint32_t b) {
  internal::WideInt<4> y =
      x.Abs().ShiftedLeft(1) + internal::WideInt<4>::FromUint64(static_cast<uint64_t>(a) * b);
  y.ShiftRightInPlace(1);
  y.DivideInPlace(a);
  y.DivideInPlace(b);
  const uint64_t magnitude =
      static_cast<uint64_t>(y.limb(0)) | (static_cast<uint64_t>(y.limb(1)) << 32);
  const int64_t value = static_cast<int64_t>(magnitude);
  return x.IsNegative() ? -value : value;
}

// Per axis: |a|, |b|, |c|, |d| in 2^-16 quanta. kGeometryOutOfRange when a
// coefficient is outside the geometry range, or the curve could leave int32
// (|x(t)| ≤ Σ|coefficients|, plus the rounding half).
template <int kDims>
Status CoefficientMagnitudes(const PowerCurve1 (&curve)[kDims], uint64_t (&m)[kDims][4]) {
  for (int c = 0; c < kDims; ++c) {
    uint64_t sum = 0;
    for (int k = 0; k < 4; ++k) {
      if (!GeometryInRange(curve[c].c[k])) return Status::kGeometryOutOfRange;
      m[c][k] = internal::Magnitude(curve[c].c[k]);
      sum += m[c][k];
    }
    if (sum + (uint64_t{1} << 15) >= static_cast<uint64_t>(kGeometryLimitRaw)) {
      return Status::kGeometryOutOfRange;
    }
  }
  return Status::kOk;
}

// The finest level L: the smallest at which every step of 2^-L passes.
// In units of 2^-(16+3L) quanta, |Δ²| ≤ (6|a| + 2|b|)·2^L + 6|a| and
// |Δ² − Δ³| is smaller; the chord limit is 8·budget = budget16·2^(3+3L).
// In step-exact mode also |Δ¹| ≤ (3|a| + 2|b| + |c|)·2^(2L) ≤ 2^(16+3L).
template <int kDims>
Status FinestLevel(const uint64_t (&m)[kDims][4], int64_t budget16, bool step_exact, int* out) {
  for (int level = 0;; ++level) {
    if (level > kMaxAdaptiveLevel) return Status::kPrecisionUnreachable;
    bool fits = true;
    const Wide chord_limit =
        Wide::FromUint64(static_cast<uint64_t>(budget16)).ShiftedLeft(3 + 3 * level);
    for (int c = 0; c < kDims && fits; ++c) {
      const Wide second = Wide::FromUint64(6 * m[c][0] + 2 * m[c][1]).ShiftedLeft(level) +
                          Wide::FromUint64(6 * m[c][0]);
      fits = !(chord_limit < second);
      if (fits && step_exact) {
        const Wide first = Wide::FromUint64(3 * m[c][0] + 2 * m[c][1] + m[c][2]);
        fits = !(Wide::PowerOfTwo(kCoefficientFracBits + level) < first);
      }
    }
    if (fits) {
      *out = level;
      return Status::kOk;
    }
  }
}

// PrepareAdaptiveCurveAtLevel's arithmetic: unsigned values below 2^127 in
// an Int128, shifted by 0 ≤ bits < 128 (the callers keep the result below
// 2^127 first).
Int128 ShiftedUp(uint64_t value, int bits) {
  if (bits == 0) return Int128{value, 0};
  if (bits < 64) return internal::ShiftLeft(Int128{value, 0}, bits);
  return Int128{0, value << (bits - 64)};
}

// value·2^bits modulo 2^128, for 0 ≤ bits < 128 (two's complement).
Int128 ShiftedBy(const Int128& value, int bits) {
  if (bits == 0) return value;
  if (bits < 64) return internal::ShiftLeft(value, bits);
  return Int128{0, value.lo << (bits - 64)};
}

// Whether value < 2^bits, for 0 ≤ bits ≤ 127.
bool Below(const Int128& value, int bits) {
  return bits >= 64 ? value.hi < (uint64_t{1} << (bits - 64))
                    : value.hi == 0 && value.lo < (uint64_t{1} << bits);
}

// The level's tests in Int128 arithmetic: FinestLevel's (which searches
// with them in WideInt), and the accumulator's: every value the stepper forms
// (differences at any level up to step 1, the doubling and halving
// intermediates, the rounding half) is below
// B = 8·(22|a| + 5|b| + 2|c| + |d|)·2^(3L) + 2^F; 64 bits when B < 2^62 (and
// F ≤ 62), else 128 when B < 2^126. With every coefficient below 2^47 (CoefficientMagnitudes)
// the sum S = 22|a| + 5|b| + 2|c| + |d| is below 2^52, so 8·S < 2^55 is
// shifted by 3L ≤ 90 only once it is known to stay below 2^126; then
// (6|a| + 2|b|)·2^L + 6|a| ≤ 8·S·2^(3L) < 2^126 too, and the chord limit is
// only formed when it is below 2^126 (else it exceeds every value the curve
// has, and the test passes).
//
// One axis at a time, in functions that are not templates, so that the 1-,
// 2- and 3-D set-ups share their code (Int128 arithmetic is long on 8-bit
// cores). *fits64 is cleared when the axis needs the Int128 accumulator.
FDSURF_OUT_OF_LINE_ON_AVR Status AxisFitsLevel(const uint64_t (&m)[4], int level, int64_t budget16,
                                               bool step_exact, bool* fits64) {
  const int frac_bits = kCoefficientFracBits + 3 * level;
  const int scale = 3 + 3 * level;  // the chord limit is budget16·8·2^(3L)
  const uint64_t eight_sum = 8 * (22 * m[0] + 5 * m[1] + 2 * m[2] + m[3]);
  if (!Below(Int128{eight_sum, 0}, 126 - 3 * level)) return Status::kPrecisionUnreachable;
  Int128 bound = ShiftedUp(eight_sum, 3 * level);
  bound += ShiftedUp(1, frac_bits);
  if (!Below(bound, 126)) return Status::kPrecisionUnreachable;
  *fits64 = *fits64 && Below(bound, 62);
  const Int128 second = ShiftedUp(6 * m[0] + 2 * m[1], level) + Int128{6 * m[0], 0};
  const uint64_t budget = static_cast<uint64_t>(budget16);
  const bool chord_limit_below_second =
      Below(Int128{budget, 0}, 126 - scale) && !(second <= ShiftedUp(budget, scale));
  if (chord_limit_below_second) return Status::kPrecisionUnreachable;
  if (step_exact && (uint64_t{1} << (kCoefficientFracBits + level)) < 3 * m[0] + 2 * m[1] + m[2]) {
    return Status::kPrecisionUnreachable;
  }
  return Status::kOk;
}

// One axis's table at step h = 2^-L, in units of 2^-(16+3L): Δ⁰ = d·2^3L,
// Δ¹ = a + b·2^L + c·2^2L, Δ² = 6a + 2b·2^L, Δ³ = 6a; every term is below B.
FDSURF_OUT_OF_LINE_ON_AVR void AxisTable(const PowerCurve1& axis, int level, Int128 (&d)[4]) {
  const Int128 a = internal::Widen(axis.c[0]);
  const Int128 b = internal::Widen(axis.c[1]);
  const Int128 six_a = internal::ShiftLeft(a, 2) + internal::ShiftLeft(a, 1);
  d[0] = ShiftedBy(internal::Widen(axis.c[3]), 3 * level);
  d[1] = a + ShiftedBy(b, level) + ShiftedBy(internal::Widen(axis.c[2]), 2 * level);
  d[2] = six_a + ShiftedBy(b, level + 1);
  d[3] = six_a;
}

// min(budget16·8·2^(3L), 2^(acc_bits − 2)): values never exceed B, so a
// larger limit would act the same, and the clamp keeps it representable.
Int128 ChordLimit(int64_t budget16, int level, int acc_bits) {
  const int clamp_bits = acc_bits - 2;
  const uint64_t budget = static_cast<uint64_t>(budget16);
  const int scale = 3 + 3 * level;
  const bool below_clamp = clamp_bits > scale && Below(Int128{budget, 0}, clamp_bits - scale);
  return below_clamp ? ShiftedUp(budget, scale) : ShiftedUp(1, clamp_bits);
}

// What the planner and the check at a level both start from: the chord
// budget and the coefficients' magnitudes, each checked.
template <int kDims>
Status CurveInputs(const PowerCurve1 (&curve)[kDims], const AdaptiveSettings& settings,
                   int64_t* budget16, uint64_t (&m)[kDims][4]) {
  static_assert(kDims >= 1 && kDims <= 3, "1, 2 or 3 coordinates");
  *budget16 = ChordBudget16(settings.tolerance_q8, kDims);
  if (*budget16 <= 0) return Status::kToleranceUnreachable;
  return CoefficientMagnitudes(curve, m);
}

// PrepareAdaptiveCurveAtLevel once CurveInputs has passed.
template <int kDims>
Status PrepareAtLevel(const PowerCurve1 (&curve)[kDims], const uint64_t (&m)[kDims][4],
                      int64_t budget16, int level, const AdaptiveSettings& settings,
                      PreparedAdaptiveCurve<kDims>* out) {
  if (level < 0 || level > kMaxAdaptiveLevel) return Status::kPrecisionUnreachable;
  const int frac_bits = kCoefficientFracBits + 3 * level;
  bool fits64 = frac_bits <= 62 && settings.max_acc_bits >= 64;
  for (int c = 0; c < kDims; ++c) {
    const Status status =
        AxisFitsLevel(m[c], level, budget16, settings.mode == AdaptiveMode::kStepExact, &fits64);
    if (status != Status::kOk) return status;
  }
  if (!fits64 && settings.max_acc_bits < 128) return Status::kPrecisionUnreachable;
  const int acc_bits = fits64 ? 64 : 128;

  PreparedAdaptiveCurve<kDims> result;
  result.format.acc_bits = static_cast<uint8_t>(acc_bits);
  result.format.frac_bits = static_cast<uint8_t>(frac_bits);
  result.format.word_aligned = 0;  // The cursor halves and doubles its steps.
  result.finest_level = static_cast<uint8_t>(level);
  result.mode = settings.mode;
  for (int c = 0; c < kDims; ++c) AxisTable(curve[c], level, result.d[c]);
  result.chord_limit = ChordLimit(budget16, level, acc_bits);
  result.step_limit = ShiftedUp(1, frac_bits);
  *out = result;
  return Status::kOk;
}

// AxisFitsLevel for the 64-bit accumulator only, in uint64_t: the same
// tests, so that it accepts exactly what AxisFitsLevel accepts with fits64
// still set. Every value formed stays below 2^63: 8·S < 2^55 is shifted by
// 3L only once it is known to stay below 2^62 (and F ≤ 62 makes 3L ≤ 46),
// B = 8·S·2^(3L) + 2^F < 2^63 then, and (6|a| + 2|b|)·2^L + 6|a| ≤ 8·S·2^(3L).
// A chord limit of 2^62 or more exceeds every value a table below 2^62 has,
// so its test passes (ChordLimit clamps it there too).
FDSURF_OUT_OF_LINE_ON_AVR Status AxisFitsLevel64(const uint64_t (&m)[4], int level,
                                                 int64_t budget16, bool step_exact) {
  constexpr uint64_t kLimit = uint64_t{1} << 62;
  const int frac_bits = kCoefficientFracBits + 3 * level;
  if (frac_bits > 62) return Status::kPrecisionUnreachable;
  const uint64_t eight_sum = 8 * (22 * m[0] + 5 * m[1] + 2 * m[2] + m[3]);
  if (eight_sum >= kLimit >> (3 * level)) return Status::kPrecisionUnreachable;
  const uint64_t bound = (eight_sum << (3 * level)) + (uint64_t{1} << frac_bits);
  if (bound >= kLimit) return Status::kPrecisionUnreachable;
  const uint64_t second = ((6 * m[0] + 2 * m[1]) << level) + 6 * m[0];
  const int scale = 3 + 3 * level;  // the chord limit is budget16·8·2^(3L)
  const uint64_t budget = static_cast<uint64_t>(budget16);
  if (budget < (kLimit >> scale) && second > (budget << scale)) {
    return Status::kPrecisionUnreachable;
  }
  if (step_exact && (uint64_t{1} << (kCoefficientFracBits + level)) < 3 * m[0] + 2 * m[1] + m[2]) {
    return Status::kPrecisionUnreachable;
  }
  return Status::kOk;
}

// AxisTable in int64_t, for a level AxisFitsLevel64 passed (every term is
// below B < 2^62).
FDSURF_OUT_OF_LINE_ON_AVR void AxisTable64(const PowerCurve1& axis, int level, int64_t (&d)[4]) {
  const int64_t a = axis.c[0];
  const int64_t six_a = 6 * a;
  d[0] = internal::ShiftLeft(axis.c[3], 3 * level);
  d[1] = a + internal::ShiftLeft(axis.c[1], level) + internal::ShiftLeft(axis.c[2], 2 * level);
  d[2] = six_a + internal::ShiftLeft(axis.c[1], level + 1);
  d[3] = six_a;
}

}  // namespace

template <int kDims>
Status PrepareAdaptiveCurveAtLevel(const PowerCurve1 (&curve)[kDims], int level,
                                   const AdaptiveSettings& settings,
                                   PreparedAdaptiveCurve<kDims>* out) {
  int64_t budget16 = 0;
  uint64_t m[kDims][4];
  const Status status = CurveInputs(curve, settings, &budget16, m);
  if (status != Status::kOk) return status;
  return PrepareAtLevel(curve, m, budget16, level, settings, out);
}

template <int kDims>
Status PrepareAdaptiveCurveAtLevel(const PowerCurve1 (&curve)[kDims], int level,
                                   const AdaptiveSettings& settings,
                                   PreparedAdaptiveCurve<kDims, int64_t>* out) {
  int64_t budget16 = 0;
  uint64_t m[kDims][4];
  const Status status = CurveInputs(curve, settings, &budget16, m);
  if (status != Status::kOk) return status;
  if (level < 0 || level > kMaxAdaptiveLevel) return Status::kPrecisionUnreachable;
  const bool step_exact = settings.mode == AdaptiveMode::kStepExact;
  for (int c = 0; c < kDims; ++c) {
    const Status fits = AxisFitsLevel64(m[c], level, budget16, step_exact);
    if (fits != Status::kOk) return fits;
  }
  const int frac_bits = kCoefficientFracBits + 3 * level;
  const int scale = 3 + 3 * level;
  const uint64_t budget = static_cast<uint64_t>(budget16);
  out->format.acc_bits = 64;
  out->format.frac_bits = static_cast<uint8_t>(frac_bits);
  out->format.word_aligned = 0;  // The cursor halves and doubles its steps.
  out->finest_level = static_cast<uint8_t>(level);
  out->mode = settings.mode;
  for (int c = 0; c < kDims; ++c) AxisTable64(curve[c], level, out->d[c]);
  // ChordLimit's min(budget16·8·2^(3L), 2^62).
  out->chord_limit = static_cast<int64_t>(
      budget < (uint64_t{1} << 62) >> scale ? budget << scale : uint64_t{1} << 62);
  out->step_limit = int64_t{1} << frac_bits;
  return Status::kOk;
}

// The search for the level is the planner's own (FinestLevel, in WideInt);
// PrepareAtLevel then checks that level in Int128 (the same tests, and the
// accumulator: docs/toolpaths.md, "Choosing the finest level, and the
// range") and forms the table, so that the table has one home.
template <int kDims>
Status PrepareAdaptiveCurve(const PowerCurve1 (&curve)[kDims], const AdaptiveSettings& settings,
                            PreparedAdaptiveCurve<kDims>* out) {
  int64_t budget16 = 0;
  uint64_t m[kDims][4];
  Status status = CurveInputs(curve, settings, &budget16, m);
  if (status != Status::kOk) return status;
  int level = 0;
  status = FinestLevel(m, budget16, settings.mode == AdaptiveMode::kStepExact, &level);
  if (status != Status::kOk) return status;
  return PrepareAtLevel(curve, m, budget16, level, settings, out);
}

template <int kDims>
Status CurvePowerCoefficients(const CurveGeometry1 (&geometry)[kDims], Basis basis,
                              PowerCurve1 (&out)[kDims]) {
  const BasisMatrix* m = GetBasisMatrix(basis);
  if (m == nullptr) return Status::kInvalidArgument;
  PowerCurve1 result[kDims];
  for (int c = 0; c < kDims; ++c) {
    for (int i = 0; i < 4; ++i) {
      if (!GeometryInRange(geometry[c].g[i])) return Status::kGeometryOutOfRange;
    }
    for (int k = 0; k < 4; ++k) {
      int64_t scaled = 0;  // |scaled| < 12·2^47
      for (int i = 0; i < 4; ++i) scaled += m->matrix[k][i] * geometry[c].g[i].Raw();
      result[c].c[k] = RoundedQuotient(internal::WideInt<4>::FromInt64(scaled),
                                       static_cast<uint32_t>(m->denominator), 1);
    }
  }
  for (int c = 0; c < kDims; ++c) out[c] = result[c];
  return Status::kOk;
}

template <int kDims>
Status IsolineWalker<kDims>::Create(const PatchGeometry1 (&geometry)[kDims], Basis basis,
                                    IsolineFamily family, uint16_t lines, IsolineWalker* out) {
  const BasisMatrix* m = GetBasisMatrix(basis);
  if (m == nullptr) return Status::kInvalidArgument;
  if (lines < 2 || lines - 1 > kMaxPatchSteps) return Status::kGridOutOfRange;
  const int64_t n = lines - 1;
  // E' = n³·E(1/n), the integer form of the difference operator across the patch.
  const int64_t e[4][4] = {{0, 0, 0, n * n * n}, {1, n, n * n, 0}, {6, 2 * n, 0, 0}, {6, 0, 0, 0}};
  IsolineWalker walker;
  int c = 0;
  for (const PatchGeometry1& g : geometry) {
    for (const auto& row : g.g) {
      for (const GeometryFixed& value : row) {
        if (!GeometryInRange(value)) return Status::kGeometryOutOfRange;
      }
    }
    // d²·2^16·C = (dM)·G·(dM)ᵀ, below 12·12·2^47 < 2^55 in magnitude.
    int64_t g_mt[4][4];
    for (int i = 0; i < 4; ++i) {
      for (int l = 0; l < 4; ++l) {
        int64_t sum = 0;
        for (int j = 0; j < 4; ++j) sum += g.g[i][j].Raw() * m->matrix[l][j];
        g_mt[i][l] = sum;
      }
    }
    int64_t power[4][4];  // [across][along]
    for (int k = 0; k < 4; ++k) {
      for (int l = 0; l < 4; ++l) {
        int64_t sum = 0;
        for (int i = 0; i < 4; ++i) sum += m->matrix[k][i] * g_mt[i][l];
        if (family == IsolineFamily::kSLines) {
          power[k][l] = sum;
        } else {
          power[l][k] = sum;
        }
      }
    }
    // The table E'·power: entries below 4·2^30·2^55 = 2^87.
    for (int r = 0; r < 4; ++r) {
      for (int l = 0; l < 4; ++l) {
        internal::WideInt<4> sum;
        for (int k = 0; k < 4; ++k) {
          if (e[r][k] != 0) sum += internal::WideInt<4>::FromInt64(power[k][l]).MulInt64(e[r][k]);
        }
        walker.table_[c][r][l] = internal::ToInt128(sum);
      }
    }
    ++c;
  }
  walker.divisor_[0] = static_cast<uint32_t>(m->denominator * m->denominator);
  walker.divisor_[1] = static_cast<uint32_t>(n * n * n);
  walker.lines_ = lines;
  walker.produced_ = 0;
  *out = walker;
  return Status::kOk;
}

template <int kDims>
bool IsolineWalker<kDims>::Next(PowerCurve1 (&curve)[kDims]) {
  if (produced_ >= lines_) return false;
  for (int c = 0; c < kDims; ++c) {
    for (int l = 0; l < 4; ++l) {
      curve[c].c[l] =
          RoundedQuotient(internal::FromInt128(table_[c][0][l]), divisor_[0], divisor_[1]);
    }
  }
  ++produced_;
  for (int c = 0; c < kDims; ++c) {
    for (int l = 0; l < 4; ++l) {
      table_[c][0][l] += table_[c][1][l];
      table_[c][1][l] += table_[c][2][l];
      table_[c][2][l] += table_[c][3][l];
    }
  }
  return true;
}

template Status PrepareAdaptiveCurve<1>(const PowerCurve1 (&)[1], const AdaptiveSettings&,
                                        PreparedAdaptiveCurve<1>*);
template Status PrepareAdaptiveCurve<2>(const PowerCurve1 (&)[2], const AdaptiveSettings&,
                                        PreparedAdaptiveCurve<2>*);
template Status PrepareAdaptiveCurve<3>(const PowerCurve1 (&)[3], const AdaptiveSettings&,
                                        PreparedAdaptiveCurve<3>*);
template Status PrepareAdaptiveCurveAtLevel<1>(const PowerCurve1 (&)[1], int,
                                               const AdaptiveSettings&, PreparedAdaptiveCurve<1>*);
template Status PrepareAdaptiveCurveAtLevel<2>(const PowerCurve1 (&)[2], int,
                                               const AdaptiveSettings&, PreparedAdaptiveCurve<2>*);
template Status PrepareAdaptiveCurveAtLevel<3>(const PowerCurve1 (&)[3], int,
                                               const AdaptiveSettings&, PreparedAdaptiveCurve<3>*);
template Status PrepareAdaptiveCurveAtLevel<1>(const PowerCurve1 (&)[1], int,
                                               const AdaptiveSettings&,
                                               PreparedAdaptiveCurve<1, int64_t>*);
template Status PrepareAdaptiveCurveAtLevel<2>(const PowerCurve1 (&)[2], int,
                                               const AdaptiveSettings&,
                                               PreparedAdaptiveCurve<2, int64_t>*);
template Status PrepareAdaptiveCurveAtLevel<3>(const PowerCurve1 (&)[3], int,
                                               const AdaptiveSettings&,
                                               PreparedAdaptiveCurve<3, int64_t>*);
template Status CurvePowerCoefficients<1>(const CurveGeometry1 (&)[1], Basis, PowerCurve1 (&)[1]);
template Status CurvePowerCoefficients<2>(const CurveGeometry1 (&)[2], Basis, PowerCurve1 (&)[2]);
template Status CurvePowerCoefficients<3>(const CurveGeometry1 (&)[3], Basis, PowerCurve1 (&)[3]);
template class IsolineWalker<1>;
template class IsolineWalker<2>;
template class IsolineWalker<3>;

}  // namespace fdsurf
