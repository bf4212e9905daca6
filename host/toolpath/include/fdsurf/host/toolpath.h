// SPDX-License-Identifier: MIT
// Toolpaths: patch sets drawn as wireframes of isoparametric curves.
//
// Each patch is mapped affinely into output space (a view's projection, a
// scale and an offset, applied to the geometry itself, which is exact for
// every basis), and each isoline is produced by the core's forward-difference
// engine: the IsolineWalker steps across the patch, the adaptive stepper walks
// along the line. docs/toolpaths.md proves the tolerance that every stroke
// keeps from the exact curve.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fdsurf/adaptive.h"
#include "fdsurf/config/nodiscard.h"
#include "fdsurf/forward_difference.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quantum.h"

namespace fdsurf::host {

/// An orthographic view: output axes as rows of a rotation of model space.
/// `right` and `up` span the drawing plane, `depth` = right × up points to
/// the viewer (the Z of 3-D output).
struct View {
  std::string name;
  std::array<double, 3> right{};
  std::array<double, 3> up{};
  std::array<double, 3> depth{};
};

/// The named views: "top" (x right, y up), "front" (x right, z up), "side"
/// (y right, z up) and "iso" (azimuth -45°, elevation atan(1/√2)); nullopt
/// for another name.
std::optional<View> NamedView(const std::string& name);

/// The view from azimuth `azimuth_deg` (from +x towards +y, the direction of
/// the eye) and elevation `elevation_deg` above the xy plane, in degrees.
/// Throws OptionError ("view") for an elevation outside -90..90 or a value
/// that is not finite.
View ViewFromAngles(const std::string& name, double azimuth_deg, double elevation_deg);

/// How curves are stepped.
enum class StepMode {
  /// Adaptive forward differences: every chord within the tolerance.
  kAdaptive,
  /// Uniform steps: per curve, the fewest that the same chord bound allows.
  kFixed,
  /// Adaptive, and at most one quantum per axis per step (step-exact).
  kStepExact,
};

/// Where the drawing goes on the page (--origin; docs/toolpaths.md, "The page").
enum class PageOrigin {
  /// The file's coordinates are the machine's: the view and the unit factor
  /// only, no scaling to a page and no offset.
  kKeep,
  /// Centred on the page.
  kCenter,
  /// The drawing's lower-left corner at (margin, margin).
  kMin,
};

struct ToolpathOptions {
  /// Largest distance between the drawn polyline and the exact curve, in
  /// output units (Euclidean, in the output's 2 or 3 dimensions). The
  /// default, and the quantum's, are mm; fdsurf converts them for inches.
  double tolerance = 0.05;
  /// Isolines per patch along each family (s-lines: s fixed; t-lines: t
  /// fixed), each ≥ 2, or 0 to leave the family out.
  int lines_s = 8;
  int lines_t = 8;
  View view;
  /// Output units per file unit (25.4 for a file in inches drawn in mm).
  double units_scale = 1.0;
  /// When set, the page (output units). Under kCenter and kMin the drawing is
  /// scaled uniformly to fit it inside the margin; under kKeep it is not
  /// scaled and must lie inside [0, W] × [0, H] as it is.
  std::optional<std::array<double, 2>> fit;
  /// Space kept around the drawing (output units); not used under kKeep
  /// with a page, and added beyond the drawing's far edge under kKeep without one.
  double margin = 0.0;
  PageOrigin origin = PageOrigin::kCenter;
  /// Output resolution: every point is a whole multiple of it.
  Quantum quantum;
  /// 2: the view plane; 3: plus depth (for CNC).
  int dims = 2;
  StepMode mode = StepMode::kAdaptive;
};

/// The affine map from file coordinates to output units.
struct OutputMap {
  View view;
  double scale = 1.0;
  std::array<double, 3> offset{};
  FDSURF_NODISCARD std::array<double, 3> Apply(const Point3& p) const;
  FDSURF_NODISCARD std::array<double, 3> ApplyLinear(const Point3& p) const;
};

/// One drawn curve: whole-quantum points (z = 0 when dims = 2) and where
/// they come from, so tests can compare them with the exact curve.
struct Stroke {
  std::vector<std::array<std::int64_t, 3>> points;
  /// The parameter along the isoline of each point (before planning).
  std::vector<double> params;
  std::size_t patch = 0;
  IsolineFamily family = IsolineFamily::kSLines;
  /// For a curve of the file (PatchSet::curves) rather than an isoline: its
  /// index; -1 for isolines.
  std::ptrdiff_t curve = -1;
  /// Fixed parameter of the isoline (s for s-lines, t for t-lines).
  double line_param = 0;
  /// Index into Toolpath::layers (the curve's PatchSet layer; 0 for the
  /// isolines of patches and when the drawing has no layers).
  int layer = 0;
  /// The exact cubic pieces the stroke draws, in order, each as its four
  /// Bézier control points in output units (the mapped, unrounded curve;
  /// z = 0 in 2-D). The first piece starts near points.front() and the last
  /// ends near points.back(), each within the tolerance. Empty when unknown:
  /// code that cuts a stroke's points (or joins it to one without cubics)
  /// must clear it or cut the cubics too, or G5 output would draw the cut part.
  std::vector<std::array<std::array<double, 3>, 4>> cubics;
};

struct Toolpath {
  int dims = 2;
  std::string units;  // "mm" or "in"
  Quantum quantum;
  OutputMap map;
  /// The page: [0, width] × [0, height] in output units.
  double width = 0;
  double height = 0;
  /// The drawing's extent along the view's depth, output units (3-D output
  /// puts its top at Z = 0 and its bottom at Z = -depth, except under
  /// PageOrigin::kKeep, where Z is the file's own).
  double depth = 0;
  /// The largest distance promised between a stroke and its exact curve,
  /// output units (ToolpathOptions::tolerance); 0 when unknown.
  double tolerance = 0;
  /// The layers' names (PatchSet::layers); empty: one unnamed layer.
  std::vector<std::string> layers;
  /// The drawing's exact extent on the page (output units, before rounding
  /// to the quantum): lower-left and upper-right corners. Under kKeep it may
  /// reach below 0 (the commands decide whether that is allowed).
  std::array<double, 2> drawing_lo{};
  std::array<double, 2> drawing_hi{};
  std::vector<Stroke> strokes;
};

/// Called after each patch with (patches done, patches in all, points so far).
using Progress = std::function<void(std::size_t, std::size_t, std::size_t)>;

/// Checks the options and plans the page: the output map (view, scale to
/// the fit, the offset options.origin asks for), width, height and the
/// drawing's extent. Under kKeep without a fit the page is the file's own
/// (set.page, times units_scale) or else runs from 0 to the drawing's far
/// edge plus the margin. No strokes. Throws OptionError ("lines",
/// "tolerance", "fit"; "fit" also for kKeep with a page the unscaled drawing
/// does not lie inside) for options that cannot be met and InputError for a
/// file with nothing to draw.
Toolpath PlanPage(const PatchSet& set, const ToolpathOptions& options, const std::string& units);

/// The patch's geometry in output space, in the engine's format: every
/// control value mapped (points by the whole map, vectors by its linear
/// part) and rounded to 2^-16 quanta. Fills geometry[0..dims). Throws
/// EngineError (naming patch.origin) for a value beyond ±2^31 quanta.
void PatchToQuanta(const Patch& patch, const OutputMap& map, const Quantum& quantum, int dims,
                   PatchGeometry1* geometry);

/// The same for a curve (points by the whole map, vectors by its linear part).
void CurveToQuanta(const Curve& curve, const OutputMap& map, const Quantum& quantum, int dims,
                   CurveGeometry1* geometry);

/// Both with a quantum per axis (a machine whose axes step differently):
/// axis c in quanta[c]. An affine map of a Bézier, Hermite, B-spline,
/// Catmull-Rom or power-basis net is the net of the mapped surface, so the
/// scaling per axis is exact before the rounding to 2^-16 quanta.
void PatchToQuanta(const Patch& patch, const OutputMap& map, const std::array<Quantum, 3>& quanta,
                   int dims, PatchGeometry1* geometry);
void CurveToQuanta(const Curve& curve, const OutputMap& map, const std::array<Quantum, 3>& quanta,
                   int dims, CurveGeometry1* geometry);

/// Draws every patch's isolines, then the file's curves, each stroke with its
/// layer and its exact cubic (Stroke::cubics). Throws as PlanPage
/// for options that cannot be met (tolerance below the quantum's reach, a
/// drawing that does not fit) and EngineError when the engine refuses a
/// curve. `progress`, when set, is called after each patch.
Toolpath BuildToolpath(const PatchSet& set, const ToolpathOptions& options,
                       const std::string& units, const Progress& progress = {});

/// The Bézier control points of a cubic given by its power coefficients
/// (ascending: power[k] multiplies u^k), exact up to double rounding.
std::array<Point3, 4> BezierFromPower(const std::array<Point3, 4>& power);

/// The exact point of a stroke's isoline or curve at `param`, in output units
/// with its depth along the view (also for 2-D output): the double
/// reference through the same map.
std::array<double, 3> ExactStrokePointWithDepth(const PatchSet& set, const Toolpath& path,
                                                const Stroke& stroke, double param);

/// The same as output holds it (z = 0 in 2-D), for checks.
std::array<double, 3> ExactStrokePoint(const PatchSet& set, const Toolpath& path,
                                       const Stroke& stroke, double param);

}  // namespace fdsurf::host
