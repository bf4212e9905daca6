// SPDX-License-Identifier: MIT
// Adaptive forward differencing of cubic curves and of the isoparametric
// curves of bicubic patches.
//
// A curve is prepared once at its finest step 2^-L, exactly: its power
// coefficients are rounded once to 2^-16 quanta, and the difference vector is
// held in units of 2^-(16+3L) quanta, where every difference at every step
// 2^-l (l ≤ L) is an integer. Stepping then adapts the step by powers of two
// with exact integer transforms of the difference vector:
//
//   double the step:  Δ¹ ← 2Δ¹ + Δ²,   Δ² ← 4Δ² + 4Δ³,   Δ³ ← 8Δ³
//   halve the step:   Δ¹ ← (8Δ¹ − 2Δ² + Δ³)/16,  Δ² ← (2Δ² − Δ³)/8,  Δ³ ← Δ³/8
//
// (the divisions are exact, because the halved table is again a table of the
// same exact curve at a step no finer than 2^-L), and each step is the
// row-add update. No multiplies or divides in the loop: shifts, additions and
// comparisons only.
//
// The chord test: on a step, the chord between two consecutive exact points
// lies within max(|Δ²|, |Δ² − Δ³|)/8 of the curve, per axis. With every
// emitted point rounded to whole quanta, the polyline of emitted points is
// within sqrt(dims)·(max/8 + 0.5 + 2^-10) quanta of the exact curve in the
// Euclidean norm; the stepper keeps that under the caller's tolerance.
// docs/toolpaths.md proves both statements.
#pragma once

#include <stdint.h>

#include "fdsurf/basis.h"
#include "fdsurf/config/nodiscard.h"
#include "fdsurf/forward_difference.h"
#include "fdsurf/int128.h"
#include "fdsurf/status.h"

