// SPDX-License-Identifier: MIT
// Set-up of the forward-difference tables and the precision planner.
//
// Everything here is exact integer arithmetic; docs/precision.md derives each
// bound that is checked below. Notation: a direction (s or t) has n steps,
// δ = 1/n; the integer basis matrix is d·M; G holds geometry in units of
// 2^-g quanta (g = kGeometryFracBits).
#include "fdsurf/forward_difference.h"

#include "fdsurf/fixed.h"
#include "fdsurf/internal/wide_int.h"

namespace fdsurf {
namespace {

// Set-up products stay below 2^124 (docs/precision.md, "Set-up arithmetic")
// and fit Narrow; scaling by 2^F before the rounding division needs Wide.
using Narrow = internal::WideInt<4>;
using Wide = internal::WideInt<8>;

// One parametric direction of the table. A curve has one active direction;
// its second direction is inactive: size 1, identity everywhere.
struct Axis {
  uint32_t steps;   // n
  int size;         // 4 when active, 1 when inactive
  int denominator;  // d, or 1 when inactive
  // E' = n³·E(1/n) = [[0,0,0,n³],[1,n,n²,0],[6,2n,0,0],[6,0,0,0]].
  int64_t e[4][4];
  // The integer basis d·M.
  int64_t basis[4][4];
  // weight[a][k] = ff(p,k)·(n+k)^(p-k)·n^(3-p), p = 3-a: n³·δ^k times the
  // largest |d^k/du^k u^p| on [0, 1+kδ] (see "Range" in docs/precision.md).
  uint64_t weight[4][4];
};

uint64_t Power(uint64_t base, int exponent) {
  uint64_t result = 1;
  for (int i = 0; i < exponent; ++i) result *= base;
  return result;
}

uint64_t FallingFactorial(int p, int k) {
  uint64_t result = 1;
  for (int i = 0; i < k; ++i) result *= static_cast<uint64_t>(p - i);
  return result;
}

void MakeActiveAxis(uint32_t n, const BasisMatrix& m, Axis* axis) {
  axis->steps = n;
  axis->size = 4;
  axis->denominator = m.denominator;
  const int64_t n1 = n;
  const int64_t n2 = n1 * n1;
  const int64_t n3 = n2 * n1;
  const int64_t e[4][4] = {{0, 0, 0, n3}, {1, n1, n2, 0}, {6, 2 * n1, 0, 0}, {6, 0, 0, 0}};
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      axis->e[r][c] = e[r][c];
      axis->basis[r][c] = m.matrix[r][c];
    }
  }
  for (int a = 0; a < 4; ++a) {
    const int p = 3 - a;
    for (int k = 0; k < 4; ++k) {
      axis->weight[a][k] =
          k > p ? 0 : FallingFactorial(p, k) * Power(n + k, p - k) * Power(n, 3 - p);
    }
  }
}

void MakeInactiveAxis(Axis* axis) {
  axis->steps = 0;
  axis->size = 1;
  axis->denominator = 1;
  axis->e[0][0] = 1;
  axis->basis[0][0] = 1;
  axis->weight[0][0] = 1;
}

// Σ_{k≤3} C(n,k): how many times the rounding of one table entry can be
// counted into one position after n steps.
uint64_t PropagationCount(uint64_t n) {
  return 1 + n + n * (n - 1) / 2 + n * (n - 1) * (n - 2) / 6;
}

int BitLength(uint64_t v) {
  int bits = 0;
  while (v != 0) {
    ++bits;
    v >>= 1;
  }
  return bits;
}

// The exact differences are the scaled table divided by
// D = 2^g·d_s·d_t·n_s³·n_t³. Dividing by D is a shift by g and a few
// single-limb divisions by the factors below, each under 2^32.
struct Denominator {
  uint32_t divisor[4];  // d_s·d_t, then n³ per patch axis (n and n² for a curve)
  int count;
  Wide value;
  Wide half;  // D/2; D is even because it carries 2^g
};

Denominator MakeDenominator(const Axis& s, const Axis& t) {
  Denominator d;
  d.count = 0;
  const uint32_t basis = static_cast<uint32_t>(s.denominator * t.denominator);
  if (basis > 1) d.divisor[d.count++] = basis;
  if (t.size == 4) {
    // Patch axes have n ≤ kMaxPatchSteps = 1024, so n³ < 2^32.
    d.divisor[d.count++] = s.steps * s.steps * s.steps;
    d.divisor[d.count++] = t.steps * t.steps * t.steps;
  } else {
    // A curve's n may be up to 65535: n² < 2^32.
    d.divisor[d.count++] = s.steps;
    d.divisor[d.count++] = s.steps * s.steps;
  }
  d.value = Wide::PowerOfTwo(kGeometryFracBits);
  for (int i = 0; i < d.count; ++i) d.value = d.value.MulInt64(d.divisor[i]);
  d.half = Wide::PowerOfTwo(kGeometryFracBits - 1);
  for (int i = 0; i < d.count; ++i) d.half = d.half.MulInt64(d.divisor[i]);
  return d;
}

