// SPDX-License-Identifier: MIT
// Patch sets as read from files: bicubic patches in double precision, in the
// units of the file, each remembering where it came from for error messages.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "fdsurf/basis.h"

namespace fdsurf::host {

using Point3 = std::array<double, 3>;

/// One bicubic patch: its basis and the 4×4 geometry matrix G per coordinate
/// (g[i][j], first index along s). For kPower, g[i][j] is the coefficient of
/// s^(3-i)·t^(3-j); for kHermite the layout of fdsurf/basis.h.
struct Patch {
  Basis basis = Basis::kBezier;
  std::array<std::array<Point3, 4>, 4> g{};
  /// Where the patch was defined, e.g. "teapot.bpt:2" or "net.json: surfaces[0] patch (1,2)".
  std::string origin;
};

/// One cubic curve segment x(u) = U·M·g, U = [u³ u² u 1], u in [0, 1]. For
/// kHermite g = (P0, P1, T0, T1); for kPower g[i] multiplies u^(3-i).
struct Curve {
  Basis basis = Basis::kHermite;
  std::array<Point3, 4> g{};
  std::string origin;
  /// Index into PatchSet::layers (0 when the file has no layers).
  int layer = 0;
  /// A straight segment from its first to its last point (an SVG `L`, a
  /// G-code `G1`): `stream` may send it as a MOVE instead of a CURVE.
  bool straight = false;
};

struct PatchSet {
  /// "mm" or "in"; empty when the file does not say (BPT).
  std::string units;
  std::vector<Patch> patches;
  /// Curves to evaluate on their own (JSON "curves", docs/constructions.md).
  std::vector<Curve> curves;
  /// What the constructions found, one line each (join classes, scale
  /// factors, approximation bounds); `fdsurf check` prints them.
  std::vector<std::string> notes;
  /// Names of the drawing's layers (Inkscape layers, stroke colours, G-code
  /// tool changes), in drawing order; Curve::layer indexes it. Empty: one
  /// unnamed layer. Between layers the pen is changed (a pause).
  std::vector<std::string> layers;
  /// The file's own page, width × height in its units, with the origin at
  /// its lower left (an SVG's width and height); nullopt when it has none.
  std::optional<std::array<double, 2>> page;
  /// The curves are a program whose order is the user's (G-code): planners
  /// keep it instead of reordering.
  bool keep_order = false;
};

}  // namespace fdsurf::host
