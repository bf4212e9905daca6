// SPDX-License-Identifier: MIT
// Expands queued commands (patches, curves, straight moves, pen changes) into
// the motion loop's entries: unit moves and pen events.
//
// A line is prepared as a step-exact adaptive table (fdsurf/adaptive.h,
// AdaptiveMode::kStepExact; what the validation on arrival checked), walked
// in chords within a budget of the curve (AdaptiveChordCursor), and each
// chord cut into unit moves by a DDA (ChordDda): consecutive points differ
// by at most one step per axis, and every point is within the command's
// tolerance of the exact curve (docs/motion.md). A patch is drawn as isolines with
// the IsolineWalker: s-lines then t-lines, every other line reversed
// (serpentine) so that pen-up travel stays short; each line starts with a
// pen-up straight move to its first point when the pen is elsewhere. Straight
// moves are stepped by StraightMoveCursor, the same DDA: every point is a
// point of the exact line with its coordinates rounded.
#pragma once

#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/config/nodiscard.h"
#include "fdsurf/motion/entry.h"
#include "fdsurf/protocol/messages.h"

/// 1 (the default): the device steps a line with the 64-bit accumulator when
/// its table fits, else with Int128 (the planner's lines need it at page
/// scale). 0: 64-bit tables only, and no Int128 code, for small chips (the
/// Arduino Uno, issue 17); a PREPARED_CURVE whose table does not fit is
/// refused (kPlannerRefused, detail kPrecisionUnreachable), so its host
/// splits lines first (HELLO_REPLY's kFeature64BitTables says so). Needs
/// FDSURF_DEVICE_PLANNER=0: a device's planner cannot split a PATCH's lines.
#ifndef FDSURF_DEVICE_WIDE_TABLES
#define FDSURF_DEVICE_WIDE_TABLES 1
#endif
#if !FDSURF_DEVICE_WIDE_TABLES && FDSURF_DEVICE_PLANNER
#error "FDSURF_DEVICE_WIDE_TABLES=0 needs FDSURF_DEVICE_PLANNER=0"
#endif