// The scaled power coefficients d_s·d_t·2^g·C = (d_sM)·G·(d_tM)ᵀ. With
// |G| < 2^47 and basis rows of absolute sum ≤ 12 they stay below 2^55.
void PowerCoefficients(const int64_t (&g)[4][4], const Axis& s, const Axis& t, int64_t (&c)[4][4]) {
  int64_t g_mt[4][4];  // G·(d_tM)ᵀ
  for (int i = 0; i < s.size; ++i) {
    for (int l = 0; l < t.size; ++l) {
      int64_t sum = 0;
      for (int j = 0; j < t.size; ++j) sum += g[i][j] * t.basis[l][j];
      g_mt[i][l] = sum;
    }
  }
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      int64_t sum = 0;
      for (int i = 0; i < s.size; ++i) sum += s.basis[k][i] * g_mt[i][l];
      c[k][l] = sum;
    }
  }
}

// The scaled table D·DD = E'_s·(d_sd_t2^g·C)·E'_tᵀ. E' is sparse; skipping its
// zeros is worth it here, as this runs for every patch.
void ScaledTable(const int64_t (&c)[4][4], const Axis& s, const Axis& t, Narrow (&dd)[4][4]) {
  Narrow c_et[4][4];  // C·E'_tᵀ
  for (int i = 0; i < s.size; ++i) {
    for (int l = 0; l < t.size; ++l) {
      Narrow sum;
      for (int j = 0; j < t.size; ++j) {
        if (t.e[l][j] != 0) sum += Narrow::FromInt64(c[i][j]).MulInt64(t.e[l][j]);
      }
      c_et[i][l] = sum;
    }
  }
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      Narrow sum;
      for (int i = 0; i < s.size; ++i) {
        if (s.e[k][i] != 0) sum += c_et[i][l].MulInt64(s.e[k][i]);
      }
      dd[k][l] = sum;
    }
  }
}

// round(x·2^F / D), halves away from zero: floor((|x|·2^F + D/2) / D) by
// successive exact floor divisions, which compose for non-negative numbers.
// Sets *exact when D divides x·2^F.
Wide RoundedQuotient(const Narrow& x, int frac_bits, const Denominator& d, bool* exact) {
  Wide y = x.Abs().Resized<Wide::kBits / 32>().ShiftedLeft(frac_bits) + d.half;
  // Dividing by 2^g, e1, e2, ... in turn leaves remainders r0, r1, r2, ...
  // and y = q·D + r with r = r0 + 2^g·(r1 + e1·(r2 + ...)).
  const uint32_t low_bits = y.ShiftRightInPlace(kGeometryFracBits);
  uint32_t remainders[4];
  for (int i = 0; i < d.count; ++i) remainders[i] = y.DivideInPlace(d.divisor[i]);
  Wide remainder;
  for (int i = d.count - 1; i >= 0; --i) {
    remainder = remainder.MulInt64(d.divisor[i]) + Wide::FromUint64(remainders[i]);
  }
  remainder = remainder.ShiftedLeft(kGeometryFracBits) + Wide::FromUint64(low_bits);
  *exact = remainder == d.half;
  return x.IsNegative() ? -y : y;
}

// The table of one coordinate and the bounds on its differences.
struct Plane {
  Narrow dd[4][4];   // scaled exact table
  Wide bound[4][4];  // scaled bound of |Δs^k Δt^l x| over the stepped box
};

