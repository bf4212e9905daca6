// SPDX-License-Identifier: MIT
// Size group "stepping": every stepper, as a device that receives prepared
// tables links it (2-D and 3-D; 64- and 128-bit accumulators; curve, patch
// and adaptive). Also the object the hot-path check inspects
// (targets/tools/check_hot_path.sh): it must not call a divide, multiply or
// soft-float routine.
#include "../image/image.h"
#include "fdsurf/adaptive.h"
#include "fdsurf/forward_difference.h"

namespace fdsurf {
namespace image {
namespace {

volatile int32_t g_out;

struct Sink {
  template <int kDims>
  void operator()(uint32_t, const int32_t (&point)[kDims]) const {
    g_out = point[0];
  }
  template <int kDims>
  void operator()(uint32_t, uint32_t, const int32_t (&point)[kDims]) const {
    g_out = point[0];
  }
};

template <typename Acc, int kDims>
void StepAll(const PreparedCurve<kDims>& curve, const PreparedPatch<kDims>& patch,
             const PreparedAdaptiveCurve<kDims>& adaptive) {
  CurveStepper<Acc, kDims>(curve).ForEachPoint(Sink());
  PatchStepper<Acc, kDims>(patch).ForEachSLinePoint(Sink());
  PatchStepper<Acc, kDims>(patch).ForEachTLinePoint(Sink());
  AdaptiveCurveStepper<Acc, kDims>(adaptive).ForEachPoint(Sink());
}

// Tables the compiler cannot see through.
PreparedCurve<2> g_curve2;
PreparedPatch<2> g_patch2;
PreparedAdaptiveCurve<2> g_adaptive2;
PreparedCurve<3> g_curve3;
PreparedPatch<3> g_patch3;
PreparedAdaptiveCurve<3> g_adaptive3;

}  // namespace

__attribute__((noinline)) void RunSteppers() {
  StepAll<int64_t, 2>(g_curve2, g_patch2, g_adaptive2);
  StepAll<Int128, 2>(g_curve2, g_patch2, g_adaptive2);
  StepAll<int64_t, 3>(g_curve3, g_patch3, g_adaptive3);
  StepAll<Int128, 3>(g_curve3, g_patch3, g_adaptive3);
}

#if !FDSURF_SIZE_NO_MAIN
int RunImage(bool) {
  RunSteppers();
  return 0;
}
#endif

}  // namespace image
}  // namespace fdsurf