namespace fdsurf {
namespace motion {

/// The tolerance used for straight moves, 2^-8 steps (a line has no chord
/// error; only the step-exact limit matters).
constexpr uint32_t kLineToleranceQ8 = 4 * 256;

/// The largest travel (steps, per axis) a configuration may have: every
/// straight move between two points of [0, 2^26] on every axis is planned
/// by the engine (a longer one needs more than 128-bit accumulators), so
/// with this cap no move execution makes can be refused.
constexpr int32_t kMaxPlannableTravelSteps = int32_t{1} << 26;

/// The travel check's bound per line and axis whose Bernstein hull crosses
/// the boundary: halvings at most kHullMaxDepth deep, at most kHullTestBudget
/// hull tests. A line that is not proven inside within it is refused with
/// detail = axis | kUndecidedTravel (docs/motion.md, "Validation on arrival").
/// A device of 64-bit tables does not halve: it refuses every line whose
/// hull crosses the boundary (HullWithinTravel), and its host splits them.
constexpr int kHullMaxDepth = 20;
constexpr uint16_t kHullTestBudget = 64;
constexpr uint8_t kUndecidedTravel = 0x80;

namespace internal {

/// The travel check's whole line, for one axis a·u³ + b·u² + c·u + d
/// (2^-16 steps, |coefficients| < 2^49) and travel T (≤ 2^26 steps): its
/// Bernstein coefficients times 3 and the ends 3·(−1/2), 3·(T + 1/2), each
/// times 2^shift and offset by 2^62 in uint64 (docs/motion.md, "Validation
/// on arrival"). Returns shift, the most that keeps the values' bitwise OR
/// (so each magnitude) below 2^61; at least 8.
int TravelHullOf(const int64_t (&k)[4], int32_t travel, uint64_t (&hull)[4], uint64_t* low3,
                 uint64_t* high3);

/// One de Casteljau halving of an offset hull: keeps the right half or the
/// left. Each average is rounded down, so a coefficient within e units of
/// the exact one's is within e + 3/2 of the half's.
void KeepHalfOfHull(uint64_t (&hull)[4], bool right);

}  // namespace internal

/// "The device's planner chooses the level" where a level may come from the
/// host (PREPARED_CURVE).
constexpr int8_t kPlannerLevel = -1;

/// Work done by ValidateCommand, counted for tests and cost models: lines
/// put through the planner, hull tests of the travel check's halving, and
/// lines whose level the host chose (PREPARED_CURVE: checked at that level,
/// several times cheaper than the planner's search).
struct ValidationWork {
  uint32_t lines;
  uint32_t hull_tests;
  uint32_t prepared_lines;
};

/// The finest level of a straight move `line` (c[0] = c[1] = 0): the
/// smallest L at which one step of 2^-L moves at most one step per axis,
/// |c| ≤ 2^(16+L). That is the level the planner chooses for a line (a line
/// has no second difference, so its chord test passes at every level), so
/// StraightMoveCursor steps moves at it, with the adaptive cursor's bits and
/// without the planner's search and wide integers.
template <int kDims>
int StraightMoveLevel(const PowerCurve1 (&line)[kDims]);

/// A line as the device steps it: relative to its first point, so that the
/// table's Δ⁰ holds the rounding of the start and not the machine's
/// position (a smaller table: the 64-bit accumulator takes more lines).
/// `first` = the first point rounded to steps, `relative` = the curve with
/// first·2^16 taken from its constant term. Each point of the relative line
/// plus `first` is the point of the line, bit for bit (round(x − k) =
/// round(x) − k for a whole k). `relative` may be `curve` (in place).
template <int kDims>
void RelativeToFirstPoint(const PowerCurve1 (&curve)[kDims], PowerCurve1 (&relative)[kDims],
                          int32_t (&first)[kDims]);

/// The travel check's first test: whether, on every axis, the Bernstein
/// hull of `curve` (2^-16 steps) lies in [−1/2, travel + 1/2), so that every
/// point the stepper emits is in [0, travel]. All a device of 64-bit tables
/// checks (FDSURF_DEVICE_WIDE_TABLES=0): a line that fails it is refused,
/// kOutOfTravel with detail axis | kUndecidedTravel unless an end of the
/// line is outside. So its host sends such a line in pieces that pass
/// (host::SplitForSixtyFourBitTables).
template <int kDims>
bool HullWithinTravel(const PowerCurve1 (&curve)[kDims], const int32_t* travel);

/// The points of a straight move from `from` to `to` (steps), exactly as
/// the adaptive cursor emits them for the move's line at its
/// StraightMoveLevel L: the distinct points round(from + (to − from)·j/2^L),
/// halves up, j = 0 .. 2^L (at that level no step can double, so the cursor
/// takes every j). Each is floor(((2·from + 1)·2^L + 2·(to − from)·j) /
/// 2^(L+1)), kept as the point and the remainder, so a j is one 32-bit
/// addition and comparison per axis: no shift, no wide integer, at any
/// length in the travel.
template <int kDims>
class StraightMoveCursor {
 public:
  /// Starts the move; `level` is StraightMoveLevel of its line, at most 29
  /// (a move within kMaxPlannableTravelSteps has at most 26), so that
  /// every value below stays within int32.
  void Reset(const int32_t (&from)[kDims], const int32_t (&to)[kDims], int level);
  /// The next point, the first one first; false after the last.
  bool Next(int32_t (&point)[kDims]);

 private:
  // The point and the remainder of the numerator above over 2^(L+1):
  // 0 ≤ remainder_ < modulus_ = 2^(L+1); each j adds 2·(to − from).
  int32_t point_[kDims] = {};
  int32_t remainder_[kDims] = {};
  int32_t increment_[kDims] = {};
  int32_t modulus_ = 2;
  uint32_t remaining_ = 0;  // values of j still to take
  bool started_ = false;
};

/// The unit moves of a line's chords (AdaptiveChordCursor, docs/motion.md,
/// "Path generation: chords"): a chord from P to Q, both in 2^-8 steps with
/// the rounding half in (floor((x + 1/2)·2^8), wrapping), is cut into N
/// events, N = ⌈max |Q − P| / 2^8⌉ (at least 1, and 1 for a finest step),
/// and event k lands on floor((P + k·(Q − P)/N) / 2^8): the exact chord point
/// rounded to steps. Kept as the point and the remainder of N·P + k·(Q − P)
/// over 2^8·N, so an event is one 32-bit addition and comparison per axis;
/// no axis moves more than one step in an event, and event N is Q rounded.
template <int kDims>
class ChordDda {
 public:
  /// Starts at `fine` (the cursor's first point) with the point `point`
  /// (steps): floor(fine / 2^8) where fine has not wrapped.
  void Start(const int32_t (&fine)[kDims], const int32_t (&point)[kDims]);
  /// Steps the chord from the last point given to `fine` next; `finest`:
  /// it is one finest step, taken as one event (its ends are within one
  /// step per axis, AdaptiveChordCursor).
  void Chord(const int32_t (&fine)[kDims], bool finest);
  /// The next point of the chord that differs from the one before; false
  /// when the chord is done.
  bool Next(int32_t (&point)[kDims]);