namespace fdsurf {

/// The finest step is at least 2^-kMaxAdaptiveLevel of the parameter range.
constexpr int kMaxAdaptiveLevel = 30;
/// Fractional bits of the power coefficients of an adaptive curve.
constexpr int kCoefficientFracBits = 16;

/// What the stepper keeps within bounds besides the point positions.
enum class AdaptiveMode : uint8_t {
  /// Every chord within the tolerance of the curve, with as few points as the
  /// power-of-two step adaptation allows.
  kTolerance = 0,
  /// Additionally, consecutive points differ by at most one quantum per axis
  /// (a step-exact path for machines that move one motor step at a time).
  /// Repeated points are not emitted.
  kStepExact = 1,
};

struct AdaptiveSettings {
  AdaptiveMode mode = AdaptiveMode::kTolerance;
  /// The Euclidean tolerance between the emitted polyline and the exact curve,
  /// in units of 2^-8 quanta. Must exceed sqrt(dims)·(0.5 + 2^-10) quanta.
  uint32_t tolerance_q8 = 0;
  /// 64 refuses curves that need the 128-bit accumulator.
  uint8_t max_acc_bits = 128;
};

/// One coordinate of a cubic a·t³ + b·t² + c·t + d as integers in units of
/// 2^-kCoefficientFracBits quanta: c[0] = a, ..., c[3] = d.
struct PowerCurve1 {
  int64_t c[4];
};

/// A curve ready for adaptive stepping. Its entries are Int128 (either
/// accumulator: format.acc_bits says which), or int64_t for a table set up for
/// the 64-bit accumulator only (PrepareAdaptiveCurveAtLevel's second form,
/// for a device without Int128 code).
template <int kDims, typename Entry = Int128>
struct PreparedAdaptiveCurve {
  /// frac_bits = kCoefficientFracBits + 3·finest_level.
  DiffFormat format;
  /// L: the finest step is 2^-L; positions are reported in these units.
  uint8_t finest_level;
  AdaptiveMode mode;
  /// Δ⁰..Δ³ per axis at t = 0 for the step 2^-L.
  Entry d[kDims][4];
  /// A step is taken only when max(|Δ²|, |Δ² − Δ³|) ≤ chord_limit on every axis.
  Entry chord_limit;
  /// In kStepExact, a step is taken only when |Δ¹| ≤ step_limit (one quantum).
  Entry step_limit;
};

/// Plans and sets up one curve from its power coefficients. Errors:
/// kToleranceUnreachable (tolerance too small for whole-quantum output),
/// kGeometryOutOfRange (positions could reach ±2^31 quanta),
/// kPrecisionUnreachable (no step ≥ 2^-kMaxAdaptiveLevel meets the tolerance
/// or the step limit, or no allowed accumulator holds the differences).
template <int kDims>
Status PrepareAdaptiveCurve(const PowerCurve1 (&curve)[kDims], const AdaptiveSettings& settings,
                            PreparedAdaptiveCurve<kDims>* out);

/// Sets up a curve whose power coefficients were rounded, and whose finest
/// level was chosen, elsewhere (the host: "the host computes, the device
/// adds"), with no wide-integer arithmetic, multiply by a variable or divide:
/// shifts, additions and comparisons of Int128 values, so that a small device
/// needs none of the planner's set-up code. It checks, at `level`, the
/// planner's own conditions (every coefficient in the geometry range, every
/// step of 2^-level within the chord limit and, in kStepExact, within one
/// quantum, every value the stepper forms below 2^62 for the 64-bit
/// accumulator or 2^126 for Int128, within settings.max_acc_bits), then forms
/// the table by shifts and additions. PrepareAdaptiveCurve is this at the
/// smallest level whose step tests pass (which it searches for); a level
/// above it may be accepted too (the step tests only get easier), one below
/// it is refused. docs/toolpaths.md, "A level chosen by the host".
/// Errors: kToleranceUnreachable, kGeometryOutOfRange, kPrecisionUnreachable
/// (level outside 0..kMaxAdaptiveLevel, a step of 2^-level fails a test, or
/// no allowed accumulator holds the values).
template <int kDims>
Status PrepareAdaptiveCurveAtLevel(const PowerCurve1 (&curve)[kDims], int level,
                                   const AdaptiveSettings& settings,
                                   PreparedAdaptiveCurve<kDims>* out);
/// The same check and table for the 64-bit accumulator only, in 64-bit
/// arithmetic: a device built without Int128 code (the Arduino Uno, issue 17)
/// links this one. It accepts exactly the curves and levels that the form
/// above accepts with settings.max_acc_bits = 64, and forms the same table
/// (docs/toolpaths.md, "A level chosen by the host"). Errors as above.
template <int kDims>
Status PrepareAdaptiveCurveAtLevel(const PowerCurve1 (&curve)[kDims], int level,
                                   const AdaptiveSettings& settings,
                                   PreparedAdaptiveCurve<kDims, int64_t>* out);

/// Converts a curve's basis geometry (fdsurf/forward_difference.h) to power
/// coefficients, rounding each once to 2^-kCoefficientFracBits quanta.
/// Errors: kInvalidArgument (basis), kGeometryOutOfRange (|g| ≥ 2^31 quanta).
template <int kDims>
Status CurvePowerCoefficients(const CurveGeometry1 (&geometry)[kDims], Basis basis,
                              PowerCurve1 (&out)[kDims]);

/// Which isoparametric curves of a patch.
enum class IsolineFamily : uint8_t {
  /// s fixed on each line, t from 0 to 1 along it.
  kSLines = 0,
  /// t fixed on each line, s from 0 to 1 along it.
  kTLines = 1,
};

/// Produces the evenly spaced isolines of a patch one after the other, by
/// forward differences across the patch: the table n³·E(1/n)·C (n = lines − 1,
/// scaled to integers, exact) is stepped with the row-add update for s-lines,
/// or its transpose for t-lines, and row 0 is the next line's coefficients.
/// Only the per-line rounding of those coefficients divides.
template <int kDims>
class IsolineWalker {
 public:
  /// `lines` ≥ 2 lines at parameters i/(lines − 1), i = 0..lines − 1, with
  /// lines − 1 ≤ kMaxPatchSteps. Errors: kInvalidArgument (basis),
  /// kGridOutOfRange (lines), kGeometryOutOfRange (|g| ≥ 2^31 quanta).
  static Status Create(const PatchGeometry1 (&geometry)[kDims], Basis basis, IsolineFamily family,
                       uint16_t lines, IsolineWalker* out);

  FDSURF_NODISCARD uint16_t lines() const { return lines_; }
  /// How many lines Next() has produced.
  FDSURF_NODISCARD uint16_t produced() const { return produced_; }

  /// The power coefficients (in t for s-lines, in s for t-lines) of the next
  /// line, then one row-add step across the patch. Returns false after the
  /// last line.
  bool Next(PowerCurve1 (&curve)[kDims]);

