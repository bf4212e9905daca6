// SPDX-License-Identifier: MIT
// Reading G-code programs (plotters, Grbl, Marlin, LinuxCNC) as curves: what
// the pen draws, in program order (docs/formats.md, "G-code").
#pragma once

#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// How a program is read. Lengths are in the program's unit (the first of
/// G20/G21 it uses; millimetres when it names neither).
struct GcodeReadOptions {
  /// Each cubic that stands for a piece of a G2/G3 arc lies within this
  /// distance of the exact arc (a proven bound, conic_arc.h). Must be > 0.
  double arc_tolerance = 1e-6;
  /// With Z words in the program, the pen is down while Z ≤ this.
  double pen_z_threshold = 0;
  /// With `M280 P<n> S<angle>` in the program (Marlin servo), the pen is down
  /// while the angle is below this (degrees).
  double servo_down_below = 50;
  /// Lines that start with `/` (block delete) are skipped, as a controller
  /// with its block-delete switch on does; false runs them.
  bool skip_block_delete = true;
};

/// Reads a G-code program. `name` is used in messages and origins
/// ("prog.gcode:12"). The result has one Curve per drawn move, in program
/// order (keep_order = true): lines as straight kBezier curves, G5/G5.1
/// exactly as cubic Bézier curves, G2/G3 arcs as cubic pieces within
/// options.arc_tolerance; units "mm" or "in"; a layer per tool change
/// (`T<n> M6`) or pause (M0/M1) when the program has them; notes for every
/// code it ignored (with its first line). Throws InputError naming the line
/// and the word for malformed words, a wrong checksum, codes that move in a
/// way the reader does not follow (canned cycles, probing, threading, other
/// coordinate systems), inconsistent arcs, or a program that draws nothing;
/// OptionError ("arc tolerance") for a tolerance that is not > 0.
PatchSet ReadGcode(const std::string& text, const std::string& name,
                   const GcodeReadOptions& options = {});

}  // namespace fdsurf::host