Status BuildPlane(const int64_t (&g)[4][4], const Axis& s, const Axis& t, Plane* plane) {
  for (int i = 0; i < s.size; ++i) {
    for (int j = 0; j < t.size; ++j) {
      if (!GeometryInRange(g[i][j])) return Status::kGeometryOutOfRange;
    }
  }
  int64_t c[4][4];
  PowerCoefficients(g, s, t, c);
  ScaledTable(c, s, t, plane->dd);
  // bound[k][l] = Σ_a Σ_b |c_ab|·w_s[a][k]·w_t[b][l], summed over b first.
  Narrow partial[4][4];  // [a][l]
  for (int a = 0; a < s.size; ++a) {
    for (int l = 0; l < t.size; ++l) {
      Narrow sum;
      for (int b = 0; b < t.size; ++b) {
        const int64_t magnitude = c[a][b] < 0 ? -c[a][b] : c[a][b];
        sum += Narrow::FromInt64(magnitude).MulInt64(static_cast<int64_t>(t.weight[b][l]));
      }
      partial[a][l] = sum;
    }
  }
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      Narrow sum;
      for (int a = 0; a < s.size; ++a) {
        sum += partial[a][l].MulInt64(static_cast<int64_t>(s.weight[a][k]));
      }
      plane->bound[k][l] = sum.Resized<Wide::kBits / 32>();
    }
  }
  return Status::kOk;
}

// A bound on a difference, plus `margin` quanta, stays below 2^headroom
// quanta: bound/D + margin < 2^headroom, checked exactly as
// bound + margin·D < D·2^headroom. The one form of every range check below;
// built once per check, then applied to each bound.
class QuantaLimit {
 public:
  QuantaLimit(const Denominator& d, int headroom, int64_t margin)
      : limit_(d.value.ShiftedLeft(headroom)), margin_d_(d.value) {
    // margin is 1 or 2: additions, not a wide product
    for (int64_t i = 1; i < margin; ++i) margin_d_ += d.value;
  }
  FDSURF_NODISCARD bool Admits(const Wide& bound) const { return bound + margin_d_ < limit_; }

 private:
  Wide limit_;
  Wide margin_d_;
};

// Every difference of the table, plus `margin` quanta, stays below
// 2^headroom quanta.
bool TableBelow(const Plane& plane, const Axis& s, const Axis& t, const Denominator& d,
                int headroom, int64_t margin) {
  const QuantaLimit below(d, headroom, margin);
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      if (!below.Admits(plane.bound[k][l])) return false;
    }
  }
  return true;
}

// Every difference, plus one quantum for the accumulated rounding, must stay
// below 2^(W-1) in units of 2^-F quanta: bound/D + 1 < 2^(W-1-F).
bool FitsWidth(const Plane& plane, const Axis& s, const Axis& t, const Denominator& d, int acc_bits,
               int frac_bits) {
  const int headroom = acc_bits - 1 - frac_bits;
  return headroom >= 1 && TableBelow(plane, s, t, d, headroom, 1);
}

// A line of the per-line stepper (docs/precision.md, "Per-line rounding")
// holds the row-0 entries (s-lines) or the column-0 entries (t-lines) in
// int64_t with `frac_bits` fractional bits, the position with the rounding
// half added: each of those bounds, plus 2 quanta, must stay below
// 2^(63-F).
bool FitsLine(const Plane& plane, const Axis& s, const Axis& t, const Denominator& d, bool s_lines,
              int frac_bits) {
  const int headroom = 63 - frac_bits;
  if (headroom < 1) return false;
  const QuantaLimit below(d, headroom, 2);
  const int entries = s_lines ? t.size : s.size;
  for (int e = 0; e < entries; ++e) {
    if (!below.Admits(s_lines ? plane.bound[0][e] : plane.bound[e][0])) return false;
  }
  return true;
}

template <int kDims>
bool AllLinesFit(const Plane (&planes)[kDims], const Axis& s, const Axis& t, const Denominator& d,
                 bool s_lines, int frac_bits) {
  for (int c = 0; c < kDims; ++c) {
    if (!FitsLine(planes[c], s, t, d, s_lines, frac_bits)) return false;
  }
  return true;
}

// The line format of one family (0: none): planned for a table in the
// 128-bit format or a 64-bit one with more than 32 fractional bits, if every
// coordinate's line fits 64 bits with fewer fractional bits than the
// table's. Where the range allows, the line gets exactly 32 bits, so that a
// point is its position's high word (the word-aligned stepping of
// docs/precision.md): a line whose derivation asks for 32 bits or fewer
// keeps them all along (more bits only shrink its error); a longer one
// (more than 586 steps) is cut into segments that need
// 32 bits or fewer (LineSegmentSteps), each rounded from the line's exact
// wide state at its start, so that its error term is a segment's. Else the
// line gets the derivation's bits and is rounded once.
struct LineFormat {
  uint8_t frac_bits;       // 0: the family has no line format
  uint16_t segment_steps;  // steps between re-roundings
};

