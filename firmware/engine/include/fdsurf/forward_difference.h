// SPDX-License-Identifier: MIT
// Forward-difference evaluation of cubic curves and bicubic patches.
//
// Set-up (Prepare*) forms the difference matrix DD = E(δ)·C·E(ε)ᵀ exactly in
// integers and rounds it once to the format the precision planner chose;
// stepping (the Stepper classes) then costs only additions:
// row1 += row2, row2 += row3, row3 += row4.
//
// The promise, proven in docs/precision.md and checked by tests/: every
// position a stepper emits is within 0.51 quanta of the exact curve or patch
// defined by the geometry the caller passed (geometry already in quanta with
// kGeometryFracBits guard bits, and an extra ≤ 0.002 quanta for the caller's
// rounding into that format). A request the engine cannot serve within that
// bound is refused by Prepare*, never stepped wrongly.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/basis.h"
#include "fdsurf/fixed.h"
#include "fdsurf/int128.h"
#include "fdsurf/status.h"

namespace fdsurf {

/// Largest step count per direction of a patch grid.
constexpr uint16_t kMaxPatchSteps = 1024;
/// Largest step count of a curve.
constexpr uint16_t kMaxCurveSteps = 65535;
/// Fractional bits kept beyond those that make the accumulated rounding of
/// the difference table exactly ≤ 1 quantum; 9 makes it ≤ 2^-10 quanta.
constexpr int kGuardBits = 9;

/// Guard bits of a line's own format under per-line rounding
/// (LinePatchStepper): re-rounding a line's 4 entries then adds at most
/// 2^-(kLineGuardBits+1) quanta to its points (docs/precision.md, "Per-line
/// rounding"; 2^-8 ≈ 0.0039, inside the 0.51-quantum budget).
constexpr int kLineGuardBits = 7;

/// The runtime format of the differences: accumulator width and the number of
/// fractional bits (values are integers in units of 2^-frac_bits quanta).
struct DiffFormat {
  uint8_t acc_bits;   // 64 or 128
  uint8_t frac_bits;  // F
  /// 1 when a 64-bit stepper may hold the table with 32 fractional bits
  /// (moved left by 32 − F) and the rounding half added to the position, so
  /// that a point is the position's high word: no shift and no add per point
  /// (docs/precision.md, "Word-aligned stepping"). Planned for 64-bit tables
  /// with F ≤ 32 whose differences stay below 2^31 − 2 quanta; 0 otherwise,
  /// and then the stepper rounds with RoundToQuanta.
  uint8_t word_aligned;
};

/// What callers may limit or (in tests only) weaken.
struct PrepareOptions {
  /// 64 refuses work that needs the wider accumulator (e.g. to keep an AVR
  /// build on 64-bit adds); 128 allows both.
  uint8_t max_acc_bits = 128;
  /// Removes fractional bits from the planned format. Exists so tests can show
  /// that the bound fails without them; production code leaves it at 0.
  uint8_t test_only_frac_bits_removed = 0;
  /// The same for the per-line formats (PreparedPatch::s_line_frac_bits).
  uint8_t test_only_line_frac_bits_removed = 0;
};

/// One coordinate of a curve's geometry: the 4 basis coefficients
/// (Hermite: P0, P1, T0, T1; Bézier: 4 control points; power: a, b, c, d).
struct CurveGeometry1 {
  GeometryFixed g[4];
};

/// One coordinate of a patch's geometry matrix G (first index along s).
struct PatchGeometry1 {
  GeometryFixed g[4][4];
};

/// A curve ready to step: its difference vectors in the planned format.
template <int kDims>
struct PreparedCurve {
  DiffFormat format;
  uint16_t steps;
  /// True when every difference was represented without rounding, so the
  /// stepping adds no error at all (power-of-two steps with enough bits).
  bool exact;
  Int128 d[kDims][4];
};

/// A patch ready to step: per coordinate the 4×4 difference matrix DD; row k
/// holds the k-th s-difference, column l the l-th t-difference.
template <int kDims>
struct PreparedPatch {
  DiffFormat format;
  uint16_t steps_s;
  uint16_t steps_t;
  bool exact;
  /// Per-line rounding (docs/precision.md, "Per-line rounding"), planned
  /// when `format` needs the 128-bit accumulator or has more than 32
  /// fractional bits: the fractional bits of the 64-bit line stepper of
  /// LinePatchStepper along s-lines (stepping t) and along t-lines (stepping
  /// s); 0 when such a line does not fit 64 bits, or for a table with 32
  /// fractional bits or fewer (its own stepper is as fast).
  uint8_t s_line_frac_bits;
  uint8_t t_line_frac_bits;
  /// Under per-line rounding, the most steps a line is stepped in 64 bits
  /// before it is re-rounded from its exact wide state (the line's own steps
  /// when it is rounded once): long lines are cut into segments short
  /// enough for 32 fractional bits, so that a point is the high word
  /// (docs/precision.md, "Per-line rounding"). 0 where the family has no
  /// line format.
  uint16_t s_line_segment_steps;
  uint16_t t_line_segment_steps;
  Int128 dd[kDims][4][4];
};

/// The fractional bits that make the stepping error ≤ 2^-(kGuardBits+1)
/// quanta for `steps_s` × `steps_t` steps (steps_t = 0 for a curve).
int RequiredFracBits(uint32_t steps_s, uint32_t steps_t);

/// The fractional bits of a line of `steps` steps under per-line rounding:
/// bitlength(S(steps)) + kLineGuardBits.
int RequiredLineFracBits(uint32_t steps);

/// The segment length of a line of `steps` steps under per-line rounding
/// with 32-bit lines: `steps` when RequiredLineFracBits(steps) ≤ 32, else
/// ceil(steps / k) for the smallest number of segments k whose length
/// needs 32 bits or fewer (up to 586 steps: one; 1024 steps: 2 of 512).
uint16_t LineSegmentSteps(uint16_t steps);

/// Plans and sets up one curve coordinate by coordinate.
/// Errors: kInvalidArgument (unknown basis, kDims out of 1..3),
/// kGridOutOfRange (steps outside 1..kMaxCurveSteps), kGeometryOutOfRange,
/// kPrecisionUnreachable. On error *out is unchanged.
template <int kDims>
Status PrepareCurve(const CurveGeometry1 (&geometry)[kDims], Basis basis, uint16_t steps,
                    const PrepareOptions& options, PreparedCurve<kDims>* out);

/// Plans and sets up one patch: a grid of steps_s × steps_t steps
/// (steps_s + 1 by steps_t + 1 points). Errors as PrepareCurve, with
/// kGridOutOfRange for a step count outside 1..kMaxPatchSteps.
template <int kDims>
Status PreparePatch(const PatchGeometry1 (&geometry)[kDims], Basis basis, uint16_t steps_s,
                    uint16_t steps_t, const PrepareOptions& options, PreparedPatch<kDims>* out);

namespace internal {

inline void Load(const Int128& from, int64_t* to) {
  // The planner proved the value fits, so the low limb is the value.
  *to = static_cast<int64_t>(from.lo);
}
inline void Load(const Int128& from, Int128* to) { *to = from; }
inline void Load(int64_t from, int64_t* to) { *to = from; }

/// Loads a table entry into a stepper's accumulator in the stepping format:
/// for a word-aligned 64-bit table (DiffFormat::word_aligned) moved to 32
/// fractional bits, with the rounding half added to the position
/// (`position`: entry 0 of a curve, entry (0,0) of a patch). The shift is
/// exact and the planner proved the range. It runs once per entry when a
/// stepper starts; out of line on AVR, where a copy in every stepper's
/// constructor costs more flash than the call costs time.
FDSURF_OUT_OF_LINE_ON_AVR inline void Load(const Int128& from, const DiffFormat& format,
                                           bool position, int64_t* to) {
  const int64_t value = static_cast<int64_t>(from.lo);
  if (format.word_aligned == 0) {
    *to = value;
    return;
  }
  const int64_t moved = format.frac_bits == 32 ? value : ShiftLeft(value, 32 - format.frac_bits);
  *to = position ? moved + (int64_t{1} << 31) : moved;
}
inline void Load(const Int128& from, const DiffFormat& /*format*/, bool /*position*/, Int128* to) {
  *to = from;
}

/// RoundToQuanta for the steppers' tables that are not word-aligned; out of
/// line on AVR (FDSURF_OUT_OF_LINE_ON_AVR).
FDSURF_OUT_OF_LINE_ON_AVR inline int32_t RoundPosition(int64_t position, int frac_bits) {
  return RoundToQuanta(position, frac_bits);
}

/// A position in the stepping format, rounded to whole quanta: the high word
/// of a word-aligned one (floor((x·2^(32−F) + 2^31) / 2^32) = floor(x·2^-F + ½),
/// the same bits as RoundToQuanta), else RoundToQuanta.
/// The high word is read as the upper 4 bytes of the position where the
/// byte order allows (avr-gcc otherwise calls __lshrdi3 for the shift by 32).
inline int32_t PositionQuanta(const int64_t& position, bool word_aligned, int frac_bits) {
  if (!word_aligned) return RoundPosition(position, frac_bits);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  uint32_t high;
  __builtin_memcpy(&high, reinterpret_cast<const unsigned char*>(&position) + 4, 4);
  return ToInt32(high);
#else
  return ToInt32(static_cast<uint32_t>(static_cast<uint64_t>(position) >> 32));
#endif
}
inline int32_t PositionQuanta(const Int128& position, bool /*word_aligned*/, int frac_bits) {
  return RoundToQuanta(position, frac_bits);
}

/// round(value·2^-shift) as an int64_t, halves up: a table entry of the
/// wide format moved to a line's format, `shift` = 1..63 bits fewer. The
/// planner proved that the result fits (docs/precision.md).
inline int64_t RoundToLine(const Int128& value, int shift) {
  const Int128 biased = value + Int128{uint64_t{1} << (shift - 1), 0};
  return static_cast<int64_t>(ShiftRightArithmetic(biased, shift).lo);
}

/// Advances a difference vector `steps` steps at once, exactly: Δ^k after
/// the steps is Σ_b C(steps, b)·Δ^(k+b), the closed form of that many
/// row-add updates (Pascal's rule), so the result is what stepping would
/// hold. Requires steps ≤ 2000 (C(steps, 3) < 2^32); the planner's range
/// proof covers the result, and MultipliedBy wraps as the steps would.
inline void AdvanceExactly(Int128 (&d)[4], uint32_t steps) {
  const uint32_t c1 = steps;
  const uint32_t c2 = steps * (steps - 1) / 2;
  const uint32_t c3 = static_cast<uint32_t>(uint64_t{c2} * (steps - 2) / 3);
  d[0] += MultipliedBy(d[1], c1) + MultipliedBy(d[2], c2) + MultipliedBy(d[3], c3);
  d[1] += MultipliedBy(d[2], c1) + MultipliedBy(d[3], c2);
  d[2] += MultipliedBy(d[3], c1);
}

/// The row-add update of one difference vector: advance one step.
template <typename Acc>
inline void Step(Acc* d) {
  d[0] += d[1];
  d[1] += d[2];
  d[2] += d[3];
}

#if defined(__AVR__)
/// The row-add update of a 64-bit vector on AVR. avr-gcc makes each 64-bit
/// add a call to `__adddi3` with both operands moved through 16 registers
/// (about 100 cycles); here the three adds walk the 32 contiguous bytes of
/// d[0..3] with two pointers, Z on the sum and X on the addend one entry
/// later, each an add-with-carry chain of 8 bytes, unrolled: 7 cycles a
/// byte, 168 for the vector, in 192 bytes of flash. After d[0] += d[1] the
/// pointers sit on d[1] and d[2], so the next add follows with no set-up;
/// d[1] is read before it is changed, as in the generic version. Out of
/// line: one copy serves every stepper.
__attribute__((noinline)) inline void Step(int64_t* d) {
  unsigned char* sum = reinterpret_cast<unsigned char*>(d);
  const unsigned char* addend = reinterpret_cast<const unsigned char*>(d + 1);
  unsigned char scratch;
  asm volatile(
      ".rept 3\n\t"
      "ld __tmp_reg__, X+\n\t"
      "ld %[s], Z\n\t"
      "add %[s], __tmp_reg__\n\t"
      "st Z+, %[s]\n\t"
      ".rept 7\n\t"
      "ld __tmp_reg__, X+\n\t"
      "ld %[s], Z\n\t"
      "adc %[s], __tmp_reg__\n\t"
      "st Z+, %[s]\n\t"
      ".endr\n\t"
      ".endr"
      : [s] "=&r"(scratch), "+z"(sum), "+x"(addend)
      :
      : "memory");
}
#endif

/// One coordinate's difference vector in a word-aligned 64-bit stepper
/// (WordAlignedLanes): Load, Step (the row-add update; `third` is the
/// coordinate's third difference in the stepper's table, the same at every
/// step of a cubic) and Quanta (the position's high word, as
/// PositionQuanta). Per core, because the compiler's own code is far from
/// the instruction count the core allows (docs/performance.md, "Stepping
/// in lanes"):
/// - generic (Thumb-2, x86-64, ...): d0..d2 as int64_t locals the compiler
///   keeps in registers; the third difference is read from the table at each
///   step, which leaves two registers a coordinate free (2-D on the
///   Cortex-M4F: 26 instructions a point, 57 with arrays);
/// - RV32, which has no carry flag: written out in 32-bit halves;
/// - ARMv6-M (Cortex-M0), whose adds take only the 8 low registers: in
///   memory, one ldm and two stm a step;
/// - AVR: in memory, internal::Step's add-with-carry chain.
#if defined(__riscv) && __riscv_xlen == 32
/// Each entry as two 32-bit halves in registers. A 64-bit add is four
/// instructions in place: add the low words, carry = sum < addend, add the
/// high words, add the carry. GCC's own keeps each old low word alive for its
/// carry test and adds a move per add (a probe: 38 instructions a 2-D point;
/// 29.3 measured with this).
struct WordAlignedLane {
  uint32_t lo[4];
  uint32_t hi[4];

