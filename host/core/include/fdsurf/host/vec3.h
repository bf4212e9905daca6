// SPDX-License-Identifier: MIT
// Small vector arithmetic on Point3 for the host's geometry code.
#pragma once

#include <cmath>

#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

inline Point3 Add(const Point3& a, const Point3& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline Point3 Sub(const Point3& a, const Point3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline Point3 Scale(const Point3& a, double k) { return {a[0] * k, a[1] * k, a[2] * k}; }
inline double Dot(const Point3& a, const Point3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline double Norm(const Point3& a) { return std::sqrt(Dot(a, a)); }
inline Point3 Cross(const Point3& a, const Point3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace fdsurf::host
