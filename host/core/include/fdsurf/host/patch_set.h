// SPDX-License-Identifier: MIT
// Patch sets as read from files: bicubic patches in double precision, in the
// units of the file, each remembering where it came from for error messages.
#pragma once

#include <array>
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
};

}  // namespace fdsurf::host