  void Load(const int64_t (&from)[4]) {
    for (int k = 0; k < 4; ++k) {
      lo[k] = static_cast<uint32_t>(static_cast<uint64_t>(from[k]));
      hi[k] = static_cast<uint32_t>(static_cast<uint64_t>(from[k]) >> 32);
    }
  }
  void Step(const int64_t& /*third: held in lo[3], hi[3]*/) {
    uint32_t carry;
    asm("add %[l0], %[l0], %[l1]\n\t"
        "sltu %[c], %[l0], %[l1]\n\t"
        "add %[h0], %[h0], %[h1]\n\t"
        "add %[h0], %[h0], %[c]\n\t"
        "add %[l1], %[l1], %[l2]\n\t"
        "sltu %[c], %[l1], %[l2]\n\t"
        "add %[h1], %[h1], %[h2]\n\t"
        "add %[h1], %[h1], %[c]\n\t"
        "add %[l2], %[l2], %[l3]\n\t"
        "sltu %[c], %[l2], %[l3]\n\t"
        "add %[h2], %[h2], %[h3]\n\t"
        "add %[h2], %[h2], %[c]"
        : [l0] "+r"(lo[0]), [h0] "+r"(hi[0]), [l1] "+r"(lo[1]), [h1] "+r"(hi[1]), [l2] "+r"(lo[2]),
          [h2] "+r"(hi[2]), [c] "=&r"(carry)
        : [l3] "r"(lo[3]), [h3] "r"(hi[3]));
  }
  FDSURF_NODISCARD int32_t Quanta() const { return ToInt32(hi[0]); }
};
#elif defined(__ARM_ARCH_6M__) || defined(__AVR__)
struct WordAlignedLane {
  int64_t d[4];

