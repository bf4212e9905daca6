// Set-up of the forward-difference tables and the precision planner.
//
// Everything here is exact integer arithmetic; docs/precision.md derives each
// bound that is checked below. Notation: a direction (s or t) has n steps,
// δ = 1/n; the integer basis matrix is d·M; G holds geometry in units of
// 2^-g quanta (g = kGeometryFracBits).
#include "fdsurf/forward_difference.h"

#include "fdsurf/internal/wide_int.h"

namespace fdsurf {
namespace {

using Wide = internal::WideInt<8>;

// One parametric direction of the table. A curve has one active direction;
// its second direction is inactive: size 1, identity everywhere.
struct Axis {
  uint32_t steps;  // n
  int size;        // 4 when active, 1 when inactive
  int denominator;  // d, or 1 when inactive
  // A = n³·E(1/n)·(d·M): maps geometry to scaled differences.
  int64_t a[4][4];
  // The integer basis d·M (used for the power coefficients C).
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
  // n³·E(1/n) with E(δ) = [[0,0,0,1],[δ³,δ²,δ,0],[6δ³,2δ²,0,0],[6δ³,0,0,0]].
  const int64_t e[4][4] = {{0, 0, 0, n3}, {1, n1, n2, 0}, {6, 2 * n1, 0, 0}, {6, 0, 0, 0}};
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      axis->basis[r][c] = m.matrix[r][c];
      int64_t sum = 0;
      for (int i = 0; i < 4; ++i) sum += e[r][i] * m.matrix[i][c];
      axis->a[r][c] = sum;
    }
  }
  for (int a = 0; a < 4; ++a) {
    const int p = 3 - a;
    for (int k = 0; k < 4; ++k) {
      axis->weight[a][k] = k > p ? 0
                                 : FallingFactorial(p, k) * Power(n + k, p - k) *
                                       Power(n, 3 - p);
    }
  }
}

void MakeInactiveAxis(Axis* axis) {
  axis->steps = 0;
  axis->size = 1;
  axis->denominator = 1;
  axis->a[0][0] = 1;
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

// D = d_s·d_t·n_s³·n_t³·2^g: exact difference = table entry / D.
Wide Denominator(const Axis& s, const Axis& t) {
  Wide d = Wide::FromInt64(1);
  const Axis* axes[2] = {&s, &t};
  for (const Axis* axis : axes) {
    if (axis->size == 4) {
      const Wide n = Wide::FromInt64(axis->steps);
      d = d * n * n * n * Wide::FromInt64(axis->denominator);
    }
  }
  return d.ShiftedLeft(kGeometryFracBits);
}

// The scaled table n_s³n_t³·d_s·d_t·2^g·DD = A_s·G·A_tᵀ for one coordinate,
// and the scaled power coefficients d_s·d_t·2^g·C = (d_sM)·G·(d_tM)ᵀ.
void ScaledTables(const int64_t (&g)[4][4], const Axis& s, const Axis& t, Wide (&dd)[4][4],
                  Wide (&c)[4][4]) {
  Wide g_at[4][4];  // G·A_tᵀ
  Wide g_mt[4][4];  // G·(d_tM)ᵀ
  for (int i = 0; i < s.size; ++i) {
    for (int l = 0; l < t.size; ++l) {
      Wide sum_a;
      Wide sum_m;
      for (int j = 0; j < t.size; ++j) {
        const Wide gij = Wide::FromInt64(g[i][j]);
        sum_a += gij * Wide::FromInt64(t.a[l][j]);
        sum_m += gij * Wide::FromInt64(t.basis[l][j]);
      }
      g_at[i][l] = sum_a;
      g_mt[i][l] = sum_m;
    }
  }
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      Wide sum_a;
      Wide sum_m;
      for (int i = 0; i < s.size; ++i) {
        sum_a += Wide::FromInt64(s.a[k][i]) * g_at[i][l];
        sum_m += Wide::FromInt64(s.basis[k][i]) * g_mt[i][l];
      }
      dd[k][l] = sum_a;
      c[k][l] = sum_m;
    }
  }
}

// round(x·2^F / D) with halves away from zero, by successive exact floor
// divisions of |x|·2^F + D/2 (D is even: it carries 2^g).
Wide RoundedQuotient(const Wide& x, int frac_bits, const Axis& s, const Axis& t) {
  const Wide denominator = Denominator(s, t);
  Wide y = x.Abs().ShiftedLeft(frac_bits);
  Wide half = denominator;
  half.DivideInPlace(2);
  y += half;
  y.DivideInPlace(uint32_t{1} << kGeometryFracBits);
  const Axis* axes[2] = {&s, &t};
  for (const Axis* axis : axes) {
    if (axis->size != 4) continue;
    y.DivideInPlace(static_cast<uint32_t>(axis->denominator));
    for (int i = 0; i < 3; ++i) y.DivideInPlace(axis->steps);
  }
  return x.IsNegative() ? -y : y;
}

Int128 ToInt128(const Wide& w) {
  Int128 v;
  v.lo = static_cast<uint64_t>(w.limb(0)) | (static_cast<uint64_t>(w.limb(1)) << 32);
  v.hi = static_cast<uint64_t>(w.limb(2)) | (static_cast<uint64_t>(w.limb(3)) << 32);
  return v;
}

// The table of one coordinate, checked and rounded. `widths_ok` is narrowed
// to the accumulator widths whose range holds every difference of it.
struct Plane {
  Wide dd[4][4];     // scaled exact table
  Wide bound[4][4];  // scaled bound of |Δs^k Δt^l x| over the stepped box
};

