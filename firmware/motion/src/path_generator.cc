// SPDX-License-Identifier: MIT
#include "fdsurf/motion/path_generator.h"

namespace fdsurf {
namespace motion {
namespace {

using protocol::ErrorCode;
using protocol::MessageType;

constexpr int64_t kOneStep = int64_t{1} << kCoefficientFracBits;
constexpr int64_t kHalfStep = kOneStep / 2;

#if FDSURF_DEVICE_PLANNER
template <int kDims>
void CopyGeometry(const PatchGeometry1 (&from)[protocol::kMaxAxes], PatchGeometry1 (&to)[kDims]) {
  for (int c = 0; c < kDims; ++c) to[c] = from[c];
}

template <int kDims>
void CopyGeometry(const CurveGeometry1 (&from)[protocol::kMaxAxes], CurveGeometry1 (&to)[kDims]) {
  for (int c = 0; c < kDims; ++c) to[c] = from[c];
}

#endif  // FDSURF_DEVICE_PLANNER
// 3·low and 3·high: a value in [−1/2, T + 1/2) rounds into [0, T].
constexpr int64_t kLow3 = -3 * kHalfStep;
int64_t High3(int32_t travel) { return 3 * (static_cast<int64_t>(travel) * kOneStep + kHalfStep); }

enum class Hull : uint8_t { kInside, kOutside, kCrossing };

// The travel check's numbers (docs/motion.md, "Validation on arrival") are
// held offset by 2^62 in uint64: every value is below 2^61 in magnitude, so
// an offset value is in [2^61, 3·2^61), a sum of two does not wrap, and a
// shift right by one halves the value and the offset alike (both rounded
// down), with no signed shift.
constexpr uint64_t kHullOffset = uint64_t{1} << 62;
constexpr uint64_t kHullLimit = uint64_t{1} << 61;

// 3·b_i, the Bernstein coefficients times 3 (integers): 3d, 3d + c,
// 3d + 2c + b, 3(a + b + c + d); below 2^53 for coefficients below 2^49.
// Out of line on AVR: the hull test and the halving's set-up share it.
FDSURF_OUT_OF_LINE_ON_AVR void BernsteinTimes3(const int64_t (&k)[4], int64_t (&b3)[4]) {
  b3[0] = 3 * k[3];
  b3[1] = b3[0] + k[2];
  b3[2] = b3[1] + k[2] + k[1];
  b3[3] = 3 * (k[0] + k[1] + k[2] + k[3]);
}

uint64_t Offset(int64_t value, int shift) {
  return kHullOffset + (static_cast<uint64_t>(value) << shift);  // two's complement: exact
}

#if FDSURF_DEVICE_WIDE_TABLES
// The piece's classification against [low3, high3), each of its
// coefficients within `slack` of the exact one: inside when every exact
// coefficient is, outside when an end (a point of the curve) is.
Hull Classify(const uint64_t (&hull)[4], uint64_t low3, uint64_t high3, uint64_t slack) {
  const auto outside = [&](uint64_t end) { return end + slack < low3 || end >= high3 + slack; };
  if (outside(hull[0]) || outside(hull[3])) return Hull::kOutside;
  for (const uint64_t value : hull) {
    if (value < low3 + slack || value + slack >= high3) return Hull::kCrossing;
  }
  return Hull::kInside;
}
#endif  // FDSURF_DEVICE_WIDE_TABLES

}  // namespace

namespace internal {

void KeepHalfOfHull(uint64_t (&hull)[4], bool right) {
  // de Casteljau at s = 1/2; each average rounds down by at most half a unit,
  // and an average of values within e of theirs is within e + 1/2: the three
  // rounds leave every coefficient within e + 3/2.
  const uint64_t m01 = (hull[0] + hull[1]) >> 1;
  const uint64_t m12 = (hull[1] + hull[2]) >> 1;
  const uint64_t m23 = (hull[2] + hull[3]) >> 1;
  const uint64_t m012 = (m01 + m12) >> 1;
  const uint64_t m123 = (m12 + m23) >> 1;
  const uint64_t middle = (m012 + m123) >> 1;
  if (right) {
    hull[0] = middle;
    hull[1] = m123;
    hull[2] = m23;
  } else {
    hull[1] = m01;
    hull[2] = m012;
    hull[3] = middle;
  }
}

int TravelHullOf(const int64_t (&k)[4], int32_t travel, uint64_t (&hull)[4], uint64_t* low3,
                 uint64_t* high3) {
  int64_t b3[4];
  BernsteinTimes3(k, b3);
  const int64_t ends[2] = {kLow3, High3(travel)};
  uint64_t largest = 0;
  for (const int64_t value : b3) largest |= fdsurf::internal::Magnitude(value);
  for (const int64_t value : ends) largest |= fdsurf::internal::Magnitude(value);
  int shift = 0;
  while ((largest << 1) < kHullLimit) {  // as many fraction bits as fit
    largest <<= 1;
    ++shift;
  }
  for (int i = 0; i < 4; ++i) hull[i] = Offset(b3[i], shift);
  *low3 = Offset(ends[0], shift);
  *high3 = Offset(ends[1], shift);
  return shift;
}

}  // namespace internal

namespace {

#if FDSURF_DEVICE_WIDE_TABLES
// Whether the cubic a·u³ + b·u² + c·u + d (2^-16 steps) stays in
// [−1/2, T + 1/2) for u ∈ [0, 1]. Pieces are taken left to right; one whose
// hull crosses the boundary is halved, one whose hull is inside is done, and
// one whose end (a point of the curve) is outside refuses the line. A piece
// is formed from the whole line by its halvings, rounded down, so each
// coefficient at depth k is within 3k/2 units of the exact one (at most 30
// units of 2^-(16+shift)/3 step, shift ≥ 8): the tests allow that much, so
// nothing is accepted that leaves the travel. A piece still crossing at
// kHullMaxDepth, or a line needing more than kHullTestBudget tests, is
// refused too (*undecided). 64-bit: no wide integers, O(1) memory.
bool AxisWithinTravel(const int64_t (&k)[4], int32_t travel, ValidationWork* work,
                      bool* undecided) {
  uint64_t whole[4];
  uint64_t low3 = 0;
  uint64_t high3 = 0;
  internal::TravelHullOf(k, travel, whole, &low3, &high3);
  uint64_t hull[4] = {whole[0], whole[1], whole[2], whole[3]};
  uint32_t j = 0;  // the piece [j·2^-depth, (j + 1)·2^-depth]
  int depth = 0;
  for (uint16_t tests = 0;; ++tests) {
    if (tests == kHullTestBudget) {
      *undecided = true;
      return false;
    }
    if (work != nullptr) ++work->hull_tests;
    const Hull verdict = Classify(hull, low3, high3, (3u * depth + 1) / 2);
    if (verdict == Hull::kOutside) return false;
    if (verdict == Hull::kCrossing) {
      if (depth == kHullMaxDepth) {
        *undecided = true;
        return false;
      }
      internal::KeepHalfOfHull(hull, false);
      ++depth;
      j <<= 1;
      continue;
    }
    ++j;  // the next piece: up while it is the right end of its parent
    while (depth > 0 && (j & 1u) == 0) {
      j >>= 1;
      --depth;
    }
    if (depth == 0) return true;
    for (int i = 0; i < 4; ++i) hull[i] = whole[i];
    for (int bit = depth - 1; bit >= 0; --bit)
      internal::KeepHalfOfHull(hull, ((j >> bit) & 1u) != 0);
  }
}
#endif  // FDSURF_DEVICE_WIDE_TABLES

// The travel check's first test, on one axis: the curve stays in the convex
// hull of its Bernstein coefficients b0..b3, and a value in [−1/2, T + 1/2)
// rounds into [0, T]; tested as 3·b_i, which are integers: 3d, 3d + c,
// 3d + 2c + b, 3(a + b + c + d). Coefficients are below 2^49 (the planner
// checked), so nothing overflows. *end_outside: an end (a point of the
// curve) is outside, so the curve is.
bool AxisHullWithinTravel(const int64_t (&k)[4], int32_t travel, bool* end_outside) {
  int64_t hull[4];
  BernsteinTimes3(k, hull);
  const int64_t high3 = High3(travel);
  bool inside = true;
  *end_outside = false;
  for (int i = 0; i < 4; ++i) {
    const bool outside = hull[i] < kLow3 || hull[i] >= high3;
    inside = inside && !outside;
    *end_outside = *end_outside || (outside && (i == 0 || i == 3));
  }
  return inside;
}

// Whether every point the stepper can emit for this curve lies in
// [0, travel] on every axis. Almost every line passes the hull test at
// once. An axis whose hull crosses the boundary is decided by
// AxisWithinTravel; a device of 64-bit tables refuses it instead, as
// undecided unless an end is outside (its host splits such lines:
// HullWithinTravel).
template <int kDims>
bool WithinTravel(const PowerCurve1 (&curve)[kDims], const int32_t* travel, uint8_t* detail,
                  ValidationWork* work) {
  for (int c = 0; c < kDims; ++c) {
    bool end_outside = false;
    if (AxisHullWithinTravel(curve[c].c, travel[c], &end_outside)) continue;
#if FDSURF_DEVICE_WIDE_TABLES
    (void)end_outside;
    bool undecided = false;
    if (!AxisWithinTravel(curve[c].c, travel[c], work, &undecided)) {
      *detail = static_cast<uint8_t>(c | (undecided ? kUndecidedTravel : 0));
      return false;
    }
#else
    (void)work;
    *detail = static_cast<uint8_t>(c | (end_outside ? 0 : kUndecidedTravel));
    return false;
#endif
  }
  return true;
}

// The step-exact settings of every path the device steps.
AdaptiveSettings StepExactSettings(uint32_t tolerance_q8) {
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = tolerance_q8;
  return settings;
}

// The table entries of the lines this device steps (FDSURF_DEVICE_WIDE_TABLES).
#if FDSURF_DEVICE_WIDE_TABLES
using TableEntry = Int128;
#else
using TableEntry = int64_t;
#endif

// Sets up a line (relative to its first point) the way execution will: by
// the planner, or, for a PREPARED_CURVE (level ≥ 0), by checking the host's
// level.
template <int kDims>
Status PrepareLine(const PowerCurve1 (&relative)[kDims], uint32_t tolerance_q8, int host_level,
                   PreparedAdaptiveCurve<kDims, TableEntry>* prepared) {
  const AdaptiveSettings settings = StepExactSettings(tolerance_q8);
#if FDSURF_DEVICE_PLANNER
  if (host_level < 0) return PrepareAdaptiveCurve(relative, settings, prepared);
#endif
  return PrepareAdaptiveCurveAtLevel(relative, host_level, settings, prepared);
}

// The planner (or, for a prepared curve, the check of the host's level) must
// accept the line as execution steps it (relative to its first point), and
// every point it will emit must lie within the travel. `curve` is made
// relative in place for the first check and restored for the second (whole
// steps taken off and added back: exact), so that a caller holding its own
// copy (a PREPARED_CURVE's, on the Uno's small stack) needs no second one.
template <int kDims>
ErrorCode CheckLineInPlace(PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8, int host_level,
                           const protocol::MachineConfig& config, uint8_t* detail,
                           ValidationWork* work) {
  int32_t first[kDims];
  RelativeToFirstPoint(curve, curve, first);
  if (work != nullptr) ++(host_level < 0 ? work->lines : work->prepared_lines);
  Status status;
  {
    PreparedAdaptiveCurve<kDims, TableEntry> prepared;
    status = PrepareLine(curve, tolerance_q8, host_level, &prepared);
  }
  for (int c = 0; c < kDims; ++c) curve[c].c[3] += static_cast<int64_t>(first[c]) * kOneStep;
  if (status != Status::kOk) {
    *detail = static_cast<uint8_t>(status);
    return ErrorCode::kPlannerRefused;
  }
  return WithinTravel(curve, config.travel_steps, detail, work) ? ErrorCode::kNone
                                                                : ErrorCode::kOutOfTravel;
}

// The curves' checks are out of line on AVR, so that their locals (the
// coefficients) do not sit in ValidateCommand's frame under a PATCH's deeper
// validation. The ATmega2560 board must keep 256 bytes of RAM the stack
// never reaches (boards/mega2560-ramps/README.md); by -fstack-usage the
// PATCH path's frames here are 34 + 866 + 244 bytes this way, 152 + 866 +
// 244 with the cases inline (and 1,205 before PREPARED_CURVE).
template <int kDims>
FDSURF_OUT_OF_LINE_ON_AVR ErrorCode CheckPreparedCurve(const protocol::PreparedCurveCommand& curve,
                                                       const protocol::MachineConfig& config,
                                                       uint8_t* detail, ValidationWork* work) {
  if (curve.dims != kDims) return ErrorCode::kDimsMismatch;
  PowerCurve1 power[kDims];
  for (int c = 0; c < kDims; ++c) power[c] = curve.power[c];
  return CheckLineInPlace(power, curve.tolerance_q8, curve.level, config, detail, work);
}

#if FDSURF_DEVICE_PLANNER
template <int kDims>
FDSURF_OUT_OF_LINE_ON_AVR ErrorCode CheckCurve(const protocol::CurveCommand& curve,
                                               const protocol::MachineConfig& config,
                                               uint8_t* detail, ValidationWork* work) {
  if (curve.dims != kDims) return ErrorCode::kDimsMismatch;
  CurveGeometry1 geometry[kDims];
  CopyGeometry(curve.geometry, geometry);
  PowerCurve1 power[kDims];
  const Status status = CurvePowerCoefficients(geometry, curve.basis, power);
  if (status != Status::kOk) {
    *detail = static_cast<uint8_t>(status);
    return ErrorCode::kPlannerRefused;
  }
  return CheckLineInPlace(power, curve.tolerance_q8, kPlannerLevel, config, detail, work);
}

template <int kDims>
ErrorCode CheckFamily(const protocol::PatchCommand& patch, IsolineFamily family,
                      const protocol::MachineConfig& config, uint8_t* detail,
                      ValidationWork* work) {
  ErrorCode error = ErrorCode::kNone;
  const Status walked =
      ForEachDrawnLine<kDims>(patch, family, [&](const PowerCurve1(&curve)[kDims]) {
        PowerCurve1 line[kDims];
        for (int c = 0; c < kDims; ++c) line[c] = curve[c];
        error = CheckLineInPlace(line, patch.tolerance_q8, kPlannerLevel, config, detail, work);
        return error == ErrorCode::kNone;
      });
  if (walked != Status::kOk) {
    *detail = static_cast<uint8_t>(walked);
    return ErrorCode::kPlannerRefused;
  }
  return error;
}

#endif  // FDSURF_DEVICE_PLANNER
}  // namespace

template <int kDims>
void ReverseCurve(PowerCurve1 (&curve)[kDims]) {
  // x(1 − u) = −a·u³ + (3a + b)·u² − (3a + 2b + c)·u + (a + b + c + d).
  for (int c = 0; c < kDims; ++c) {
    const int64_t a = curve[c].c[0];
    const int64_t b = curve[c].c[1];
    const int64_t cc = curve[c].c[2];
    const int64_t d = curve[c].c[3];
    curve[c].c[0] = -a;
    curve[c].c[1] = 3 * a + b;
    curve[c].c[2] = -(3 * a + 2 * b + cc);
    curve[c].c[3] = a + b + cc + d;
  }
}

template <int kDims>
bool HullWithinTravel(const PowerCurve1 (&curve)[kDims], const int32_t* travel) {
  for (int c = 0; c < kDims; ++c) {
    bool end_outside = false;
    if (!AxisHullWithinTravel(curve[c].c, travel[c], &end_outside)) return false;
  }
  return true;
}

template <int kDims>
void RelativeToFirstPoint(const PowerCurve1 (&curve)[kDims], PowerCurve1 (&relative)[kDims],
                          int32_t (&first)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    first[c] = RoundToQuanta(curve[c].c[3], kCoefficientFracBits);
    relative[c] = curve[c];
    relative[c].c[3] -= static_cast<int64_t>(first[c]) * kOneStep;
  }
}

namespace {

// One event of a DDA (StraightMoveCursor, ChordDda): each axis's remainder
// gains its increment and carries a step into the point when it leaves
// [0, modulus). The callers keep the point one step at most from the
// event's exact rounding, so one carry suffices. Whether any axis moved.
template <int kDims>
inline bool DdaEvent(int32_t (&remainder)[kDims], const int32_t (&increment)[kDims],
                     int32_t modulus, int32_t (&point)[kDims]) {
  bool moved = false;
  for (int c = 0; c < kDims; ++c) {
    remainder[c] += increment[c];
    if (remainder[c] >= modulus) {
      remainder[c] -= modulus;
      ++point[c];
      moved = true;
    } else if (remainder[c] < 0) {
      remainder[c] += modulus;
      --point[c];
      moved = true;
    }
  }
  return moved;
}

}  // namespace

template <int kDims>
void StraightMoveCursor<kDims>::Reset(const int32_t (&from)[kDims], const int32_t (&to)[kDims],
                                      int level) {
  modulus_ = int32_t{1} << (level + 1);
  for (int c = 0; c < kDims; ++c) {
    point_[c] = from[c];
    // (2·from + 1)·2^L over 2^(L+1) is from + 1/2: the rounding half.
    remainder_[c] = int32_t{1} << level;
    increment_[c] = 2 * (to[c] - from[c]);
  }
  remaining_ = uint32_t{1} << level;
  started_ = false;
}

template <int kDims>
bool StraightMoveCursor<kDims>::Next(int32_t (&point)[kDims]) {
  if (!started_) {
    started_ = true;
    for (int c = 0; c < kDims; ++c) point[c] = point_[c];
    return true;
  }
  while (remaining_ > 0) {
    --remaining_;
    if (DdaEvent(remainder_, increment_, modulus_, point_)) {
      for (int c = 0; c < kDims; ++c) point[c] = point_[c];
      return true;
    }
  }
  return false;
}

template <int kDims>
void ChordDda<kDims>::Start(const int32_t (&fine)[kDims], const int32_t (&point)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    fine_[c] = fine[c];
    point_[c] = point[c];
  }
  remaining_ = 0;
}