  void Load(const int64_t (&from)[4]) {
    for (int k = 0; k < 4; ++k) d[k] = from[k];
  }
#if defined(__AVR__)
  void Step(const int64_t& /*third: d[3]*/) { internal::Step(d); }
#else
  /// The 8 words of a lane do not fit the 8 low registers beside a pointer,
  /// so the lane stays in memory: one ldm loads d0..d2 into r0-r5, d0 += d1
  /// and d1 += d2 run there, one stm stores d0 and d1, which frees r0 and r1
  /// for d3, and d2 += d3 is stored with a second stm: 12 instructions a
  /// coordinate, where GCC's version moves every word through the stack (a
  /// probe: 49 instructions a 2-D point; 35.7 measured with this). The
  /// pointer takes a seventh low
  /// register, so the block builds with a frame pointer (r7) too, and the
  /// eighth is left to the caller's loop counter.
  void Step(const int64_t& /*third: d[3]*/) {
    int64_t* at = d;
    // GCC passes Thumb-1 inline assembly in the divided syntax; this block
    // is written in the unified one and switches back at its end.
    asm volatile(
        ".syntax unified\n\t"
        "ldm %[at]!, {r0, r1, r2, r3, r4, r5}\n\t"
        "adds r0, r0, r2\n\t"
        "adcs r1, r1, r3\n\t"
        "adds r2, r2, r4\n\t"
        "adcs r3, r3, r5\n\t"
        "subs %[at], %[at], #24\n\t"
        "stm %[at]!, {r0, r1, r2, r3}\n\t"
        "ldr r0, [%[at], #8]\n\t"
        "ldr r1, [%[at], #12]\n\t"
        "adds r4, r4, r0\n\t"
        "adcs r5, r5, r1\n\t"
        "stm %[at]!, {r4, r5}\n\t"
        ".syntax divided"
        : [at] "+l"(at)
        :
        : "r0", "r1", "r2", "r3", "r4", "r5", "cc", "memory");
  }
#endif
  FDSURF_NODISCARD int32_t Quanta() const { return PositionQuanta(d[0], true, 32); }
};
#else
struct WordAlignedLane {
  int64_t d[3];

