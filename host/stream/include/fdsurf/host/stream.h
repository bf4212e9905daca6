// SPDX-License-Identifier: MIT
// Jobs for a device: the drawing as patches in motor steps, ready to stream.
//
// The host does what needs the whole drawing (the view, the fit to the page,
// the order of the patches) and maps every patch into steps with the same
// map and rounding that `fdsurf plot` uses (toolpath.h, PatchToQuanta, with
// the quantum = one step). The device then evaluates the isolines itself.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/hidden_lines.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/toolpath.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf::host {

/// Which corner of the page the machine's position 0 is at, seen as the
/// drawing is seen: the page's own origin (bottom left, X right and Y up,
/// Grbl's and most CNCs'), or another corner, toward which that axis's
/// position then decreases (top left: an AxiDraw's home, Y toward the user).
enum class MachineOrigin { kBottomLeft, kTopLeft, kBottomRight, kTopRight };

/// "bottom-left", "top-left", "bottom-right", "top-right": the origin; nullopt
/// for another text.
std::optional<MachineOrigin> ParseMachineOrigin(const std::string& text);

/// The machine, in output units (mm or in) and seconds. The defaults are in
/// mm (mm/s, mm/s²); a caller working in inches converts them (fdsurf stream
/// does, stream_command.cc).
struct MachineOptions {
  /// Length of one motor step; every position is a whole number of steps.
  /// X's, and every axis's that has no step of its own in `own_step`.
  Quantum step = Quantum::Parse("0.0125");
  /// Y's and Z's steps (index 1, 2) where they differ from `step` (a
  /// leadscrew Z under belt-driven X and Y); index 0 is not used. The job
  /// then gives the device each axis in its own steps, and its path speed
  /// and acceleration limits in steps of the coarsest axis (so that no
  /// direction exceeds them); docs/machines.md, "Steps per unit".
  std::array<std::optional<Quantum>, 3> own_step{};
  /// Axis `axis`'s step (0 X, 1 Y, 2 Z).
  FDSURF_NODISCARD const Quantum& StepOf(int axis) const {
    const std::optional<Quantum>& own = own_step[static_cast<std::size_t>(axis)];
    return axis > 0 && own ? *own : step;
  }
  /// The longest step of the first `dims` axes.
  FDSURF_NODISCARD double CoarsestStep(int dims) const {
    double coarsest = 0;
    for (int a = 0; a < dims; ++a) coarsest = std::max(coarsest, StepOf(a).value());
    return coarsest;
  }
  /// Travel of each axis from 0; {0, 0, 0} means the page (and, in 3-D, the
  /// drawing's depth).
  std::array<double, 3> travel{0, 0, 0};
  /// Path speed and acceleration limits.
  double speed = 100;
  double accel = 2000;
  /// Each axis's acceleration limit (x, y, z), the centripetal part on
  /// curves included (CONFIG axis_accel, docs/motion.md "Each axis on
  /// curves"); above `accel`, whose excess is what turning may use; an
  /// entry of 0: twice `accel`. The device keeps every axis within the
  /// smallest of the limits of the axes it drives.
  std::array<double, 3> axis_accel{0, 0, 0};
  /// Path speed limit with the pen up (the device's CONFIG travel_rate);
  /// 0: the same as `speed`.
  double travel_speed = 0;
  int pen_delay_ms = 100;
  /// A hobby-servo pen lift's pulse widths, µs (the device's CONFIG
  /// servo_up_us/servo_down_us): both 0 for a plain switch pen, else each
  /// in 500..2500.
  int servo_up_us = 0;
  int servo_down_us = 0;
  /// CONFIG's kConfigFlagHomingRequired: the device refuses motion
  /// (kNotHomed) until every axis has been homed (`fdsurf machine home`).
  bool homing_required = false;
  /// Where position 0 is on the page; the job mirrors X and/or Y so that
  /// the drawing comes out as seen (StreamJob::mirror_steps).
  MachineOrigin origin = MachineOrigin::kBottomLeft;
};

/// One patch as the device will draw it, for checks: the patch, and the
/// isolines it draws.
struct StreamedPatch {
  std::size_t patch = 0;  // index in the patch set
  int lines_s = 0;
  int lines_t = 0;
};

/// Where a layer of the file's curves begins in StreamJob::commands.
struct LayerStart {
  /// Index of the layer's first command (the pen is up before it).
  std::size_t command = 0;
  /// PatchSet::layers name (may be empty).
  std::string name;
};