template <int kDims>
void ChordDda<kDims>::Chord(const int32_t (&fine)[kDims], bool finest) {
  uint32_t events = 1;
  for (int c = 0; c < kDims; ++c) {
    // The difference of two wrapped points is exact: a chord moves an axis
    // at most 2^8 steps (AdaptiveChordCursor), far below 2^31 / 2^8.
    increment_[c] =
        static_cast<int32_t>(static_cast<uint32_t>(fine[c]) - static_cast<uint32_t>(fine_[c]));
    const uint32_t magnitude =
        static_cast<uint32_t>(increment_[c] < 0 ? -increment_[c] : increment_[c]);
    const uint32_t needed = (magnitude + ((1u << kFineBits) - 1)) >> kFineBits;
    if (needed > events) events = needed;
  }
  if (finest) events = 1;
  modulus_ = static_cast<int32_t>(events << kFineBits);
  for (int c = 0; c < kDims; ++c) {
    // N·P − 2^8·N·floor(P / 2^8) = N·(P mod 2^8): the start's fraction, which
    // wrapping (by a multiple of 2^8) keeps.
    remainder_[c] = static_cast<int32_t>(events * (static_cast<uint32_t>(fine_[c]) & 0xFFu));
    fine_[c] = fine[c];
  }
  remaining_ = static_cast<uint16_t>(events);
}