  void Load(const int64_t (&from)[4]) {
    for (int k = 0; k < 3; ++k) d[k] = from[k];
  }
  void Step(const int64_t& third) {
    d[0] += d[1];
    d[1] += d[2];
    d[2] += third;
  }
  FDSURF_NODISCARD int32_t Quanta() const { return PositionQuanta(d[0], true, 32); }
};
#endif

/// The difference vectors of a word-aligned 64-bit stepper, one lane per
/// coordinate as a member rather than an array indexed by a loop over the
/// coordinates, so that every entry is a named local the compiler can hold
/// in a register (an array stays in memory and is read and written at every
/// step). Built by recursion on kDims, so C++14 suffices. `table` is the
/// difference vectors the lanes were loaded from.
template <int kDims>
struct WordAlignedLanes {
  WordAlignedLane first;
  WordAlignedLanes<kDims - 1> rest;

  void Load(const int64_t (*table)[4]) {
    first.Load(table[0]);
    rest.Load(table + 1);
  }
  void Step(const int64_t (*table)[4]) {
    first.Step(table[0][3]);
    rest.Step(table + 1);
  }
  void Read(int32_t* point) const {
    *point = first.Quanta();
    rest.Read(point + 1);
  }
};
template <>
struct WordAlignedLanes<0> {
  void Load(const int64_t (*)[4]) {}
  void Step(const int64_t (*)[4]) {}
  void Read(int32_t*) const {}
};

/// Steps the difference vectors `d` (one per coordinate) `steps` times,
/// calling emit(n, point) at n = 0..steps with the point in quanta; `d` is
/// scratch afterwards. The int64_t overload steps a word-aligned table in
/// WordAlignedLanes.
template <typename Acc, int kDims, typename Emit>
inline void StepVectors(Acc (&d)[kDims][4], uint32_t steps, int frac_bits, Emit&& emit) {
  int32_t point[kDims];
  for (uint32_t n = 0;; ++n) {
    for (int c = 0; c < kDims; ++c) point[c] = PositionQuanta(d[c][0], false, frac_bits);
    emit(n, point);
    if (n == steps) return;
    for (int c = 0; c < kDims; ++c) Step(d[c]);
  }
}
template <int kDims, typename Emit>
inline void StepVectors(int64_t (&d)[kDims][4], uint32_t steps, bool word_aligned, int frac_bits,
                        Emit&& emit) {
  if (!word_aligned) {
    StepVectors(d, steps, frac_bits, emit);
    return;
  }
  WordAlignedLanes<kDims> lanes;
  lanes.Load(d);
  int32_t point[kDims];
  // Counting the steps left down to 0 keeps one register free where the
  // sink ignores the index (steps − left is then dead code).
  for (uint32_t left = steps;; --left) {
    lanes.Read(point);
    emit(steps - left, point);
    if (left == 0) return;
    lanes.Step(d);
  }
}
/// 128-bit tables are never word-aligned (the planner sets it for 64 only).
template <int kDims, typename Emit>
inline void StepVectors(Int128 (&d)[kDims][4], uint32_t steps, bool /*word_aligned*/, int frac_bits,
                        Emit&& emit) {
  StepVectors(d, steps, frac_bits, emit);
}

}  // namespace internal

/// Steps a prepared curve with accumulator Acc (int64_t or Int128; int64_t
/// only when format.acc_bits == 64). Sink is called as sink(i, point) with
/// point an `const int32_t (&)[kDims]` in quanta, for i = 0..steps.
template <typename Acc, int kDims>
class CurveStepper {
 public:
  explicit CurveStepper(const PreparedCurve<kDims>& curve)
      : frac_bits_(curve.format.frac_bits),
        word_aligned_(curve.format.word_aligned != 0),
        steps_(curve.steps) {
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) internal::Load(curve.d[c][k], curve.format, k == 0, &d_[c][k]);
    }
  }

  template <typename Sink>
  void ForEachPoint(Sink&& sink) const {
    Acc d[kDims][4];
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) d[c][k] = d_[c][k];
    }
    internal::StepVectors(d, steps_, word_aligned_, frac_bits_, sink);
  }

 private:
  Acc d_[kDims][4];
  int frac_bits_;
  bool word_aligned_;
  uint16_t steps_;
};