 private:
  static constexpr int kFineBits = 8;
  int32_t fine_[kDims] = {};  // where the next chord starts
  int32_t point_[kDims] = {};
  // 0 ≤ remainder_ < modulus_ = 2^8·N; each event adds increment_ = Q − P.
  int32_t remainder_[kDims] = {};
  int32_t increment_[kDims] = {};
  int32_t modulus_ = 1;
  uint16_t remaining_ = 0;  // events still to take
};

/// Whether every axis's travel is at most kMaxPlannableTravelSteps; *axis =
/// the first that is not.
template <int kDims>
bool TravelPlannable(const protocol::MachineConfig& config, uint8_t* axis);

/// Checks, before a command is queued, everything that could make it fail or
/// leave the machine's travel later: the engine's planner on every line it
/// will step (so execution never meets a refusal; the straight moves between
/// them are covered by kMaxPlannableTravelSteps), and that every point stays
/// within [0, travel_steps] on every axis: each line must stay in
/// [−1/2, travel + 1/2) on every axis, decided from its Bernstein hull,
/// halved in exact integers where it crosses, within a fixed bound per line.
/// Returns kNone, or kPlannerRefused with *detail = the fdsurf::Status,
/// kOutOfTravel with *detail = the axis (| kUndecidedTravel when the bound
/// ran out before deciding), kDimsMismatch. Worst case per frame: the
/// planner on each of lines_s + lines_t lines plus kDims·kHullTestBudget
/// hull tests each (docs/motion.md has it in cycles). `work`, if not null,
/// is incremented by the work done.
template <int kDims>
protocol::ErrorCode ValidateCommand(const protocol::Command& command,
                                    const protocol::MachineConfig& config, uint8_t* detail);
template <int kDims>
protocol::ErrorCode ValidateCommand(const protocol::Command& command,
                                    const protocol::MachineConfig& config, uint8_t* detail,
                                    ValidationWork* work);

/// Expands one command at a time into entries for the motion loop.
template <int kDims>
class PathGenerator {
 public:
  PathGenerator() = default;

  /// Sets where the machine is (steps) and the pen state; drops any command
  /// in progress.
  void Reset(const int32_t* position, bool pen_down);

  /// True when no command is being expanded and every entry was handed out.
  FDSURF_NODISCARD bool Idle() const {
    return stage_ == Stage::kIdle && pending_head_ >= pending_count_;
  }

  /// Starts expanding a validated motion command (patch, curve, move, pen).
  void Start(const protocol::Command& command);

  /// The next entry of the current command; the last one is kCommandDone.
  /// Returns false when idle. Returns false and sets failed() if the engine
  /// refuses a line (ValidateCommand rules that out).
  bool Next(uint8_t* entry);

  FDSURF_NODISCARD bool failed() const { return failed_; }
  Status failure() const { return failure_; }
  FDSURF_NODISCARD const int32_t* position() const { return position_; }

 private:
  enum class Stage : uint8_t {
    kIdle,
    kPatchNextLine,  // take the walker's next line (or finish the patch)
    kLineStart,      // the line is prepared: travel to its start if needed
    kAfterTravel,    // pen down if drawing, then step the line
    kStepping,       // the cursor runs the current path
    kFinish,         // pen up (patch), then the command-done entry
  };

  /// Prepares `curve` relative to its first point (by the
  /// planner for kPlannerLevel, else at the host's level) and points the
  /// cursor at it.
  bool PrepareInto(const PowerCurve1 (&curve)[kDims], uint32_t tolerance_q8, int host_level);
  bool NextPoint(int32_t (&point)[kDims]);
  /// The line's next chord end from its cursor; false after the last.
  bool NextChord(int32_t (&fine)[kDims], bool* finest);
  /// Queues an entry to hand out before anything else.
  void Emit(uint8_t entry);
  /// Starts a straight pen-at-current-state move to `target`.
  void StartTravel(const int32_t (&target)[kDims]);
  void Fail(Status status);