template <int kDims>
LineFormat PlanLineFormat(const Plane (&planes)[kDims], const Axis& s, const Axis& t,
                          const Denominator& d, bool s_lines, int table_frac_bits,
                          const PrepareOptions& options) {
  const uint16_t steps = static_cast<uint16_t>(s_lines ? t.steps : s.steps);
  int frac_bits = RequiredLineFracBits(steps);
  const bool weakened = options.test_only_line_frac_bits_removed != 0;
  frac_bits -= options.test_only_line_frac_bits_removed;
  if (frac_bits < 1 || frac_bits >= table_frac_bits) return {0, 0};
  if (!weakened && 32 < table_frac_bits && AllLinesFit(planes, s, t, d, s_lines, 32)) {
    return {32, LineSegmentSteps(steps)};
  }
  if (!AllLinesFit(planes, s, t, d, s_lines, frac_bits)) return {0, 0};
  return {static_cast<uint8_t>(frac_bits), steps};
}

// A word-aligned 64-bit stepper (docs/precision.md, "Word-aligned stepping")
// holds every entry with 32 fractional bits and the position with the
// rounding half added: each bound plus 2 quanta must stay below 2^31 quanta,
// so that (B + 2)·2^32 < 2^63.
bool FitsWordAligned(const Plane& plane, const Axis& s, const Axis& t, const Denominator& d) {
  return TableBelow(plane, s, t, d, 31, 2);
}

// Positions themselves (plus a quantum) must fit the int32_t output.
bool FitsOutput(const Plane& plane, const Denominator& d) {
  return QuantaLimit(d, 31, 1).Admits(plane.bound[0][0]);
}

template <int kDims>
Status Prepare(const int64_t (&g)[kDims][4][4], Basis basis, const Axis& s, const Axis& t,
               const PrepareOptions& options, DiffFormat* format, bool* exact,
               Int128 (&table)[kDims][4][4], LineFormat (*line_formats)[2] = nullptr) {
  static_assert(kDims >= 1 && kDims <= 3, "1, 2 or 3 coordinates");
  if (GetBasisMatrix(basis) == nullptr) return Status::kInvalidArgument;
  const Denominator denominator = MakeDenominator(s, t);
  Plane planes[kDims];
  for (int c = 0; c < kDims; ++c) {
    const Status status = BuildPlane(g[c], s, t, &planes[c]);
    if (status != Status::kOk) return status;
    if (!FitsOutput(planes[c], denominator)) return Status::kGeometryOutOfRange;
  }
  int frac_bits = RequiredFracBits(s.steps, t.size == 4 ? t.steps : 0);
  frac_bits -= options.test_only_frac_bits_removed;
  if (frac_bits < 1) frac_bits = 1;

  int acc_bits = 0;
  const int widths[2] = {64, 128};
  for (int width : widths) {
    if (width > options.max_acc_bits) break;
    bool fits = true;
    for (int c = 0; c < kDims && fits; ++c) {
      fits = FitsWidth(planes[c], s, t, denominator, width, frac_bits);
    }
    if (fits) {
      acc_bits = width;
      break;
    }
  }
  if (acc_bits == 0) return Status::kPrecisionUnreachable;

  bool all_exact = true;
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k) {
      for (int l = 0; l < 4; ++l) {
        if (k >= s.size || l >= t.size) {
          table[c][k][l] = Int128{0, 0};
          continue;
        }
        bool entry_exact = false;
        const Wide q = RoundedQuotient(planes[c].dd[k][l], frac_bits, denominator, &entry_exact);
        // Implied by FitsWidth; kept so that a planner bug refuses instead of
        // wrapping around.
        if (q.MagnitudeBits() > acc_bits - 1) return Status::kPrecisionUnreachable;
        table[c][k][l] = internal::ToInt128(q);
        all_exact = all_exact && entry_exact;
      }
    }
  }
  format->acc_bits = static_cast<uint8_t>(acc_bits);
  format->frac_bits = static_cast<uint8_t>(frac_bits);
  bool word_aligned = acc_bits == 64 && frac_bits <= 32;
  for (int c = 0; c < kDims && word_aligned; ++c) {
    word_aligned = FitsWordAligned(planes[c], s, t, denominator);
  }
  format->word_aligned = word_aligned ? 1 : 0;
  *exact = all_exact;
  if (line_formats != nullptr) {
    // Lines for every patch table whose own points are not already the
    // high word: the 128-bit ones, and the 64-bit ones with more than 32
    // fractional bits (grids from 26×26 on), whose lines get 32.
    const bool lines = t.size == 4 && (acc_bits == 128 || frac_bits > 32);
    for (int family = 0; family < 2; ++family) {
      (*line_formats)[family] =
          lines ? PlanLineFormat(planes, s, t, denominator, family == 0, frac_bits, options)
                : LineFormat{0, 0};
    }
  }
  return Status::kOk;
}

}  // namespace