/// Steps a prepared patch with accumulator Acc (see CurveStepper).
template <typename Acc, int kDims>
class PatchStepper {
 public:
  explicit PatchStepper(const PreparedPatch<kDims>& patch)
      : frac_bits_(patch.format.frac_bits),
        word_aligned_(patch.format.word_aligned != 0),
        steps_s_(patch.steps_s),
        steps_t_(patch.steps_t) {
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) {
        for (int l = 0; l < 4; ++l) {
          internal::Load(patch.dd[c][k][l], patch.format, k == 0 && l == 0, &dd_[c][k][l]);
        }
      }
    }
  }

  /// s-lines (t varies along each): sink(i, j, point) for i = 0..steps_s, and
  /// within each i, j = 0..steps_t. This is also the full grid, i-major.
  /// Row 0 of DD is the t-difference vector of the s-line at s_i; stepping s
  /// is the row-add update applied to the columns of DD.
  template <typename Sink>
  void ForEachSLinePoint(Sink&& sink) const {
    Acc dd[kDims][4][4];
    Copy(dd);
    Acc line[kDims][4];
    for (uint32_t i = 0;; ++i) {
      for (int c = 0; c < kDims; ++c) {
        for (int l = 0; l < 4; ++l) line[c][l] = dd[c][0][l];
      }
      internal::StepVectors(line, steps_t_, word_aligned_, frac_bits_,
                            [&](uint32_t j, const int32_t(&point)[kDims]) { sink(i, j, point); });
      if (i == steps_s_) break;
      for (int c = 0; c < kDims; ++c) {
        for (int l = 0; l < 4; ++l) {
          dd[c][0][l] += dd[c][1][l];
          dd[c][1][l] += dd[c][2][l];
          dd[c][2][l] += dd[c][3][l];
        }
      }
    }
  }

  /// t-lines (s varies along each): sink(i, j, point) for j = 0..steps_t, and
  /// within each j, i = 0..steps_s. The transposed stepping: column 0 of DD
  /// is the s-difference vector of the t-line at t_j.
  template <typename Sink>
  void ForEachTLinePoint(Sink&& sink) const {
    Acc dd[kDims][4][4];
    Copy(dd);
    Acc line[kDims][4];
    for (uint32_t j = 0;; ++j) {
      for (int c = 0; c < kDims; ++c) {
        for (int k = 0; k < 4; ++k) line[c][k] = dd[c][k][0];
      }
      internal::StepVectors(line, steps_s_, word_aligned_, frac_bits_,
                            [&](uint32_t i, const int32_t(&point)[kDims]) { sink(i, j, point); });
      if (j == steps_t_) break;
      for (int c = 0; c < kDims; ++c) {
        for (int k = 0; k < 4; ++k) internal::Step(dd[c][k]);
      }
    }
  }

 private:
  void Copy(Acc (&to)[kDims][4][4]) const {
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) {
        for (int l = 0; l < 4; ++l) to[c][k][l] = dd_[c][k][l];
      }
    }
  }

  Acc dd_[kDims][4][4];
  int frac_bits_;
  bool word_aligned_;
  uint16_t steps_s_;
  uint16_t steps_t_;
};

