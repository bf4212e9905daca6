// SPDX-License-Identifier: MIT
#include "fdsurf/motion/path_generator.h"

namespace fdsurf {
namespace motion {
namespace {

using protocol::ErrorCode;
using protocol::MessageType;

constexpr int64_t kOneStep = int64_t{1} << kCoefficientFracBits;
constexpr int64_t kHalfStep = kOneStep / 2;

template <int kDims>
void CopyGeometry(const PatchGeometry1 (&from)[protocol::kMaxAxes], PatchGeometry1 (&to)[kDims]) {
  for (int c = 0; c < kDims; ++c) to[c] = from[c];
}

template <int kDims>
void CopyGeometry(const CurveGeometry1 (&from)[protocol::kMaxAxes], CurveGeometry1 (&to)[kDims]) {
  for (int c = 0; c < kDims; ++c) to[c] = from[c];
}

// Whether line `index` of `lines` in a family is an edge the command says
// another patch draws.
bool Skipped(uint8_t skip_lines, IsolineFamily family, uint16_t index, uint16_t lines) {
  const uint8_t first =
      family == IsolineFamily::kSLines ? protocol::kSkipFirstSLine : protocol::kSkipFirstTLine;
  const uint8_t last =
      family == IsolineFamily::kSLines ? protocol::kSkipLastSLine : protocol::kSkipLastTLine;
  return (index == 0 && (skip_lines & first) != 0) ||
         (index + 1u == lines && (skip_lines & last) != 0);
}

template <int kDims>
bool IsPoint(const PowerCurve1 (&curve)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    if (curve[c].c[0] != 0 || curve[c].c[1] != 0 || curve[c].c[2] != 0) return false;
  }
  return true;
}

// Whether every point the stepper can emit for this curve surely lies in
// [0, travel] on every axis: the curve stays in the convex hull of its
// Bernstein coefficients b0..b3, and a value in [−1/2, T + 1/2) rounds into
// [0, T]. Tested as 3·b_i, which are integers: 3d, 3d + c, 3d + 2c + b,
// 3(a + b + c + d). Coefficients are below 2^54, so nothing overflows.
template <int kDims>
bool WithinTravel(const PowerCurve1 (&curve)[kDims], const int32_t* travel, uint8_t* axis) {
  for (int c = 0; c < kDims; ++c) {
    const int64_t a = curve[c].c[0];
    const int64_t b = curve[c].c[1];
    const int64_t cc = curve[c].c[2];
    const int64_t d = curve[c].c[3];
    const int64_t hull[4] = {3 * d, 3 * d + cc, 3 * d + 2 * cc + b, 3 * (a + b + cc + d)};
    const int64_t low = -3 * kHalfStep;
    const int64_t high = 3 * (static_cast<int64_t>(travel[c]) * kOneStep + kHalfStep);
    for (const int64_t value : hull) {
      if (value < low || value >= high) {
        *axis = static_cast<uint8_t>(c);
        return false;
      }
    }
  }
  return true;
}

// Steps the prepared curve exactly as execution will, checking every point.
template <typename Acc, int kDims>
bool PointsWithinTravel(const PreparedAdaptiveCurve<kDims>& prepared, const int32_t* travel,
                        uint8_t* axis) {
  AdaptiveCurveCursor<Acc, kDims> cursor(prepared);
  int32_t point[kDims];
  uint32_t position = 0;
  while (cursor.Next(point, &position)) {
    for (int c = 0; c < kDims; ++c) {
      if (point[c] < 0 || point[c] > travel[c]) {
        *axis = static_cast<uint8_t>(c);
        return false;
      }
    }
  }
  return true;
}

// The planner must accept the line, and every point it will emit must lie
// within the travel: the hull test decides at once for almost every line;
// a line whose hull crosses the boundary is stepped through to decide.
template <int kDims>
ErrorCode CheckLine(const PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8,
                    const protocol::MachineConfig& config, uint8_t* detail) {
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = tolerance_q8;
  PreparedAdaptiveCurve<kDims> prepared;
  const Status status = PrepareAdaptiveCurve(curve, settings, &prepared);
  if (status != Status::kOk) {
    *detail = static_cast<uint8_t>(status);
    return ErrorCode::kPlannerRefused;
  }
  if (WithinTravel(curve, config.travel_steps, detail)) return ErrorCode::kNone;
  const bool inside = prepared.format.acc_bits == 64
                          ? PointsWithinTravel<int64_t>(prepared, config.travel_steps, detail)
                          : PointsWithinTravel<Int128>(prepared, config.travel_steps, detail);
  return inside ? ErrorCode::kNone : ErrorCode::kOutOfTravel;
}

template <int kDims>
ErrorCode CheckFamily(const PatchGeometry1 (&geometry)[kDims], const protocol::PatchCommand& patch,
                      IsolineFamily family, uint16_t lines, const protocol::MachineConfig& config,
                      uint8_t* detail) {
  if (lines == 0) return ErrorCode::kNone;
  IsolineWalker<kDims> walker;
  const Status created =
      IsolineWalker<kDims>::Create(geometry, patch.basis, family, lines, &walker);
  if (created != Status::kOk) {
    *detail = static_cast<uint8_t>(created);
    return ErrorCode::kPlannerRefused;
  }
  PowerCurve1 curve[kDims];
  for (uint16_t index = 0; walker.Next(curve); ++index) {
    if (IsPoint(curve) || Skipped(patch.skip_lines, family, index, lines)) continue;  // not drawn
    if ((index & 1u) != 0) ReverseCurve(curve);
    const ErrorCode error = CheckLine(curve, patch.tolerance_q8, config, detail);
    if (error != ErrorCode::kNone) return error;
  }
  return ErrorCode::kNone;
}

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
ErrorCode ValidateCommand(const protocol::Command& command, const protocol::MachineConfig& config,
                          uint8_t* detail) {
  *detail = 0;
  switch (command.type) {
    case MessageType::kPatch: {
      const protocol::PatchCommand& patch = command.body.patch;
      if (patch.dims != kDims) return ErrorCode::kDimsMismatch;
      PatchGeometry1 geometry[kDims];
      CopyGeometry(patch.geometry, geometry);
      const ErrorCode s_lines =
          CheckFamily(geometry, patch, IsolineFamily::kSLines, patch.lines_s, config, detail);
      if (s_lines != ErrorCode::kNone) return s_lines;
      return CheckFamily(geometry, patch, IsolineFamily::kTLines, patch.lines_t, config, detail);
    }
    case MessageType::kCurve: {
      const protocol::CurveCommand& curve = command.body.curve;
      if (curve.dims != kDims) return ErrorCode::kDimsMismatch;
      CurveGeometry1 geometry[kDims];
      CopyGeometry(curve.geometry, geometry);
      PowerCurve1 power[kDims];
      const Status status = CurvePowerCoefficients(geometry, curve.basis, power);
      if (status != Status::kOk) {
        *detail = static_cast<uint8_t>(status);
        return ErrorCode::kPlannerRefused;
      }
      return CheckLine(power, curve.tolerance_q8, config, detail);
    }
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
bool PathGenerator<kDims>::PrepareInto(const PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8) {
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = tolerance_q8;
  const Status status = PrepareAdaptiveCurve(curve, settings, &prepared_);
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
  return PrepareInto(line, kLineToleranceQ8);
}

template <int kDims>
void PathGenerator<kDims>::Start(const protocol::Command& command) {
  type_ = command.type;
  failed_ = false;
  pending_count_ = 0;
  pending_head_ = 0;
  switch (command.type) {
    case MessageType::kPatch: {
      patch_ = command.body.patch;
      tolerance_q8_ = patch_.tolerance_q8;
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
        if (IsPoint(line_) || Skipped(patch_.skip_lines, family_, index, walker_.lines())) continue;
        if ((index & 1u) != 0) ReverseCurve(line_);
        stage_ = Stage::kLineStart;
        continue;
      }
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
        if (!PrepareInto(line_, tolerance_q8_)) return false;
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
template ErrorCode ValidateCommand<2>(const protocol::Command&, const protocol::MachineConfig&,
                                      uint8_t*);
template ErrorCode ValidateCommand<3>(const protocol::Command&, const protocol::MachineConfig&,
                                      uint8_t*);
template class PathGenerator<2>;
template class PathGenerator<3>;

}  // namespace motion
}  // namespace fdsurf