struct StreamJob {
  protocol::MachineConfig config{};
  /// CONFIG first, then the patches (StreamPlan: one PATCH per patch, in
  /// drawing order, or their lines as PEN, MOVE and CURVE commands), then
  /// the file's curves (PEN, MOVE and CURVE commands; a straight curve is one
  /// MOVE with the pen down). The curves go layer by layer; within a layer
  /// in file order when PatchSet::keep_order, else chains of curves that
  /// meet end to end are ordered by nearest neighbour (Bézier and Hermite
  /// chains may be drawn reversed, exactly).
  std::vector<protocol::Command> commands;
  std::vector<std::string> labels;
  std::vector<StreamedPatch> patches;
  /// The file's curves (PatchSet::curves indices), drawn after the patches.
  std::vector<std::size_t> curves;
  /// The start of every layer of curves, in drawing order, when the file
  /// has layers (PatchSet::layers not empty); runners pause between them.
  std::vector<LayerStart> layers;
  /// The page and the map from file units to output units; quantum = X's
  /// step.
  Toolpath page;
  /// Each axis's step (MachineOptions::StepOf): a position of axis a in
  /// steps is that many steps[a] in output units.
  std::array<Quantum, 3> steps{};
  /// Tolerance in steps (of the coarsest axis: a deviation of that many
  /// steps of any axis is within the tolerance), and as the devices's
  /// 2^-8-step units.
  double tolerance_steps = 0;
  std::uint32_t tolerance_q8 = 0;
  /// Edge lines left out because a patch earlier in the order draws the
  /// same curve (PatchCommand::skip_lines).
  std::size_t shared_edges_skipped = 0;
  /// For X and Y, 0 when the machine's axis runs as the page's; else the
  /// axis is mirrored (MachineOptions::origin): the machine's position is
  /// mirror_steps[a] minus the page's, both in whole steps (the page's
  /// width or height rounded up to a whole step).
  std::array<std::int64_t, 2> mirror_steps{0, 0};
};

/// The CONFIG of `machine` for `dims` axes without a drawing (`fdsurf
/// machine`'s commands): BuildStreamJob's configuration with the travel as
/// the page. machine.travel must be given for every axis; throws OptionError
/// as BuildStreamJob does for a limit the device cannot take.
protocol::MachineConfig MachineConfigFor(const MachineOptions& machine, int dims,
                                         const std::string& units);

/// A point the machine drew (steps, its own axes) on the page (each axis's
/// steps from the page's origin): the identity unless the job mirrors an
/// axis.
std::array<std::int64_t, 3> PageSteps(const StreamJob& job, std::array<std::int64_t, 3> machine);

/// The largest decimal that divides the step of every axis the job drives:
/// X's step when they agree (0.0025 for 0.0125 and 0.01). The quantum of a
/// drawn toolpath (the pictures of what the machine drew).
Quantum PageQuantum(const StreamJob& job);

/// A point the machine drew on the page in PageQuantum(job): PageSteps,
/// then each axis's steps as whole multiples of that quantum.
std::array<std::int64_t, 3> PagePosition(const StreamJob& job,
                                         const std::array<std::int64_t, 3>& machine);

/// How a job's patches travel to the device and in what order their lines
/// are drawn. Either way every line is the one the device's walker forms
/// for the patch (motion::ForEachDrawnLine), stepped the same, and an edge
/// line that a patch before it draws is left out (DrawnCurves).
enum class StreamPlan {
  /// Each drawn line as a CURVE, power basis, with the walker's
  /// coefficients, planned across patches as `fdsurf plot` plans its
  /// strokes (plan.h): lines that meet end to end are one pen-down stroke,
  /// across patch edges too; strokes in nearest-neighbour order improved by
  /// 2-opt, either direction. As few pen lifts and as little pen-up travel
  /// as plot's plan of the same drawing; more bytes on the wire.
  kLines,
  /// One PATCH per patch, the patches in nearest-neighbour order; the
  /// device draws a patch's lines in its own order (s-lines, then t-lines,
  /// serpentine) and lifts the pen between lines that do not meet and at
  /// the end of every patch. The fewest bytes on the wire.
  kPatches,
};

/// "lines", "patches": the plan; nullopt for another text.
std::optional<StreamPlan> ParseStreamPlan(const std::string& text);

/// Builds the job. `options` as for `fdsurf plot` (lines, view, fit, margin,
/// tolerance, dims; the quantum is replaced by machine.step); the patches
/// as `plan` says, then the file's curves. Throws OptionError ("lines", "tolerance", "fit", "travel
/// X", "travel Y", "travel Z", "speed", "accel", "pen delay"; a travel over
/// motion::kMaxPlannableTravelSteps, which the device refuses), InputError
/// (a file with nothing to draw) and EngineError (a patch out of range).
/// Before returning, every command is put through the device's own
/// validation (motion::ValidateCommand) with the job's configuration: a job
/// returned here is never refused by the device for its travel or planner;
/// one that would be throws EngineError naming the command and its exact
/// range in `units`.
StreamJob BuildStreamJob(const PatchSet& set, const ToolpathOptions& options,
                         const MachineOptions& machine, const std::string& units,
                         StreamPlan plan = StreamPlan::kLines);

