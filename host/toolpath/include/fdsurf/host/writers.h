// SPDX-License-Identifier: MIT
// Writers for planned toolpaths: SVG, G-code, HPGL, the strokes as JSON, and a
// PNG picture (cairo). The text writers return the whole file as a string,
// so that a caller can produce everything before it writes anything.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {

/// What an SVG or PNG shows, in quanta of path.quantum, y up: the page
/// [0, W] × [0, H] (W and H rounded up to whole quanta), grown on each side
/// that a stroke's point lies beyond to that point plus half the SVG pen
/// (0.25 mm or 0.01 in, rounded up to whole quanta), so that nothing drawn
/// is cut off (docs/toolpaths.md, "The page").
struct PageView {
  std::array<std::int64_t, 2> lo{};
  std::array<std::int64_t, 2> hi{};
  /// The view is larger than the page: some point lies outside it.
  bool past_page = false;
};
PageView ViewOfPage(const Toolpath& path);

/// SVG 1.1: the view of ViewOfPage, as width × height output units (mm or
/// in) and a viewBox in the same units, one <path> per stroke, y flipped at
/// the page's top edge (H − y) so that up in the drawing is up on the page.
/// A point's coordinates are the same whatever the view: a view that grows
/// past the page only moves the viewBox's origin (negative past the left or
/// the top edge). No page outline is drawn (a plotter would draw it). When
/// the toolpath has layers, each run of strokes of one layer is an Inkscape
/// layer group (<g inkscape:groupmode="layer" inkscape:label="NAME">).
std::string WriteSvg(const Toolpath& path, const std::string& title);

struct GcodeOptions {
  /// The machine's dialect: "generic" (what fdsurf always wrote), "grbl",
  /// "marlin" or "linuxcnc"; docs/toolpaths.md has the table of differences.
  std::string flavor = "generic";
  /// "z": pen up/down (or the plunge in 3-D) as Z moves; "m3": M3/M5 with a
  /// dwell; "servo": Marlin's M280 P<servo_index> S<angle> with a dwell.
  std::string pen = "z";
  /// Z heights, output units. These and the rates below default to mm and
  /// mm/min; a caller working in inches converts them (fdsurf plot does).
  double pen_up_z = 5;
  double pen_down_z = 0;
  /// Servo angles (degrees) for the pen up and down, and the servo's index.
  double servo_up = 90;
  double servo_down = 30;
  int servo_index = 0;
  /// Drawing and plunge feed rates, output units per minute.
  double feed = 1500;
  double plunge_feed = 300;
  /// The rate assumed for G0 travel in the time estimate (the machine's own
  /// rapid rate is not known here), output units per minute.
  double travel_rate = 3000;
  /// The time estimate's machine (gcode_estimate.h): the acceleration of
  /// every move, output units/s² (0: acceleration ignored, each move takes
  /// length / rate), and Grbl's junction deviation, output units.
  double accel = 0;
  double junction_deviation = 0.01;
  /// Each axis's acceleration limit (x, y, z; Grbl's $120..$122), output
  /// units/s²; 0: that axis has none. A move accelerates at most at
  /// min(accel, limit_i / |u_i|) over the axes i of its direction u, as
  /// Grbl's planner limits it (and its junction speeds by the same rule on
  /// the junction's direction).
  std::array<double, 3> axis_accel{0, 0, 0};
  /// Write the estimate's comments in the header for the generic flavour
  /// too (every other flavour always has them; generic, left alone, stays
  /// what fdsurf always wrote). fdsurf plot sets it.
  bool estimate_in_header = false;
  /// Dwell after M3/M5 and after each servo move, seconds.
  double dwell = 0.2;
  /// M3 spindle/laser power word.
  int power = 1000;
  /// Strokes with exact cubics as G5 where the flavour has G5 (marlin,
  /// linuxcnc) and the output is 2-D; false: G1 segments everywhere.
  bool g5 = true;
};

/// G-code: G21/G20, G90; G0 for travel, G1 with feed for drawing (or G5
/// cubics, see GcodeOptions::g5). In 3-D the Z of each point is the
/// surface's depth and travel happens at pen_up_z. `header` lines become
/// leading comments; every flavour but generic adds its name and the
/// estimate (DescribeGcodeEstimate, gcode_estimate.h) as comments, generic
/// the estimate when options.estimate_in_header. Between layers: the pen lifted, a comment naming
/// the next layer and M0. Throws OptionError ("pen") for a flavour or pen
/// that is not known, or servo with a flavour without M280, and
/// OptionError ("tolerance") when a G5's control points, printed at the
/// quantum, would move the curve further than path.tolerance.
std::string WriteGcode(const Toolpath& path, const GcodeOptions& options,
                       const std::vector<std::string>& header);

/// The estimated machine time of WriteGcode's program, seconds:
/// EstimateGcode(path, options).seconds (gcode_estimate.h). With accel 0:
/// pen-down length / feed + travel (G0, pen lifts) / travel_rate + plunges /
/// plunge_feed + dwells (docs/toolpaths.md, "Time estimate").
double EstimateGcodeSeconds(const Toolpath& path, const GcodeOptions& options);

/// HPGL: IN; SP1; PU/PD with absolute plotter units. Requires the toolpath's
/// quantum to be the plotter unit (0.025 mm), so every point is exact.
std::string WriteHpgl(const Toolpath& path);

/// {"units", "quantum", "dims", "width", "height", "bbox", "strokes"}: the
/// points exactly as the other writers print them.
std::string WriteStrokesJson(const Toolpath& path);

/// Draws the strokes on white as a PNG file: the view of ViewOfPage,
/// `width_px` pixels wide (the height in proportion, rounded up). Throws
/// OutputError naming the file when it cannot be written.
void RenderPng(const Toolpath& path, int width_px, const std::string& file);

/// Writes `content` to `file`; throws OutputError naming the file.
void WriteFile(const std::string& file, const std::string& content);

}  // namespace fdsurf::host
