// SPDX-License-Identifier: MIT
// Writers for planned toolpaths: SVG, G-code, HPGL, the strokes as JSON, and a
// PNG picture (cairo). The text writers return the whole file as a string,
// so that a caller can produce everything before it writes anything.
#pragma once

#include <string>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {

/// SVG 1.1: a page of width × height output units (mm or in), one <path> per
/// stroke, y flipped so that up in the drawing is up on the page.
std::string WriteSvg(const Toolpath& path, const std::string& title);

struct GcodeOptions {
  /// "z": pen up/down (or the plunge in 3-D) as Z moves; "m3": M3/M5 with a dwell.
  std::string pen = "z";
  double pen_up_z = 5;
  double pen_down_z = 0;
  /// Drawing and plunge feed rates, output units per minute.
  double feed = 1500;
  double plunge_feed = 300;
  /// Dwell after M3/M5, seconds.
  double dwell = 0.2;
  /// M3 spindle/laser power word.
  int power = 1000;
};

/// G-code: G21/G20, G90; G0 for travel, G1 with feed for drawing. In 3-D the
/// Z of each point is the surface's depth and travel happens at pen_up_z.
/// `header` lines become leading comments.
std::string WriteGcode(const Toolpath& path, const GcodeOptions& options,
                       const std::vector<std::string>& header);

/// HPGL: IN; SP1; PU/PD with absolute plotter units. Requires the toolpath's
/// quantum to be the plotter unit (0.025 mm), so every point is exact.
std::string WriteHpgl(const Toolpath& path);

/// {"units", "quantum", "dims", "width", "height", "bbox", "strokes"}: the
/// points exactly as the other writers print them.
std::string WriteStrokesJson(const Toolpath& path);

/// Draws the strokes on a white page, `width_px` pixels wide, as a PNG file.
void RenderPng(const Toolpath& path, int width_px, const std::string& file);

/// Writes `content` to `file`; throws OutputError naming the file.
void WriteFile(const std::string& file, const std::string& content);

}  // namespace fdsurf::host