/// `fdsurf stream --prepare-on-host`: the job with every PATCH and CURVE
/// replaced by what the device draws for it, planned here ("the host
/// computes, the device adds"; docs/protocol.md, "Prepared curves"), so that
/// the device needs no planner:
/// - a CURVE becomes one PREPARED_CURVE: the same power coefficients, at
///   the finest level this host's planner (PrepareAdaptiveCurve, the
///   device's own) chooses;
/// - a PATCH becomes, for every line the device draws of it
///   (motion::ForEachDrawnLine, in its order and direction), a pen-up and a
///   MOVE to the line's first point unless the previous line ended there, a
///   pen-down and the line's PREPARED_CURVE; then a pen-up.
/// The device then makes the same unit moves and pen changes as for the
/// PATCH and CURVE commands (a pen-up with the pen up, and a MOVE to where
/// the machine is, make none). Labels follow their commands ("patch 3 (…)
/// s-line 2"), and layers their first command. Throws EngineError for a
/// line the planner refuses (BuildStreamJob's check rules that out for the
/// jobs it builds).
void PrepareOnHost(StreamJob* job);

/// The job for a device that steps 64-bit tables only (HELLO_REPLY's
/// protocol::kFeature64BitTables, the Arduino Uno): every PREPARED_CURVE whose
/// table, relative to its first point, does not fit the 64-bit accumulator
/// at its level (the device's own check, PrepareAdaptiveCurveAtLevel's
/// 64-bit form), or whose Bernstein hull crosses the edge of the travel
/// (such a device does not halve it: motion::HullWithinTravel), is replaced
/// by its pieces over [i/2^k, (i+1)/2^k], halved until each passes both,
/// each at the level this host's planner chooses for it.
/// A piece's power coefficients are computed exactly from the line's and
/// rounded once to 2^-16 steps: within 2^-15 steps of the line, which the
/// engine's allowance for rounding before stepping covers, so every piece
/// keeps the line's tolerance (docs/protocol.md, "Prepared curves"). Each
/// piece starts where the previous one ended, or one step from it where the
/// two roundings fall either side of a half (the device joins them with a
/// one-step straight move). Other commands are kept; labels gain ", piece j
/// of n"; layers follow their first command. Throws EngineError naming the
/// line when 16 halvings do not make it fit.
void SplitForSixtyFourBitTables(StreamJob* job);

/// `fdsurf stream --hidden remove`: the visible pieces of a drawing as a
/// flat drawing of Bézier curves, which BuildStreamJob(set, options,
/// machine, units) streams like any file's curves (CURVE commands, straight
/// pieces as MOVEs) and ReferenceLines compares with.
struct VisibleCurves {
  /// No patches; one Basis::kBezier curve per exact sub-cubic of a visible
  /// piece (Stroke::cubics), in output units on the page of the whole
  /// drawing (in 3-D, z placed so that the job of `set` puts every point at
  /// the Z the whole drawing's job would), with the piece's layer; `straight` when its control
  /// points lie within 10⁻⁶ steps of its chord. In the order PlanStrokes gives (shared edges drawn
  /// once, pieces that meet joined), kept (keep_order); the page and the
  /// layers of the drawing.
  PatchSet set;
  /// The options that draw `set` where the whole drawing would be drawn:
  /// view top, origin keep, no scale, the page as set.page.
  ToolpathOptions options;
  /// The machine; in 3-D with the Z travel of the whole drawing unless given.
  MachineOptions machine;
  /// How visibility was decided (HiddenLineDefaults of the tolerance) and
  /// what it removed; what planning joined and removed.
  HiddenLineOptions hidden;
  HiddenLineReport report;
  PlanReport plan;
};

/// The drawing of `set` with `options` (as for BuildStreamJob) drawn as
/// `fdsurf plot --hidden remove` draws it (adaptive steps, the quantum = one
/// step), its hidden lines removed (RemoveHiddenLines), planned
/// (PlanStrokes), and the visible pieces made curves. Throws as
/// BuildToolpath and RemoveHiddenLines, and InputError when nothing is
/// visible.
VisibleCurves VisibleCurvesOf(const PatchSet& set, const ToolpathOptions& options,
                              const MachineOptions& machine, const std::string& units);

/// The isolines of the job as the exact (double) curves, in steps, sampled
/// densely enough that the polyline is within `chord_steps` of the curve.
/// Lines that collapse to a point are left out (the device skips them too).
std::vector<std::vector<std::array<double, 3>>> ReferenceLines(const PatchSet& set,
                                                               const StreamJob& job,
                                                               double chord_steps = 0.005);

}  // namespace fdsurf::host
