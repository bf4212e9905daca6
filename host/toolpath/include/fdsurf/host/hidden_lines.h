// SPDX-License-Identifier: MIT
// Hidden lines removed against the exact patches.
//
// A point of a drawn line is hidden when some patch, seen along the view's
// depth (orthographic), lies in front of it: a patch point q with the same
// (right, up) coordinates and depth(q) > depth(p) + eps. The question is
// answered against the patches themselves (each converted exactly to Bézier
// form in output space, pruned by the convex hulls of its sub-patches and
// decided by Newton's method in (s, t)), not against a mesh. Strokes are cut
// where visibility changes; the cut is located by bisection on the line's
// parameter with exact evaluation. docs/toolpaths.md ("Hidden lines") states
// what is guaranteed and what is not.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {

/// The occlusion query against every patch of a set, through one output map.
/// Built once (each patch as Bézier sub-patches with their boxes, indexed by
/// a grid over the drawing plane), then asked for many points.
class SurfaceOcclusion {
 public:
  /// `eps` > 0 is the depth margin in output units: a surface counts as
  /// hiding a point only when it is more than eps nearer the viewer (so the
  /// point's own patch and the neighbours sharing its edge, where q = p, do
  /// not). Throws OptionError ("hidden eps") for eps not above 0.
  SurfaceOcclusion(const PatchSet& set, const OutputMap& map, double eps);
  ~SurfaceOcclusion();
  SurfaceOcclusion(const SurfaceOcclusion&) = delete;
  SurfaceOcclusion& operator=(const SurfaceOcclusion&) = delete;

  struct Answer {
    /// A witness was found: a patch point q with |(right, up) of q − of p| ≤
    /// 1e-6·eps and depth(q) > depth(p) + eps.
    bool hidden = false;
    /// The search reached sub-patches smaller than eps/2 that may lie in
    /// front of the point without finding a witness (the point's line of
    /// sight passes within eps/2 of an occluder's silhouette or edge); the
    /// point counts as visible.
    bool undecided = false;
  };

  /// `point` in output space: (right, up, depth) as OutputMap::Apply gives
  /// it (the depth even in 2-D output).
  FDSURF_NODISCARD Answer Query(const std::array<double, 3>& point) const;

  FDSURF_NODISCARD double eps() const;

 private:
  struct Index;
  std::unique_ptr<Index> index_;
};

struct HiddenLineOptions {
  /// Depth margin, output units (SurfaceOcclusion). Default: the drawing
  /// tolerance.
  double eps = 0.05;
  /// A cut is placed within this distance (in the drawing plane, output
  /// units, between the bracketing exact points) of where visibility
  /// changes. Default: the drawing tolerance.
  double locate = 0.05;
  /// Visibility is sampled along each line at points at most this far apart
  /// (in the drawing plane, output units): a hidden stretch longer than this
  /// is always found. Default: 10× the drawing tolerance.
  double spacing = 0.5;
};

struct HiddenLineReport {
  std::size_t strokes_before = 0;
  std::size_t strokes_after = 0;
  /// Pen-down length in the drawing plane, output units.
  double length_before = 0;
  double length_after = 0;
  /// Points whose visibility was decided (samples and bisection steps).
  std::size_t queries = 0;
  /// Of those, the ones decided at the smallest sub-patches (Answer::undecided).
  std::size_t undecided = 0;
  double seconds = 0;
};

/// The options for a drawing of tolerance `tolerance` (output units): eps and
/// locate equal to it, spacing 10× it.
HiddenLineOptions HiddenLineDefaults(double tolerance);

/// Replaces the strokes of `path` (as BuildToolpath made them, before
/// PlanStrokes: every stroke still knows its patch, family, line parameter
/// and point parameters) by their visible pieces. A piece's end points are
/// the exact points at the located parameters, rounded to the quantum; its
/// other points are the stroke's own. Every patch of `set` can hide; curves
/// of the file are hidden but hide nothing. Throws OptionError ("hidden
/// eps", "hidden locate", "hidden spacing") for a value not above 0, or a
/// spacing below locate.
HiddenLineReport RemoveHiddenLines(const PatchSet& set, const HiddenLineOptions& options,
                                   Toolpath* path);

/// The report as one line for stderr (no newline), lengths and options in
/// `units`: "hidden: 504 strokes -> 445 visible pieces; drawn 20840.7 ->
/// 9589.1 mm; ..." with the depth margin, the cut location and the spacing.
std::string DescribeHiddenLines(const HiddenLineReport& report, const HiddenLineOptions& options,
                                const std::string& units);

}  // namespace fdsurf::host