/// Steps a prepared patch with per-line rounding, a 64-bit inner loop whose
/// points are the high word wherever the plan gives the lines 32 bits
/// (docs/precision.md, "Per-line rounding"): the outer
/// direction is stepped in the wide format, and at each line its difference
/// vector is rounded to the line's own format (s_line_frac_bits or
/// t_line_frac_bits, which must be non-zero for the family stepped), the
/// rounding half added to its position, and stepped in int64_t; a line
/// longer than its family's segment steps is re-rounded at the start of each
/// segment from its exact wide state. Every point is within 0.51 quanta of
/// the exact patch; s-lines and t-lines may differ by a quantum where the
/// exact value is within about 0.005 quanta of a half (they round different
/// lines).
template <int kDims>
class LinePatchStepper {
 public:
  explicit LinePatchStepper(const PreparedPatch<kDims>& patch) : patch_(patch) {}

  /// As PatchStepper::ForEachSLinePoint; needs patch.s_line_frac_bits.
  template <typename Sink>
  void ForEachSLinePoint(Sink&& sink) const {
    Int128 dd[kDims][4][4];
    Copy(dd);
    for (uint32_t i = 0;; ++i) {
      Int128 line[kDims][4];
      for (int c = 0; c < kDims; ++c) {
        for (int l = 0; l < 4; ++l) line[c][l] = dd[c][0][l];
      }
      StepLine(line, patch_.s_line_frac_bits, patch_.s_line_segment_steps, patch_.steps_t,
               [&](uint32_t j, const int32_t(&point)[kDims]) { sink(i, j, point); });
      if (i == patch_.steps_s) break;
      for (int c = 0; c < kDims; ++c) {
        for (int l = 0; l < 4; ++l) {
          dd[c][0][l] += dd[c][1][l];
          dd[c][1][l] += dd[c][2][l];
          dd[c][2][l] += dd[c][3][l];
        }
      }
    }
  }