template <int kDims>
bool ChordDda<kDims>::Next(int32_t (&point)[kDims]) {
  while (remaining_ > 0) {
    --remaining_;
    // |increment| ≤ modulus (≤ 2^8 per event), so at most one step; for a
    // finest step the ends are at most one step apart.
    if (DdaEvent(remainder_, increment_, modulus_, point_)) {
      for (int c = 0; c < kDims; ++c) point[c] = point_[c];
      return true;
    }
  }
  return false;
}

template <int kDims>
int StraightMoveLevel(const PowerCurve1 (&line)[kDims]) {
  uint64_t largest = 0;
  for (int c = 0; c < kDims; ++c) {
    const int64_t slope = line[c].c[2];
    const uint64_t magnitude =
        slope < 0 ? ~static_cast<uint64_t>(slope) + 1 : static_cast<uint64_t>(slope);
    if (magnitude > largest) largest = magnitude;
  }
  int level = 0;
  while (level < 63 - kCoefficientFracBits &&
         (uint64_t{1} << (kCoefficientFracBits + level)) < largest) {
    ++level;
  }
  return level;
}

template <int kDims>
bool TravelPlannable(const protocol::MachineConfig& config, uint8_t* axis) {
  for (int c = 0; c < kDims; ++c) {
    if (config.travel_steps[c] < 0 || config.travel_steps[c] > kMaxPlannableTravelSteps) {
      *axis = static_cast<uint8_t>(c);
      return false;
    }
  }
  return true;
}