Status BuildPlane(const int64_t (&g)[4][4], const Axis& s, const Axis& t, Plane* plane) {
  for (int i = 0; i < s.size; ++i) {
    for (int j = 0; j < t.size; ++j) {
      if (g[i][j] >= kGeometryLimitRaw || g[i][j] <= -kGeometryLimitRaw) {
        return Status::kGeometryOutOfRange;
      }
    }
  }
  Wide c[4][4];
  ScaledTables(g, s, t, plane->dd, c);
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      Wide sum;
      for (int a = 0; a < s.size; ++a) {
        for (int b = 0; b < t.size; ++b) {
          sum += c[a][b].Abs() * Wide::FromUint64(s.weight[a][k]) *
                 Wide::FromUint64(t.weight[b][l]);
        }
      }
      plane->bound[k][l] = sum;
    }
  }
  return Status::kOk;
}

// Every difference, plus one quantum for the accumulated rounding, must stay
// below 2^(W-1) in units of 2^-F quanta: bound/D + 1 < 2^(W-1-F).
bool FitsWidth(const Plane& plane, const Axis& s, const Axis& t, int acc_bits, int frac_bits) {
  const int headroom = acc_bits - 1 - frac_bits;
  if (headroom < 1) return false;
  const Wide denominator = Denominator(s, t);
  const Wide limit = denominator.ShiftedLeft(headroom);
  for (int k = 0; k < s.size; ++k) {
    for (int l = 0; l < t.size; ++l) {
      if (!(plane.bound[k][l] + denominator < limit)) return false;
    }
  }
  return true;
}

// Positions themselves (plus a quantum) must fit the int32_t output.
bool FitsOutput(const Plane& plane, const Axis& s, const Axis& t) {
  const Wide denominator = Denominator(s, t);
  return plane.bound[0][0] + denominator < denominator.ShiftedLeft(31);
}

template <int kDims>
Status Prepare(const int64_t (&g)[kDims][4][4], Basis basis, const Axis& s, const Axis& t,
               const PrepareOptions& options, DiffFormat* format, bool* exact,
               Int128 (&table)[kDims][4][4]) {
  static_assert(kDims >= 1 && kDims <= 3, "1, 2 or 3 coordinates");
  if (GetBasisMatrix(basis) == nullptr) return Status::kInvalidArgument;
  Plane planes[kDims];
  for (int c = 0; c < kDims; ++c) {
    const Status status = BuildPlane(g[c], s, t, &planes[c]);
    if (status != Status::kOk) return status;
    if (!FitsOutput(planes[c], s, t)) return Status::kGeometryOutOfRange;
  }
  int frac_bits = RequiredFracBits(s.steps, t.size == 4 ? t.steps : 0);
  frac_bits -= options.test_only_frac_bits_removed;
  if (frac_bits < 1) frac_bits = 1;

  int acc_bits = 0;
  const int widths[2] = {64, 128};
  for (int width : widths) {
    if (width > options.max_acc_bits) break;
    bool fits = true;
    for (int c = 0; c < kDims && fits; ++c) fits = FitsWidth(planes[c], s, t, width, frac_bits);
    if (fits) {
      acc_bits = width;
      break;
    }
  }
  if (acc_bits == 0) return Status::kPrecisionUnreachable;

  const Wide denominator = Denominator(s, t);
  bool all_exact = true;
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k) {
      for (int l = 0; l < 4; ++l) {
        if (k >= s.size || l >= t.size) {
          table[c][k][l] = Int128{0, 0};
          continue;
        }
        const Wide q = RoundedQuotient(planes[c].dd[k][l], frac_bits, s, t);
        if (q * denominator != planes[c].dd[k][l].ShiftedLeft(frac_bits)) all_exact = false;
        table[c][k][l] = ToInt128(q);
      }
    }
  }
  format->acc_bits = static_cast<uint8_t>(acc_bits);
  format->frac_bits = static_cast<uint8_t>(frac_bits);
  *exact = all_exact;
  return Status::kOk;
}

}  // namespace

int RequiredFracBits(uint32_t steps_s, uint32_t steps_t) {
  return BitLength(PropagationCount(steps_s) * PropagationCount(steps_t)) + kGuardBits;
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
  const Status status = Prepare(g, basis, s, t, options, &result.format, &result.exact, result.dd);
  if (status != Status::kOk) return status;
  result.steps_s = steps_s;
  result.steps_t = steps_t;
  *out = result;
  return Status::kOk;
}

template Status PrepareCurve<1>(const CurveGeometry1 (&)[1], Basis, uint16_t,
                                const PrepareOptions&, PreparedCurve<1>*);
template Status PrepareCurve<2>(const CurveGeometry1 (&)[2], Basis, uint16_t,
                                const PrepareOptions&, PreparedCurve<2>*);
template Status PrepareCurve<3>(const CurveGeometry1 (&)[3], Basis, uint16_t,
                                const PrepareOptions&, PreparedCurve<3>*);
template Status PreparePatch<1>(const PatchGeometry1 (&)[1], Basis, uint16_t, uint16_t,
                                const PrepareOptions&, PreparedPatch<1>*);
template Status PreparePatch<2>(const PatchGeometry1 (&)[2], Basis, uint16_t, uint16_t,
                                const PrepareOptions&, PreparedPatch<2>*);
template Status PreparePatch<3>(const PatchGeometry1 (&)[3], Basis, uint16_t, uint16_t,
                                const PrepareOptions&, PreparedPatch<3>*);

}  // namespace fdsurf
