// SPDX-License-Identifier: MIT
#include "fdsurf/motion/path_generator.h"

namespace fdsurf {
namespace motion {
namespace {

using internal::Widen;
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

// The cubic A·s³ + B·s² + C·s + D of one piece [j·2^-k, (j+1)·2^-k] of a
// line's axis, in the piece's own parameter s ∈ [0, 1], in units of
// 2^-(16+3k) steps: every coefficient is an integer, and every move between
// neighbouring pieces is additions and exact shifts.
struct Piece {
  Int128 a, b, c, d;
};

enum class Hull : uint8_t { kInside, kOutside, kCrossing };

bool InRange(const Int128& value, const Int128& low3, const Int128& high3) {
  return low3 <= value && !(high3 <= value);
}

// The piece's Bernstein coefficients, times 3: 3D, 3D + C, 3D + 2C + B,
// 3(A + B + C + D). The first and last are points of the curve: outside
// means the line leaves the travel.
Hull Classify(const Piece& p, const Int128& low3, const Int128& high3) {
  const Int128 d3 = p.d + p.d + p.d;
  const Int128 sum = p.a + p.b + p.c + p.d;
  if (!InRange(d3, low3, high3) || !InRange(sum + sum + sum, low3, high3)) return Hull::kOutside;
  const Int128 h1 = d3 + p.c;
  return InRange(h1, low3, high3) && InRange(h1 + p.c + p.b, low3, high3) ? Hull::kInside
                                                                          : Hull::kCrossing;
}

// The left half, rescaled: p(s/2)·8 = A, 2B, 4C, 8D.
void ToLeftHalf(Piece* p) {
  p->b = internal::ShiftLeft(p->b, 1);
  p->c = internal::ShiftLeft(p->c, 2);
  p->d = internal::ShiftLeft(p->d, 3);
}

// From a left half to its right neighbour at the same scale: p(s + 1).
void ToRightNeighbour(Piece* p) {
  const Int128 a3 = p->a + p->a + p->a;
  p->d = p->d + p->c + p->b + p->a;
  p->c = p->c + p->b + p->b + a3;
  p->b = p->b + a3;
}

// From a right half back to the whole piece it is half of: p(s − 1) is the
// left half, and the left half divided back (exactly: it was multiplied).
void ToParent(Piece* p) {
  const Int128 a3 = p->a + p->a + p->a;
  p->d = p->d - p->c + p->b - p->a;
  p->c = p->c - p->b - p->b + a3;
  p->b = p->b - a3;
  p->b = internal::ShiftRightArithmetic(p->b, 1);
  p->c = internal::ShiftRightArithmetic(p->c, 2);
  p->d = internal::ShiftRightArithmetic(p->d, 3);
}

// Whether the cubic a·u³ + b·u² + c·u + d (2^-16 steps) stays in
// [−1/2, T + 1/2) for u ∈ [0, 1]: pieces whose hull crosses the boundary are
// halved, depth first, in exact integers, until every hull is inside
// (accepted) or a curve point is outside (refused: exact). A piece still
// crossing at kHullMaxDepth, or a line needing more than kHullTestBudget
// tests, is refused too (*undecided): never accepted unless proven inside.
// Coefficients below 2^49 times 8^20 stay below 2^113: no overflow.
bool AxisWithinTravel(const int64_t (&k)[4], int32_t travel, ValidationWork* work,
                      bool* undecided) {
  Piece p{Widen(k[0]), Widen(k[1]), Widen(k[2]), Widen(k[3])};
  Int128 low3 = Widen(kLow3);
  Int128 high3 = Widen(High3(travel));
  uint32_t j = 0;
  int depth = 0;
  for (uint16_t tests = 0;; ++tests) {
    if (tests == kHullTestBudget) {
      *undecided = true;
      return false;
    }
    if (work != nullptr) ++work->hull_tests;
    const Hull hull = Classify(p, low3, high3);
    if (hull == Hull::kOutside) return false;
    if (hull == Hull::kCrossing) {
      if (depth == kHullMaxDepth) {
        *undecided = true;
        return false;
      }
      ToLeftHalf(&p);
      low3 = internal::ShiftLeft(low3, 3);
      high3 = internal::ShiftLeft(high3, 3);
      ++depth;
      j <<= 1;
      continue;
    }
    while ((j & 1u) != 0) {  // a right half is done: so is its parent
      ToParent(&p);
      low3 = internal::ShiftRightArithmetic(low3, 3);
      high3 = internal::ShiftRightArithmetic(high3, 3);
      --depth;
      j >>= 1;
    }
    if (depth == 0) return true;
    ToRightNeighbour(&p);
    ++j;
  }
}

// Whether every point the stepper can emit for this curve lies in
// [0, travel] on every axis. The curve stays in the convex hull of its
// Bernstein coefficients b0..b3, and a value in [−1/2, T + 1/2) rounds into
// [0, T]; tested as 3·b_i, which are integers: 3d, 3d + c, 3d + 2c + b,
// 3(a + b + c + d). Almost every line passes this at once; an axis whose
// hull crosses the boundary is decided by AxisWithinTravel. Coefficients
// are below 2^49 (the planner checked), so nothing overflows.
template <int kDims>
bool WithinTravel(const PowerCurve1 (&curve)[kDims], const int32_t* travel, uint8_t* detail,
                  ValidationWork* work) {
  for (int c = 0; c < kDims; ++c) {
    const int64_t(&k)[4] = curve[c].c;
    const int64_t hull[4] = {3 * k[3], 3 * k[3] + k[2], 3 * k[3] + 2 * k[2] + k[1],
                             3 * (k[0] + k[1] + k[2] + k[3])};
    bool crossing = false;
    for (const int64_t value : hull)
      crossing = crossing || value < kLow3 || value >= High3(travel[c]);
    if (!crossing) continue;
    bool undecided = false;
    if (!AxisWithinTravel(k, travel[c], work, &undecided)) {
      *detail = static_cast<uint8_t>(c | (undecided ? kUndecidedTravel : 0));
      return false;
    }
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

// Sets up a line the way execution will: by the planner, or, for a
// PREPARED_CURVE (level ≥ 0), by checking the host's level.
template <int kDims>
Status PrepareLine(const PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8, int host_level,
                   PreparedAdaptiveCurve<kDims>* prepared) {
  const AdaptiveSettings settings = StepExactSettings(tolerance_q8);
#if FDSURF_DEVICE_PLANNER
  if (host_level < 0) return PrepareAdaptiveCurve(curve, settings, prepared);
#endif
  return PrepareAdaptiveCurveAtLevel(curve, host_level, settings, prepared);
}

// The planner (or, for a prepared curve, the check of the host's level) must
// accept the line, and every point it will emit must lie within the travel.
template <int kDims>
ErrorCode CheckLine(const PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8, int host_level,
                    const protocol::MachineConfig& config, uint8_t* detail, ValidationWork* work) {
  PreparedAdaptiveCurve<kDims> prepared;
  if (work != nullptr) ++work->lines;
  const Status status = PrepareLine(curve, tolerance_q8, host_level, &prepared);
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
  return CheckLine(power, curve.tolerance_q8, curve.level, config, detail, work);
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
  return CheckLine(power, curve.tolerance_q8, kPlannerLevel, config, detail, work);
}

template <int kDims>
ErrorCode CheckFamily(const protocol::PatchCommand& patch, IsolineFamily family,
                      const protocol::MachineConfig& config, uint8_t* detail,
                      ValidationWork* work) {
  ErrorCode error = ErrorCode::kNone;
  const Status walked =
      ForEachDrawnLine<kDims>(patch, family, [&](const PowerCurve1(&curve)[kDims]) {
        error = CheckLine(curve, patch.tolerance_q8, kPlannerLevel, config, detail, work);
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
// so the move's coefficients are at most that on every axis, and the planner
// accepts every such line (it is monotone in the coefficients' magnitudes;
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
  const Status status = PrepareLine(curve, tolerance_q8, host_level, &prepared_);
  if (status != Status::kOk) {
    Fail(status);
    return false;
  }
  cursor_wide_ = prepared_.format.acc_bits != 64;
  if (cursor_wide_) {
    cursor128_.Reset(prepared_);
  } else {
    cursor64_.Reset(prepared_);
  }
  return true;
}

template <int kDims>
bool PathGenerator<kDims>::StartTravel(const int32_t (&target)[kDims]) {
  PowerCurve1 line[kDims];
  for (int c = 0; c < kDims; ++c) {
    line[c].c[0] = 0;
    line[c].c[1] = 0;
    line[c].c[2] = (static_cast<int64_t>(target[c]) - position_[c]) * kOneStep;
    line[c].c[3] = static_cast<int64_t>(position_[c]) * kOneStep;
  }
  return PrepareInto(line, kLineToleranceQ8, StraightMoveLevel(line));
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
      stage_ = StartTravel(target) ? Stage::kStepping : Stage::kIdle;
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
  uint32_t position = 0;
  return cursor_wide_ ? cursor128_.Next(point, &position) : cursor64_.Next(point, &position);
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
        if (!StartTravel(line_start_)) return false;
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
