// SPDX-License-Identifier: MIT
// The pen's plan: what `fdsurf plot` and `fdsurf stream` both decide before
// anything is drawn, in one place.
//
//  - Which curves are drawn already. Patches of a surface share their edges
//    (the teapot's 32 patches share 52), and a curve is drawn once. Two
//    curves are the same when nine samples of their exact (double) curves,
//    in quanta, agree within 0.1 quanta forwards or backwards: DrawnCurves.
//  - In what order the pieces are visited: nearest neighbour from the
//    origin, entering a piece at its start (patches, whose drawing order the
//    device fixes) or at either end (strokes): OrderNearestNeighbour.
//
//  - Which pieces meet end to end and are drawn as one stroke
//    (ChainTouching), and a better order by 2-opt (ImproveByTwoOpt).
//
// `plot` applies all of them to strokes (PlanStrokes); `stream` to the lines
// the device draws of each patch (stream.h, StreamPlan::kLines), or, for
// the patches plan, the first two to whole patches, sending the edge lines
// drawn already as PATCH skip_lines.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {

/// A point in output quanta (or motor steps), z = 0 in 2-D.
using PlanPoint = std::array<double, 3>;

/// Nine points of a curve at parameters 0, 1/8, ..., 1, in output quanta.
using SampledCurve = std::array<PlanPoint, 9>;

/// The exact isoline of `patch` through `map`, in units of `unit` (the
/// quantum or the motor step): s fixed at `at` for s-lines, t for t-lines.
SampledCurve SampleIsoline(const Patch& patch, const OutputMap& map, double unit, int dims,
                           IsolineFamily family, double at);

/// The same for a curve of the file.
SampledCurve SampleCurve(const Curve& curve, const OutputMap& map, double unit, int dims);

/// Whether the samples are all one point (a pole, like the teapot lid's top).
bool IsPoint(const SampledCurve& samples);

/// The curves drawn so far.
class DrawnCurves {
 public:
  /// True when the same curve (within 0.1 units, either direction) was
  /// added before; otherwise adds it and returns false.
  bool CheckAndAdd(const SampledCurve& samples);

 private:
  /// Curves by their end points rounded to whole units, lower end first.
  std::multimap<std::array<std::int64_t, 6>, SampledCurve> by_ends_;
};

/// How distances between pieces are measured.
enum class PlanMetric {
  /// In the drawing plane (x, y): a pen's travel.
  kPlane,
  /// In all three axes: a CNC's travel.
  kSpace,
};

/// One piece of the order: its index, and whether it is entered at its end.
struct Visit {
  std::size_t index = 0;
  bool reversed = false;
};

/// Greedy nearest neighbour from `start`: repeatedly the piece whose entry
/// is nearest to where the last one left off (ends[i] = {start, end} of
/// piece i; with `may_reverse` a piece may be entered at its end and left at
/// its start). Ties go to the lower index, then to the forward direction.
std::vector<Visit> OrderNearestNeighbour(const std::vector<std::array<PlanPoint, 2>>& ends,
                                         bool may_reverse, PlanMetric metric,
                                         const PlanPoint& start = {0, 0, 0});

/// Chains of pieces that meet end to end, the ends compared exactly
/// (ends[i] = {start, end} of piece i, in whole quanta or steps). Every piece
/// is in one chain; a chain lists its pieces in drawing order, each entered
/// at its end where `reversed`. Chains start at the pieces in index order and
/// grow at their end, then at their start, taking the lowest-indexed piece
/// that meets them (a piece that meets at both ends closes a loop).
std::vector<std::vector<Visit>> ChainTouching(
    const std::vector<std::array<std::array<std::int64_t, 3>, 2>>& ends);

/// Improves an order of pieces (`order`, as OrderNearestNeighbour gives it
/// for the same `ends`) by 2-opt: reverses a run of pieces, each drawn the
/// other way, wherever that shortens the travel from `start` through the
/// order, until no such run is left (at most 30 passes; runs of up to 300
/// pieces, which keeps large drawings fast).
void ImproveByTwoOpt(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
                     const PlanPoint& start, std::vector<Visit>* order);

/// Improves an order by Or-opt: takes a run of one, two or three pieces
/// out and puts it back elsewhere (within 300 pieces), either way round,
/// wherever that shortens the travel, until no such move is left.
void ImproveByOrOpt(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
                    const PlanPoint& start, std::vector<Visit>* order);

/// 2-opt and Or-opt in turn until neither shortens the travel (at most four
/// rounds): what plot and stream do to the nearest-neighbour order.
void ImproveOrder(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
                  const PlanPoint& start, std::vector<Visit>* order);

struct PlanReport {
  std::size_t strokes_before = 0;
  std::size_t strokes_after = 0;
  /// Strokes that draw a curve drawn already by another (shared edges).
  std::size_t duplicates_removed = 0;
  /// Pen-down and pen-up (travel) lengths in output units, in the plane.
  double pen_down_before = 0;
  double pen_down_after = 0;
  double pen_up_before = 0;
  double pen_up_after = 0;
};

/// Plans the pen's path of a drawing of `set`: removes strokes that draw a
/// curve drawn already (DrawnCurves), joins strokes that meet end to end,
/// orders them by nearest neighbour from the origin (reversing where it
/// helps) and improves the order by 2-opt. Distances are in the drawing
/// plane. Joined strokes lose their params (they span several curves) and
/// keep their cubics in order (reversed with the stroke). Each layer
/// (Stroke::layer) is planned on its own, layers in ascending order, the
/// next starting where the last left the pen: nothing is joined, removed or
/// reordered across layers.
PlanReport PlanStrokes(const PatchSet& set, Toolpath* path);

}  // namespace fdsurf::host