template <int kDims>
ErrorCode ValidateCommand(const protocol::Command& command, const protocol::MachineConfig& config,
                          uint8_t* detail) {
  return ValidateCommand<kDims>(command, config, detail, nullptr);
}

// Every straight move execution makes (a MOVE, the travel before a line)
// goes from where the machine is to a point inside the travel. The machine
// is only ever where an accepted command took it, inside a travel of at most
// kMaxPlannableTravelSteps (TravelPlannable, also checked for each CONFIG),
// so the move is at most that long on every axis. StraightMoveCursor steps
// any such move in 32 bits (its values stay below 2^28), and the planner
// would accept it too (it is monotone in the coefficients' magnitudes;
// ValidateCommand.EveryMoveInsideTheLargestTravelIsPlannable checks the
// largest). So the start of a command needs no check of its own.
template <int kDims>
ErrorCode ValidateCommand(const protocol::Command& command, const protocol::MachineConfig& config,
                          uint8_t* detail, ValidationWork* work) {
  *detail = 0;
  if (command.type != MessageType::kConfig && !TravelPlannable<kDims>(config, detail)) {
    return ErrorCode::kOutOfTravel;
  }
  switch (command.type) {
#if FDSURF_DEVICE_PLANNER
    case MessageType::kPatch: {
      const protocol::PatchCommand& patch = command.body.patch;
      if (patch.dims != kDims) return ErrorCode::kDimsMismatch;
      const ErrorCode s_lines =
          CheckFamily<kDims>(patch, IsolineFamily::kSLines, config, detail, work);
      if (s_lines != ErrorCode::kNone) return s_lines;
      return CheckFamily<kDims>(patch, IsolineFamily::kTLines, config, detail, work);
    }
    case MessageType::kCurve:
      return CheckCurve<kDims>(command.body.curve, config, detail, work);
#endif  // FDSURF_DEVICE_PLANNER
    case MessageType::kPreparedCurve:
      return CheckPreparedCurve<kDims>(command.body.prepared_curve, config, detail, work);
    case MessageType::kMove:
      for (int c = 0; c < kDims; ++c) {
        const int32_t target = command.body.move.target[c];
        if (target < 0 || target > config.travel_steps[c]) {
          *detail = static_cast<uint8_t>(c);
          return ErrorCode::kOutOfTravel;
        }
      }
      return ErrorCode::kNone;
    default:
      return ErrorCode::kNone;
  }
}

