// SPDX-License-Identifier: MIT
// Numbers as text for messages, reports, file headers and SVG/HPGL/CSV
// coordinates: one formatting routine, so that a value reads the same in an
// error, a report and an output file.
#pragma once

#include <string>

#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// `v` with at most `significant` significant digits and no trailing zeros,
/// as printf's "%.Ng" ("0.05", "200", "1.5e-07", "nan", "inf"). 6 digits
/// for messages and drawings, 9 where a message must tell close values
/// apart (construction input), 17 to print a double exactly (CSV of the
/// reference). `significant` is 1..17.
std::string FormatNumber(double v, int significant = 6);

/// "(x, y, z)", each as FormatNumber(c, significant).
std::string FormatPoint(const Point3& p, int significant = 9);

}  // namespace fdsurf::host
