// SPDX-License-Identifier: MIT
// Numbers as text for messages, file headers and SVG/HPGL coordinates: one
// format everywhere, so that a value reads the same in an error, a report and
// an output file.
#pragma once

#include <string>

namespace fdsurf::host {

/// `v` with at most 6 significant digits and no trailing zeros, as printf's
/// "%.6g" ("0.05", "200", "1.5e-07", "nan", "inf").
std::string FormatNumber(double v);

}  // namespace fdsurf::host