template <int kDims>
void PathGenerator<kDims>::Reset(const int32_t* position, bool pen_down) {
  for (int c = 0; c < kDims; ++c) position_[c] = position[c];
  pen_down_ = pen_down;
  stage_ = Stage::kIdle;
  failed_ = false;
  failure_ = Status::kOk;
  pending_count_ = 0;
  pending_head_ = 0;
}

template <int kDims>
void PathGenerator<kDims>::Emit(uint8_t entry) {
  pending_[pending_count_++] = entry;
}

template <int kDims>
void PathGenerator<kDims>::Fail(Status status) {
  failed_ = true;
  failure_ = status;
  stage_ = Stage::kIdle;
  pending_count_ = 0;
  pending_head_ = 0;
}

template <int kDims>
bool PathGenerator<kDims>::PrepareInto(const PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8,
                                       int host_level) {
  PowerCurve1 relative[kDims];
  RelativeToFirstPoint(curve, relative, line_start_);
#if FDSURF_DEVICE_WIDE_TABLES
  PreparedAdaptiveCurve<kDims> prepared;
#else
  PreparedAdaptiveCurve<kDims, int64_t> prepared;
#endif
  const Status status = PrepareLine(relative, tolerance_q8, host_level, &prepared);
  if (status != Status::kOk) {
    Fail(status);
    return false;
  }
  // Chords within what the tolerance leaves after rounding, so that every
  // point stepped from them is within it (docs/motion.md).
  const int budget_bits = ChordBudgetBits(tolerance_q8, kDims);
#if FDSURF_DEVICE_WIDE_TABLES
  if (prepared.format.acc_bits != 64) {
    path_ = Path::kLine128;
    cursor128_.Reset(prepared, budget_bits);
  } else {
    path_ = Path::kLine64;
    cursor64_.Reset(prepared, budget_bits);
  }
#else
  path_ = Path::kLine64;
  cursor64_.Reset(prepared, budget_bits);
#endif
  // The first point: the relative line starts within half a step of 0, so
  // its fine value has not wrapped and rounds to 0.
  int32_t fine[kDims];
  bool finest = false;
  (void)NextChord(fine, &finest);
  int32_t origin[kDims];
  for (int c = 0; c < kDims; ++c)
    origin[c] = fine[c] >> AdaptiveChordCursor<int64_t, kDims>::kFineBits;
  dda_.Start(fine, origin);
  return true;
}