  Stage stage_ = Stage::kIdle;
  protocol::MessageType type_ = protocol::MessageType::kPen;
  /// Where the next stepping phase goes after the cursor is exhausted.
  Stage after_stepping_ = Stage::kIdle;
  bool lift_for_travel_ = false;  // patches lift the pen for travel; curves keep it
  bool pen_down_ = false;
  bool failed_ = false;
  Status failure_ = Status::kOk;
  int32_t position_[kDims] = {};

#if FDSURF_DEVICE_PLANNER
  // Patch state.
  IsolineWalker<kDims> walker_;
  IsolineFamily family_ = IsolineFamily::kSLines;
  uint16_t lines_t_ = 0;
  uint16_t line_index_ = 0;
  protocol::PatchCommand patch_;  // kept for the t-line walker
#endif
  uint32_t tolerance_q8_ = 0;
  /// The finest level of a PREPARED_CURVE, or kPlannerLevel.
  int8_t host_level_ = kPlannerLevel;

  // The line to draw (power coefficients, 2^-16 steps) and its first point;
  // the path being stepped now (the line, or a straight travel move to it).
  PowerCurve1 line_[kDims];
  int32_t line_start_[kDims] = {};
  /// What is being stepped: a straight move, or the line (relative to
  /// line_start_) with the 64-bit or the Int128 accumulator.
  enum class Path : uint8_t { kStraight, kLine64, kLine128 };
  Path path_ = Path::kStraight;
  StraightMoveCursor<kDims> straight_;
  // The cursors copy what they need of the line's prepared table, which is
  // then a local of PrepareInto(): 90 bytes of static RAM less on the Uno.
#if FDSURF_DEVICE_WIDE_TABLES
  AdaptiveChordCursor<Int128, kDims> cursor128_;
#endif
  AdaptiveChordCursor<int64_t, kDims> cursor64_;
  /// The unit moves of the line's current chord, relative to line_start_.
  ChordDda<kDims> dda_;

  // Entries to hand out before stepping on (at most a pen event and a
  // command-done marker at a time).
  uint8_t pending_[2] = {};
  uint8_t pending_count_ = 0;
  uint8_t pending_head_ = 0;
};

/// The power coefficients of the same curve run backwards: x(1 − u). Exact.
template <int kDims>
void ReverseCurve(PowerCurve1 (&curve)[kDims]);

/// Whether a line is a single point (a pole of the patch): it draws nothing.
template <int kDims>
bool IsPoint(const PowerCurve1 (&curve)[kDims]) {
  for (int c = 0; c < kDims; ++c) {
    if (curve[c].c[0] != 0 || curve[c].c[1] != 0 || curve[c].c[2] != 0) return false;
  }
  return true;
}

/// Whether line `index` of `lines` in a family is an edge that
/// PatchCommand::skip_lines says another patch draws.
inline bool IsSkippedEdge(uint8_t skip_lines, IsolineFamily family, uint16_t index,
                          uint16_t lines) {
  const uint8_t first =
      family == IsolineFamily::kSLines ? protocol::kSkipFirstSLine : protocol::kSkipFirstTLine;
  const uint8_t last =
      family == IsolineFamily::kSLines ? protocol::kSkipLastSLine : protocol::kSkipLastTLine;
  return (index == 0 && (skip_lines & first) != 0) ||
         (index + 1u == lines && (skip_lines & last) != 0);
}

/// The lines of one family of a PATCH that the device draws, in its order
/// and direction: every other line reversed (serpentine), poles and the
/// edges in skip_lines left out. Calls line(curve) with each line's power
/// coefficients (2^-16 steps) until it returns false. PathGenerator draws
/// these lines (one at a time, as the motion loop pulls them); a host that
/// sends a patch as PREPARED_CURVEs walks them with this. Returns the
/// walker's refusal (kInvalidArgument, kGridOutOfRange, kGeometryOutOfRange)
/// or kOk; a family of 0 lines has none.
template <int kDims, typename LineFn>
Status ForEachDrawnLine(const protocol::PatchCommand& patch, IsolineFamily family, LineFn&& line) {
  const uint16_t lines = family == IsolineFamily::kSLines ? patch.lines_s : patch.lines_t;
  if (lines == 0) return Status::kOk;
  PatchGeometry1 geometry[kDims];
  for (int c = 0; c < kDims; ++c) geometry[c] = patch.geometry[c];
  IsolineWalker<kDims> walker;
  const Status created =
      IsolineWalker<kDims>::Create(geometry, patch.basis, family, lines, &walker);
  if (created != Status::kOk) return created;
  PowerCurve1 curve[kDims];
  for (uint16_t index = 0; walker.Next(curve); ++index) {
    if (IsPoint(curve) || IsSkippedEdge(patch.skip_lines, family, index, lines)) continue;
    if ((index & 1u) != 0) ReverseCurve(curve);
    if (!line(static_cast<const PowerCurve1(&)[kDims]>(curve))) break;
  }
  return Status::kOk;
}

}  // namespace motion
}  // namespace fdsurf
