// SPDX-License-Identifier: MIT
// Reading SVG drawings (docs/formats.md, "SVG"): paths and the basic shapes
// become cubic Bézier curves in millimetres on the file's own page, exactly
// where SVG has cubics, quadratics and lines, and within a proven bound for
// elliptical arcs.
#pragma once

#include <string>
#include <string_view>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

struct SvgOptions {
  /// The largest distance, in millimetres on the output page, of the cubic
  /// pieces of an elliptical arc from the exact arc (after every transform).
  /// Must be > 0; default 1e-6 mm.
  double arc_tolerance = 1e-6;
};

/// Reads SVG text: <path>, <line>, <polyline>, <polygon>, <rect>, <circle>,
/// <ellipse>, <g>, nested <svg>, <use>, transforms and viewBox. The result
/// is in mm (units "mm"), y up with the page's lower left at the origin
/// (y_out = page height − y), page = the file's width × height in mm when it
/// has a size. Each curve's origin names `name`, the element and its line,
/// e.g. `a.svg: <path id="p3"> (line 12)`. Inkscape layers or, without them,
/// several stroke colours become PatchSet::layers. What is left out (text,
/// images, hidden elements, clip paths, masks, CSS sheets, ...) is counted
/// in one note starting "NAME: left out: ".
/// Throws InputError naming `name`, the line, the element and the attribute
/// for malformed XML or attributes, a file whose root is not <svg>, a file
/// with nothing to draw, or an arc that cannot be drawn within the bound;
/// OptionError ("arc tolerance") for a tolerance that is not > 0.
PatchSet ReadSvg(const std::string& text, const std::string& name, const SvgOptions& options = {});

/// Whether text looks like SVG: its first non-blank characters are "<?xml",
/// "<svg" or "<!--"/"<!DOCTYPE svg" (the content sniffing of ReadPatchFile).
FDSURF_NODISCARD bool LooksLikeSvg(std::string_view text);

/// Keeps only the curves of one layer: `spec` is a layer's name or its
/// 1-based number. Afterwards set->layers holds that name alone and the kept
/// curves have layer 0. Works for any PatchSet with layers (SVG, G-code).
/// Throws InputError listing the available layers when none matches, or
/// saying the drawing has no layers.
void SelectLayer(PatchSet* set, const std::string& spec);

}  // namespace fdsurf::host