template <int kDims>
bool PathGenerator<kDims>::NextChord(int32_t (&fine)[kDims], bool* finest) {
#if FDSURF_DEVICE_WIDE_TABLES
  if (path_ == Path::kLine128) return cursor128_.Next(fine, finest);
#endif
  return cursor64_.Next(fine, finest);
}

template <int kDims>
void PathGenerator<kDims>::StartTravel(const int32_t (&target)[kDims]) {
  PowerCurve1 line[kDims];
  for (int c = 0; c < kDims; ++c) {
    line[c].c[0] = 0;
    line[c].c[1] = 0;
    line[c].c[2] = (static_cast<int64_t>(target[c]) - position_[c]) * kOneStep;
    line[c].c[3] = static_cast<int64_t>(position_[c]) * kOneStep;
  }
  path_ = Path::kStraight;
  straight_.Reset(position_, target, StraightMoveLevel(line));
}

template <int kDims>
void PathGenerator<kDims>::Start(const protocol::Command& command) {
  type_ = command.type;
  failed_ = false;
  pending_count_ = 0;
  pending_head_ = 0;
  switch (command.type) {
#if FDSURF_DEVICE_PLANNER
    case MessageType::kPatch: {
      patch_ = command.body.patch;
      tolerance_q8_ = patch_.tolerance_q8;
      host_level_ = kPlannerLevel;
      lift_for_travel_ = true;
      lines_t_ = patch_.lines_t;
      line_index_ = 0;
      PatchGeometry1 geometry[kDims];
      CopyGeometry(patch_.geometry, geometry);
      family_ = patch_.lines_s >= 2 ? IsolineFamily::kSLines : IsolineFamily::kTLines;
      const uint16_t lines = family_ == IsolineFamily::kSLines ? patch_.lines_s : lines_t_;
      const Status status =
          IsolineWalker<kDims>::Create(geometry, patch_.basis, family_, lines, &walker_);
      if (status != Status::kOk) {
        Fail(status);
        return;
      }
      stage_ = Stage::kPatchNextLine;
      return;
    }
    case MessageType::kCurve: {
      CurveGeometry1 geometry[kDims];
      CopyGeometry(command.body.curve.geometry, geometry);
      const Status status = CurvePowerCoefficients(geometry, command.body.curve.basis, line_);
      if (status != Status::kOk) {
        Fail(status);
        return;
      }
      tolerance_q8_ = command.body.curve.tolerance_q8;
      host_level_ = kPlannerLevel;
      lift_for_travel_ = false;
      stage_ = Stage::kLineStart;
      return;
    }
#endif  // FDSURF_DEVICE_PLANNER
    case MessageType::kPreparedCurve: {
      const protocol::PreparedCurveCommand& curve = command.body.prepared_curve;
      for (int c = 0; c < kDims; ++c) line_[c] = curve.power[c];
      tolerance_q8_ = curve.tolerance_q8;
      host_level_ = curve.level;
      lift_for_travel_ = false;
      stage_ = Stage::kLineStart;
      return;
    }
    case MessageType::kMove: {
      int32_t target[kDims];
      for (int c = 0; c < kDims; ++c) target[c] = command.body.move.target[c];
      lift_for_travel_ = false;
      after_stepping_ = Stage::kFinish;
      StartTravel(target);
      stage_ = Stage::kStepping;
      return;
    }
    case MessageType::kPen:
      lift_for_travel_ = false;
      if (command.body.pen.down != pen_down_) {
        pen_down_ = command.body.pen.down;
        Emit(MakeEntry(pen_down_ ? EntryKind::kPenDown : EntryKind::kPenUp));
      }
      stage_ = Stage::kFinish;
      return;
    default:
      // Configuration is applied by the device, not expanded here.
      stage_ = Stage::kFinish;
      return;
  }
}