  /// As PatchStepper::ForEachTLinePoint; needs patch.t_line_frac_bits.
  template <typename Sink>
  void ForEachTLinePoint(Sink&& sink) const {
    Int128 dd[kDims][4][4];
    Copy(dd);
    for (uint32_t j = 0;; ++j) {
      Int128 line[kDims][4];
      for (int c = 0; c < kDims; ++c) {
        for (int k = 0; k < 4; ++k) line[c][k] = dd[c][k][0];
      }
      StepLine(line, patch_.t_line_frac_bits, patch_.t_line_segment_steps, patch_.steps_s,
               [&](uint32_t i, const int32_t(&point)[kDims]) { sink(i, j, point); });
      if (j == patch_.steps_t) break;
      for (int c = 0; c < kDims; ++c) {
        for (int k = 0; k < 4; ++k) internal::Step(dd[c][k]);
      }
    }
  }

 private:
  /// Steps one line of `steps` steps from `wide`, its difference vectors in
  /// the table's format, segment by segment: each segment's vectors are
  /// rounded to `line_bits` fractional bits with the rounding half added to
  /// the position (the planner left 2 quanta of range for it), so that a
  /// point is a floor shift or the high word, and stepped in int64_t; then
  /// `wide` is advanced exactly to the next segment's start. Calls
  /// line_sink(index along the line, point) for indices 0..steps.
  template <typename LineSink>
  void StepLine(Int128 (&wide)[kDims][4], int line_bits, uint16_t segment_steps, uint16_t steps,
                LineSink&& line_sink) const {
    const int shift = patch_.format.frac_bits - line_bits;
    // 0 (a table built by hand without segments): the whole line at once.
    const uint32_t segment = segment_steps == 0 ? steps : segment_steps;
    int64_t half;
    internal::RoundingHalf(line_bits, &half);
    int64_t line[kDims][4];
    int32_t point[kDims];
    for (uint32_t start = 0;;) {
      const bool last_segment = steps - start <= segment;
      const uint32_t end = last_segment ? steps : start + segment;
      for (int c = 0; c < kDims; ++c) {
        for (int k = 0; k < 4; ++k) line[c][k] = internal::RoundToLine(wide[c][k], shift);
        line[c][0] += half;
      }
      // A segment's last point is the next segment's first: only the last
      // segment emits its end.
      const uint32_t last_point = last_segment ? end : end - 1;
      if (line_bits == 32) {
        // The point is the high word: the word-aligned lanes.
        internal::StepVectors(
            line, last_point - start, true, 32,
            [&](uint32_t k, const int32_t(&at)[kDims]) { line_sink(start + k, at); });
      } else {
        for (uint32_t n = start;; ++n) {
          for (int c = 0; c < kDims; ++c) point[c] = FloorToQuanta(line[c][0], line_bits);
          line_sink(n, point);
          if (n == last_point) break;
          for (int c = 0; c < kDims; ++c) internal::Step(line[c]);
        }
      }
      if (last_segment) return;
      for (int c = 0; c < kDims; ++c) internal::AdvanceExactly(wide[c], end - start);
      start = end;
    }
  }

  void Copy(Int128 (&to)[kDims][4][4]) const {
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) {
        for (int l = 0; l < 4; ++l) to[c][k][l] = patch_.dd[c][k][l];
      }
    }
  }

  const PreparedPatch<kDims>& patch_;
};

}  // namespace fdsurf