 private:
  /// Per coordinate: row k is the k-th difference across the patch; column l
  /// multiplies the along-line power u^(3-l). Scaled by divisor_ and by
  /// 2^kCoefficientFracBits.
  Int128 table_[kDims][4][4];
  uint32_t divisor_[2];  // d² (basis denominators), n³
  uint16_t lines_;
  uint16_t produced_;
};

namespace internal {

/// Whether every axis passes the chord test (and, in step-exact mode, the
/// one-quantum step test) for the current step.
template <typename Acc, int kDims>
inline bool StepFits(const Acc (&d)[kDims][4], const Acc& chord_limit, const Acc& step_limit,
                     bool step_exact) {
  for (int c = 0; c < kDims; ++c) {
    if (!WithinMagnitude(d[c][2], chord_limit)) return false;
    if (!WithinMagnitude(d[c][2] - d[c][3], chord_limit)) return false;
    if (step_exact && !WithinMagnitude(d[c][1], step_limit)) return false;
  }
  return true;
}

/// The same test for the doubled step, without forming it: the doubled Δ² is
/// 4(Δ² + Δ³) and the doubled Δ² − Δ³ is 4(Δ² − Δ³); the doubled Δ¹ is 2Δ¹ + Δ².
template <typename Acc, int kDims>
inline bool DoubledStepFits(const Acc (&d)[kDims][4], const Acc& quarter_chord_limit,
                            const Acc& step_limit, bool step_exact) {
  for (int c = 0; c < kDims; ++c) {
    if (!WithinMagnitude(d[c][2] + d[c][3], quarter_chord_limit)) return false;
    if (!WithinMagnitude(d[c][2] - d[c][3], quarter_chord_limit)) return false;
    if (step_exact && !WithinMagnitude(ShiftLeft(d[c][1], 1) + d[c][2], step_limit)) return false;
  }
  return true;
}

template <typename Acc>
inline void DoubleStep(Acc* d) {
  d[1] = ShiftLeft(d[1], 1) + d[2];
  d[2] = ShiftLeft(d[2] + d[3], 2);
  d[3] = ShiftLeft(d[3], 3);
}

template <typename Acc>
inline void HalveStep(Acc* d) {
  const Acc d1 = ShiftRightArithmetic(ShiftLeft(d[1], 3) - ShiftLeft(d[2], 1) + d[3], 4);
  const Acc d2 = ShiftRightArithmetic(ShiftLeft(d[2], 1) - d[3], 3);
  d[1] = d1;
  d[2] = d2;
  d[3] = ShiftRightArithmetic(d[3], 3);
}

/// One step of an adaptive cursor at *position (units of the finest step,
/// *step long before, end the last): halves while the step fails its tests
/// or would overshoot `end`, down to the finest step at most (which is then
/// taken as it is); doubles while the doubled step passes and stays within
/// `end`; then steps the table and advances *position by the step taken.
/// `test_step`: the Δ¹ test against step_limit applies too.
template <typename Acc, int kDims>
inline void AdaptAndStep(Acc (&d)[kDims][4], const Acc& chord_limit, const Acc& quarter_chord_limit,
                         const Acc& step_limit, bool test_step, uint32_t end, uint32_t* step,
                         uint32_t* position) {
  while (*step > 1 &&
         (*step > end - *position || !StepFits(d, chord_limit, step_limit, test_step))) {
    for (int c = 0; c < kDims; ++c) HalveStep(d[c]);
    *step >>= 1;
  }
  while (*step <= (end - *position) / 2 &&
         DoubledStepFits(d, quarter_chord_limit, step_limit, test_step)) {
    for (int c = 0; c < kDims; ++c) DoubleStep(d[c]);
    *step <<= 1;
  }
  for (int c = 0; c < kDims; ++c) Step(d[c]);
  *position += *step;
}

}  // namespace internal

/// Steps a prepared adaptive curve one point at a time, with accumulator Acc
/// (int64_t only when format.acc_bits == 64, else Int128). Resumable, so a
/// motion loop can pull points as it needs them; AdaptiveCurveStepper wraps
/// it in a callback loop.
template <typename Acc, int kDims>
class AdaptiveCurveCursor {
 public:
  AdaptiveCurveCursor() = default;
  explicit AdaptiveCurveCursor(const PreparedAdaptiveCurve<kDims>& curve) { Reset(curve); }