template <int kDims>
bool PathGenerator<kDims>::NextPoint(int32_t (&point)[kDims]) {
  if (path_ == Path::kStraight) return straight_.Next(point);
  for (;;) {
    if (dda_.Next(point)) {
      for (int c = 0; c < kDims; ++c) point[c] += line_start_[c];
      return true;
    }
    int32_t fine[kDims];
    bool finest = false;
    if (!NextChord(fine, &finest)) return false;
    dda_.Chord(fine, finest);
  }
}

// One state machine over the stages of a command (stepping, next line,
// travel to the line's start, after travel, finish): longer than the
// project's 80 lines on purpose, since the stages hand over to each other
// through `stage_` and read best side by side, and the per-point case
// (kStepping) runs on every unit move without a further call.
template <int kDims>
bool PathGenerator<kDims>::Next(uint8_t* entry) {  // NOLINT(readability-function-size)
  for (;;) {
    if (pending_head_ < pending_count_) {
      *entry = pending_[pending_head_++];
      return true;
    }
    pending_count_ = 0;
    pending_head_ = 0;
    switch (stage_) {
      case Stage::kIdle:
        return false;
      case Stage::kStepping: {
        int32_t point[kDims];
        if (!NextPoint(point)) {
          stage_ = after_stepping_;
          continue;
        }
        int32_t delta[3] = {0, 0, 0};
        bool moved = false;
        for (int c = 0; c < kDims; ++c) {
          delta[c] = point[c] - position_[c];
          // Step-exact paths move at most one step per axis; the planner
          // proved it. Refuse rather than emit a jump if that ever broke.
          if (delta[c] > 1 || delta[c] < -1) {
            Fail(Status::kPrecisionUnreachable);
            return false;
          }
          moved = moved || delta[c] != 0;
          position_[c] = point[c];
        }
        if (!moved) continue;
        *entry = MakeMove(delta, kDims);
        return true;
      }
#if FDSURF_DEVICE_PLANNER
      case Stage::kPatchNextLine: {
        if (!walker_.Next(line_)) {
          if (family_ == IsolineFamily::kSLines && lines_t_ >= 2) {
            PatchGeometry1 geometry[kDims];
            CopyGeometry(patch_.geometry, geometry);
            family_ = IsolineFamily::kTLines;
            line_index_ = 0;
            const Status status =
                IsolineWalker<kDims>::Create(geometry, patch_.basis, family_, lines_t_, &walker_);
            if (status != Status::kOk) {
              Fail(status);
              return false;
            }
            continue;
          }
          stage_ = Stage::kFinish;
          continue;
        }
        const uint16_t index = line_index_++;
        // A line collapsed to a point (a pole) draws nothing; an edge another
        // patch draws is left to it.
        if (IsPoint(line_) || IsSkippedEdge(patch_.skip_lines, family_, index, walker_.lines()))
          continue;
        if ((index & 1u) != 0) ReverseCurve(line_);
        stage_ = Stage::kLineStart;
        continue;
      }
#else
      case Stage::kPatchNextLine:  // no PATCH is accepted without the planner
        stage_ = Stage::kFinish;
        continue;
#endif  // FDSURF_DEVICE_PLANNER
      case Stage::kLineStart: {
        bool there = true;
        for (int c = 0; c < kDims; ++c) {
          // The first point as the stepper will round it.
          line_start_[c] = RoundToQuanta(line_[c].c[3], kCoefficientFracBits);
          there = there && line_start_[c] == position_[c];
        }
        if (there) {
          stage_ = Stage::kAfterTravel;
          continue;
        }
        if (lift_for_travel_ && pen_down_) {
          pen_down_ = false;
          Emit(MakeEntry(EntryKind::kPenUp));
        }
        StartTravel(line_start_);
        after_stepping_ = Stage::kAfterTravel;
        stage_ = Stage::kStepping;
        continue;
      }
      case Stage::kAfterTravel: {
        if (lift_for_travel_ && !pen_down_) {
          pen_down_ = true;
          Emit(MakeEntry(EntryKind::kPenDown));
        }
        if (!PrepareInto(line_, tolerance_q8_, host_level_)) return false;
        after_stepping_ = type_ == MessageType::kPatch ? Stage::kPatchNextLine : Stage::kFinish;
        stage_ = Stage::kStepping;
        continue;
      }
      case Stage::kFinish:
        if (type_ == MessageType::kPatch && pen_down_) {
          pen_down_ = false;
          Emit(MakeEntry(EntryKind::kPenUp));
        }
        Emit(MakeEntry(EntryKind::kCommandDone));
        stage_ = Stage::kIdle;
        continue;
    }
  }
}