int RequiredFracBits(uint32_t steps_s, uint32_t steps_t) {
  return BitLength(PropagationCount(steps_s) * PropagationCount(steps_t)) + kGuardBits;
}

int RequiredLineFracBits(uint32_t steps) {
  return BitLength(PropagationCount(steps)) + kLineGuardBits;
}

uint16_t LineSegmentSteps(uint16_t steps) {
  for (uint32_t segments = 1;; ++segments) {
    const uint32_t length = (steps + segments - 1) / segments;
    if (RequiredLineFracBits(length) <= 32) return static_cast<uint16_t>(length);
  }
}

template <int kDims>
Status PrepareCurve(const CurveGeometry1 (&geometry)[kDims], Basis basis, uint16_t steps,
                    const PrepareOptions& options, PreparedCurve<kDims>* out) {
  const BasisMatrix* m = GetBasisMatrix(basis);
  if (m == nullptr) return Status::kInvalidArgument;
  if (steps < 1) return Status::kGridOutOfRange;
  Axis s;
  Axis t;
  MakeActiveAxis(steps, *m, &s);
  MakeInactiveAxis(&t);
  int64_t g[kDims][4][4] = {};
  for (int c = 0; c < kDims; ++c) {
    for (int i = 0; i < 4; ++i) g[c][i][0] = geometry[c].g[i].Raw();
  }
  Int128 table[kDims][4][4];
  PreparedCurve<kDims> result;
  const Status status = Prepare(g, basis, s, t, options, &result.format, &result.exact, table);
  if (status != Status::kOk) return status;
  result.steps = steps;
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k) result.d[c][k] = table[c][k][0];
  }
  *out = result;
  return Status::kOk;
}

template <int kDims>
Status PreparePatch(const PatchGeometry1 (&geometry)[kDims], Basis basis, uint16_t steps_s,
                    uint16_t steps_t, const PrepareOptions& options, PreparedPatch<kDims>* out) {
  const BasisMatrix* m = GetBasisMatrix(basis);
  if (m == nullptr) return Status::kInvalidArgument;
  if (steps_s < 1 || steps_t < 1 || steps_s > kMaxPatchSteps || steps_t > kMaxPatchSteps) {
    return Status::kGridOutOfRange;
  }
  Axis s;
  Axis t;
  MakeActiveAxis(steps_s, *m, &s);
  MakeActiveAxis(steps_t, *m, &t);
  int64_t g[kDims][4][4];
  for (int c = 0; c < kDims; ++c) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) g[c][i][j] = geometry[c].g[i][j].Raw();
    }
  }
  PreparedPatch<kDims> result;
  LineFormat line_formats[2];
  const Status status =
      Prepare(g, basis, s, t, options, &result.format, &result.exact, result.dd, &line_formats);
  if (status != Status::kOk) return status;
  result.s_line_frac_bits = line_formats[0].frac_bits;
  result.t_line_frac_bits = line_formats[1].frac_bits;
  result.s_line_segment_steps = line_formats[0].segment_steps;
  result.t_line_segment_steps = line_formats[1].segment_steps;
  result.steps_s = steps_s;
  result.steps_t = steps_t;
  *out = result;
  return Status::kOk;
}

template Status PrepareCurve<1>(const CurveGeometry1 (&)[1], Basis, uint16_t, const PrepareOptions&,
                                PreparedCurve<1>*);
template Status PrepareCurve<2>(const CurveGeometry1 (&)[2], Basis, uint16_t, const PrepareOptions&,
                                PreparedCurve<2>*);
template Status PrepareCurve<3>(const CurveGeometry1 (&)[3], Basis, uint16_t, const PrepareOptions&,
                                PreparedCurve<3>*);
template Status PreparePatch<1>(const PatchGeometry1 (&)[1], Basis, uint16_t, uint16_t,
                                const PrepareOptions&, PreparedPatch<1>*);
template Status PreparePatch<2>(const PatchGeometry1 (&)[2], Basis, uint16_t, uint16_t,
                                const PrepareOptions&, PreparedPatch<2>*);
template Status PreparePatch<3>(const PatchGeometry1 (&)[3], Basis, uint16_t, uint16_t,
                                const PrepareOptions&, PreparedPatch<3>*);

}  // namespace fdsurf
