// SPDX-License-Identifier: MIT
#include "fdsurf/host/text.h"

#include <algorithm>
#include <cstdio>

namespace fdsurf::host {

std::string FormatNumber(double v, int significant) {
  // 17 digits and an exponent fit: "-1.2345678901234567e-308" is 24 bytes.
  char text[40];
  std::snprintf(text, sizeof text, "%.*g", std::clamp(significant, 1, 17), v);
  return text;
}

std::string FormatPoint(const Point3& p, int significant) {
  return "(" + FormatNumber(p[0], significant) + ", " + FormatNumber(p[1], significant) + ", " +
         FormatNumber(p[2], significant) + ")";
}

}  // namespace fdsurf::host