template void ReverseCurve<2>(PowerCurve1 (&)[2]);
template void ReverseCurve<3>(PowerCurve1 (&)[3]);
template void RelativeToFirstPoint<2>(const PowerCurve1 (&)[2], PowerCurve1 (&)[2], int32_t (&)[2]);
template void RelativeToFirstPoint<3>(const PowerCurve1 (&)[3], PowerCurve1 (&)[3], int32_t (&)[3]);
template bool HullWithinTravel<2>(const PowerCurve1 (&)[2], const int32_t*);
template bool HullWithinTravel<3>(const PowerCurve1 (&)[3], const int32_t*);
template class StraightMoveCursor<2>;
template class ChordDda<2>;
template class ChordDda<3>;
template class StraightMoveCursor<3>;
template int StraightMoveLevel<2>(const PowerCurve1 (&)[2]);
template int StraightMoveLevel<3>(const PowerCurve1 (&)[3]);
template bool TravelPlannable<2>(const protocol::MachineConfig&, uint8_t*);
template bool TravelPlannable<3>(const protocol::MachineConfig&, uint8_t*);
template ErrorCode ValidateCommand<2>(const protocol::Command&, const protocol::MachineConfig&,
                                      uint8_t*);
template ErrorCode ValidateCommand<3>(const protocol::Command&, const protocol::MachineConfig&,
                                      uint8_t*);
template ErrorCode ValidateCommand<2>(const protocol::Command&, const protocol::MachineConfig&,
                                      uint8_t*, ValidationWork*);
template ErrorCode ValidateCommand<3>(const protocol::Command&, const protocol::MachineConfig&,
                                      uint8_t*, ValidationWork*);
template class PathGenerator<2>;
template class PathGenerator<3>;

}  // namespace motion
}  // namespace fdsurf
