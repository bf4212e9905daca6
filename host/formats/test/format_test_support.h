// SPDX-License-Identifier: MIT
// What the readers' tests share: the message of a refusal, and a Bézier curve
// evaluated from its Bernstein form (written here, independent of the readers
// and of the engine, so the tests do not check the code with itself).
#pragma once

#include <functional>
#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host::format_test {

/// The message of the InputError that `f` throws; "(no error)" when it
/// throws none (another exception goes on to the test).
inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

/// The cubic Bézier curve `c` (c.g the four control points) at u in [0, 1].
inline Point3 BezierAt(const Curve& c, double u) {
  const double v = 1 - u;
  const double b[4] = {v * v * v, 3 * u * v * v, 3 * u * u * v, u * u * u};
  Point3 p{0, 0, 0};
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t k = 0; k < 3; ++k) p[k] += b[i] * c.g[i][k];
  }
  return p;
}

}  // namespace fdsurf::host::format_test
