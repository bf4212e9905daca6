// SPDX-License-Identifier: MIT
#include "fdsurf/host/text.h"

#include <cstdio>

namespace fdsurf::host {

std::string FormatNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

}  // namespace fdsurf::host