  /// Starts over on `curve` (Int128 entries, or int64_t ones for Acc = int64_t).
  template <typename Entry>
  void Reset(const PreparedAdaptiveCurve<kDims, Entry>& curve) {
    // The rounding half rides in the position, which only ever has steps
    // added to it (halving and doubling change d[1..3]), so a point is
    // floor(d[0]·2^-F): no add per point. The planner's bound covers it
    // (docs/toolpaths.md, "Choosing the finest level, and the range").
    Acc half;
    internal::RoundingHalf(curve.format.frac_bits, &half);
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) internal::Load(curve.d[c][k], &d_[c][k]);
      d_[c][0] += half;
    }
    internal::Load(curve.chord_limit, &chord_limit_);
    internal::Load(curve.step_limit, &step_limit_);
    quarter_chord_limit_ = internal::ShiftRightArithmetic(chord_limit_, 2);
    frac_bits_ = curve.format.frac_bits;
    end_ = uint32_t{1} << curve.finest_level;
    position_ = 0;
    step_ = 1;
    step_exact_ = curve.mode == AdaptiveMode::kStepExact;
    started_ = false;
    for (int c = 0; c < kDims; ++c) last_[c] = FloorToQuanta(d_[c][0], frac_bits_);
  }

  /// The next point in whole quanta and its position in units of
  /// 2^-finest_level of the parameter (0 first, 2^finest_level last).
  /// Returns false after the last point.
  bool Next(int32_t (&point)[kDims], uint32_t* position) {
    if (!started_) {
      started_ = true;
      for (int c = 0; c < kDims; ++c) point[c] = last_[c];
      *position = 0;
      return true;
    }
    while (position_ < end_) {
      // The planner proved the finest step always passes.
      internal::AdaptAndStep(d_, chord_limit_, quarter_chord_limit_, step_limit_, step_exact_, end_,
                             &step_, &position_);
      bool moved = !step_exact_;
      for (int c = 0; c < kDims; ++c) {
        point[c] = FloorToQuanta(d_[c][0], frac_bits_);
        moved = moved || point[c] != last_[c];
      }
      if (moved) {
        for (int c = 0; c < kDims; ++c) last_[c] = point[c];
        *position = position_;
        return true;
      }
    }
    return false;
  }

 private:
  Acc d_[kDims][4];
  Acc chord_limit_;
  Acc quarter_chord_limit_;
  Acc step_limit_;
  int32_t last_[kDims];
  uint32_t end_;
  uint32_t position_;
  uint32_t step_;  // in units of the finest step
  uint8_t frac_bits_;
  bool step_exact_;
  bool started_;
};

/// The chord budget of AdaptiveChordCursor for a command's tolerance: the
/// largest 2^-b quanta per axis, b ≥ kLargestChordBudgetBits, such that a
/// point rounded from a chord (docs/motion.md, "Path generation: chords") is
/// within the tolerance: √d·(1/2 + 2^-10 + 2^-8 + 2^-b) ≤ tol. Returns b, or
/// kFinestStepsOnly when even 2^-kSmallestChordBudgetBits does not fit (a
/// tolerance within 2^-8·√d of the least one): then only finest steps.
constexpr int kLargestChordBudgetBits = 6;
constexpr int kSmallestChordBudgetBits = 16;
constexpr int kFinestStepsOnly = 0;
int ChordBudgetBits(uint32_t tolerance_q8, int dims);

/// Walks a prepared adaptive curve as **chords** for a machine that steps
/// each chord itself (a DDA; docs/motion.md, "Path generation: chords"):
/// the longest power-of-two steps whose chord is within the budget
/// (2^-budget_bits quanta per axis) of the curve and which move no axis more
/// than 2^kMaxChordBits quanta where the accumulator can hold that limit
/// (else the table's range keeps every chord within 2^(kMaxChordBits + 1)
/// quanta). It takes any prepared table: the planner's range bound covers
/// every step from the finest up to the whole curve (docs/toolpaths.md), and
/// the finest step is always taken (a step-exact table's is at most one
/// quantum). Points are reported finer than quanta, as
/// floor((x + 1/2)·2^kFineBits) modulo 2^32 (x the point in quanta), so that
/// consecutive points' difference (at most 2^(kMaxChordBits + 1) quanta per
/// axis, times 2^kFineBits) and each point's fraction are exact on any
/// travel; floor(point / 2^kFineBits) is the point rounded to quanta
/// (halves up) where it is not wrapped.
template <typename Acc, int kDims>
class AdaptiveChordCursor {
 public:
  static constexpr int kFineBits = 8;
  static constexpr int kMaxChordBits = 7;

