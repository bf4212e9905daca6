// SPDX-License-Identifier: MIT
// Instantiates every stepper template under the core's freestanding flags, so
// that header-only code is held to the same rules as the .cc files.
#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"

namespace fdsurf {

template class CurveStepper<int64_t, 1>;
template class CurveStepper<int64_t, 2>;
template class CurveStepper<int64_t, 3>;
template class CurveStepper<Int128, 1>;
template class CurveStepper<Int128, 2>;
template class CurveStepper<Int128, 3>;
template class PatchStepper<int64_t, 2>;
template class PatchStepper<int64_t, 3>;
template class PatchStepper<Int128, 2>;
template class PatchStepper<Int128, 3>;
template class AdaptiveCurveStepper<int64_t, 2>;
template class AdaptiveCurveStepper<int64_t, 3>;
template class AdaptiveCurveStepper<Int128, 2>;
template class AdaptiveCurveStepper<Int128, 3>;

namespace {
struct CountingSink {
  uint32_t count;
  template <int kDims>
  void operator()(uint32_t, uint32_t, const int32_t (&)[kDims]) {
    ++count;
  }
};
}  // namespace

// Not called; forces the member templates to compile freestanding too.
uint32_t FreestandingCheckCountPoints(const PreparedPatch<3>& patch) {
  CountingSink sink{0};
  PatchStepper<Int128, 3>(patch).ForEachSLinePoint(sink);
  PatchStepper<int64_t, 3>(patch).ForEachTLinePoint(sink);
  return sink.count;
}

uint32_t FreestandingCheckCountAdaptivePoints(const PreparedAdaptiveCurve<2>& curve) {
  uint32_t count = 0;
  const auto counter = [&count](uint32_t, const int32_t(&)[2]) { ++count; };
  AdaptiveCurveStepper<Int128, 2>(curve).ForEachPoint(counter);
  AdaptiveCurveStepper<int64_t, 2>(curve).ForEachPoint(counter);
  return count;
}

}  // namespace fdsurf