  /// Starts on `curve` with a budget of 2^-budget_bits quanta per axis,
  /// kLargestChordBudgetBits ≤ budget_bits ≤ kSmallestChordBudgetBits, or
  /// kFinestStepsOnly.
  template <typename Entry>
  void Reset(const PreparedAdaptiveCurve<kDims, Entry>& curve, int budget_bits) {
    Acc half;
    internal::RoundingHalf(curve.format.frac_bits, &half);
    for (int c = 0; c < kDims; ++c) {
      for (int k = 0; k < 4; ++k) internal::Load(curve.d[c][k], &d_[c][k]);
      d_[c][0] += half;
    }
    frac_bits_ = curve.format.frac_bits;
    if (budget_bits == kFinestStepsOnly) {
      // A negative limit fails every test: no step doubles, each is finest.
      Acc one;
      internal::RoundingHalf(1, &one);
      chord_limit_ = -one;
    } else {
      // The chord limit is 8·budget (the chord bound, docs/toolpaths.md):
      // 2^(F + 3 − budget_bits) in the table's units (F ≥ 16).
      internal::RoundingHalf(frac_bits_ + 4 - budget_bits, &chord_limit_);
    }
    quarter_chord_limit_ = internal::ShiftRightArithmetic(chord_limit_, 2);
    // A table's values are below 2^62 (int64_t) or 2^126 (Int128). Where
    // 2^(F + kMaxChordBits) is not, no point is 2^kMaxChordBits quanta from
    // the first, so no chord moves an axis 2^(kMaxChordBits + 1): no test.
    const int acc_limit_bits = sizeof(Acc) == 8 ? 62 : 126;
    capped_ = frac_bits_ + kMaxChordBits < acc_limit_bits;
    step_limit_ = chord_limit_;  // unused when not capped
    if (capped_) internal::RoundingHalf(frac_bits_ + kMaxChordBits + 1, &step_limit_);
    end_ = uint32_t{1} << curve.finest_level;
    position_ = 0;
    step_ = 1;
    started_ = false;
  }

  /// The next chord end (the first point first) in 2^-kFineBits quanta as
  /// above; *finest: the chord is one finest step (2^-L), which a step-exact
  /// table's planner proved moves each axis at most one quantum, though its
  /// chord may exceed the budget. Returns false after the last.
  bool Next(int32_t (&fine)[kDims], bool* finest) {
    if (started_) {
      if (position_ >= end_) return false;
      // A finest step that fails the budget is taken as it is.
      internal::AdaptAndStep(d_, chord_limit_, quarter_chord_limit_, step_limit_, capped_, end_,
                             &step_, &position_);
    }
    started_ = true;
    *finest = step_ == 1;
    for (int c = 0; c < kDims; ++c) fine[c] = FloorToQuanta(d_[c][0], frac_bits_ - kFineBits);
    return true;
  }

  /// Where the last point is, in units of 2^-finest_level of the parameter.
  FDSURF_NODISCARD uint32_t position() const { return position_; }

 private:
  Acc d_[kDims][4];
  Acc chord_limit_;
  Acc quarter_chord_limit_;
  Acc step_limit_;
  uint32_t end_;
  uint32_t position_;
  uint32_t step_;  // in units of the finest step
  uint8_t frac_bits_;
  bool capped_;
  bool started_;
};

/// Steps a prepared adaptive curve with accumulator Acc (int64_t only when
/// format.acc_bits == 64, else Int128). Sink is called as
/// sink(position, point): position in units of 2^-finest_level of the
/// parameter (0 first, 2^finest_level last), point a `const int32_t (&)[kDims]`
/// in whole quanta.
template <typename Acc, int kDims>
class AdaptiveCurveStepper {
 public:
  explicit AdaptiveCurveStepper(const PreparedAdaptiveCurve<kDims>& curve) : curve_(curve) {}

  template <typename Sink>
  void ForEachPoint(Sink&& sink) const {
    AdaptiveCurveCursor<Acc, kDims> cursor(curve_);
    int32_t point[kDims];
    uint32_t position = 0;
    while (cursor.Next(point, &position)) sink(position, point);
  }

 private:
  PreparedAdaptiveCurve<kDims> curve_;
};

}  // namespace fdsurf
