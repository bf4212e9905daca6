#include "bench.h"

#include "port.h"
#include "report.h"

namespace fdsurf {
namespace image {
namespace {

// Every loop writes its points here, so that no compiler can drop the work.
volatile int32_t g_sink[3];

// Control points in quanta: (0,0,0), (10000,40000,5000), (50000,45000,15000),
// (60000,0,20000).
const int32_t kBenchControl[3][4] = {
    {0, 10000, 50000, 60000}, {0, 40000, 45000, 0}, {0, 5000, 15000, 20000}};

void PutBenchLine(const char* name, int dims, uint32_t points, uint32_t acc_bits) {
  PutString("bench ");
  PutString(name);
  PutString(dims == 2 ? " 2d" : " 3d");
  PutString(" points ");
  PutUnsigned(points);
  PutString(" acc ");
  PutUnsigned(acc_bits);
  PutString("\n");
}

template <int kDims>
struct Sink {
  void operator()(uint32_t, const int32_t (&point)[kDims]) const {
    for (int c = 0; c < kDims; ++c) g_sink[c] = point[c];
  }
  void operator()(uint32_t, uint32_t, const int32_t (&point)[kDims]) const {
    for (int c = 0; c < kDims; ++c) g_sink[c] = point[c];
  }
};

template <int kDims>
void BenchEngineCurve(const char* name, const PreparedCurve<kDims>& curve) {
  PortMark();
  if (curve.format.acc_bits == 64) {
    CurveStepper<int64_t, kDims>(curve).ForEachPoint(Sink<kDims>());
  } else {
    CurveStepper<Int128, kDims>(curve).ForEachPoint(Sink<kDims>());
  }
  PortMark();
  PutBenchLine(name, kDims, curve.steps + 1u, curve.format.acc_bits);
}

template <int kDims>
void BenchEnginePatch(const PreparedPatch<kDims>& patch) {
  PortMark();
  if (patch.format.acc_bits == 64) {
    PatchStepper<int64_t, kDims>(patch).ForEachSLinePoint(Sink<kDims>());
  } else {
    PatchStepper<Int128, kDims>(patch).ForEachSLinePoint(Sink<kDims>());
  }
  PortMark();
  PutBenchLine("engine-patch", kDims,
               static_cast<uint32_t>(patch.steps_s + 1u) * (patch.steps_t + 1u),
               patch.format.acc_bits);
}

void BenchEngineAdaptive(const PreparedAdaptiveCurve<2>& curve) {
  uint32_t points = 0;
  const auto sink = [&points](uint32_t, const int32_t(&point)[2]) {
    g_sink[0] = point[0];
    g_sink[1] = point[1];
    ++points;
  };
  PortMark();
  if (curve.format.acc_bits == 64) {
    AdaptiveCurveStepper<int64_t, 2>(curve).ForEachPoint(sink);
  } else {
    AdaptiveCurveStepper<Int128, 2>(curve).ForEachPoint(sink);
  }
  PortMark();
  PutBenchLine("engine-adaptive", 2, points, curve.format.acc_bits);
}

// --- The alternatives, as a firmware author would write them. ---

inline int32_t RoundFloat(float x) { return static_cast<int32_t>(x >= 0.0f ? x + 0.5f : x - 0.5f); }

inline float Lerp(float a, float b, float t) { return a + (b - a) * t; }

// De Casteljau's algorithm in float per point (Marlin's G5 evaluates its
// Bézier segments this way).
template <int kDims>
void BenchDeCasteljau() {
  float p[kDims][4];
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 4; ++k) p[c][k] = static_cast<float>(kBenchControl[c][k]);
  }
  const float step = 1.0f / kBenchSteps;
  PortMark();
  for (uint16_t i = 0; i <= kBenchSteps; ++i) {
    const float t = static_cast<float>(i) * step;
    for (int c = 0; c < kDims; ++c) {
      const float a = Lerp(p[c][0], p[c][1], t);
      const float b = Lerp(p[c][1], p[c][2], t);
      const float d = Lerp(p[c][2], p[c][3], t);
      g_sink[c] = RoundFloat(Lerp(Lerp(a, b, t), Lerp(b, d, t), t));
    }
  }
  PortMark();
  PutBenchLine("float-de-casteljau", kDims, kBenchSteps + 1u, 0);
}

// Horner's rule in float on power coefficients formed once.
template <int kDims>
void BenchFloatHorner() {
  float a[kDims][4];
  for (int c = 0; c < kDims; ++c) {
    const float p0 = static_cast<float>(kBenchControl[c][0]);
    const float p1 = static_cast<float>(kBenchControl[c][1]);
    const float p2 = static_cast<float>(kBenchControl[c][2]);
    const float p3 = static_cast<float>(kBenchControl[c][3]);
    a[c][0] = -p0 + 3.0f * p1 - 3.0f * p2 + p3;
    a[c][1] = 3.0f * p0 - 6.0f * p1 + 3.0f * p2;
    a[c][2] = -3.0f * p0 + 3.0f * p1;
    a[c][3] = p0;
  }
  const float step = 1.0f / kBenchSteps;
  PortMark();
  for (uint16_t i = 0; i <= kBenchSteps; ++i) {
    const float t = static_cast<float>(i) * step;
    for (int c = 0; c < kDims; ++c) {
      g_sink[c] = RoundFloat(((a[c][0] * t + a[c][1]) * t + a[c][2]) * t + a[c][3]);
    }
  }
  PortMark();
  PutBenchLine("float-horner", kDims, kBenchSteps + 1u, 0);
}

// Horner's rule in fixed point: power coefficients in quanta with 16
// fractional bits (int64_t), t in Q16 advanced by a constant, 64-bit products.
template <int kDims>
void BenchFixedHorner() {
  int64_t a[kDims][4];
  for (int c = 0; c < kDims; ++c) {
    const int64_t p0 = static_cast<int64_t>(kBenchControl[c][0]) * 65536;
    const int64_t p1 = static_cast<int64_t>(kBenchControl[c][1]) * 65536;
    const int64_t p2 = static_cast<int64_t>(kBenchControl[c][2]) * 65536;
    const int64_t p3 = static_cast<int64_t>(kBenchControl[c][3]) * 65536;
    a[c][0] = -p0 + 3 * p1 - 3 * p2 + p3;
    a[c][1] = 3 * p0 - 6 * p1 + 3 * p2;
    a[c][2] = -3 * p0 + 3 * p1;
    a[c][3] = p0;
  }
  const int32_t dt = 65536 / kBenchSteps;
  int32_t t = 0;
  PortMark();
  for (uint16_t i = 0; i <= kBenchSteps; ++i, t += dt) {
    for (int c = 0; c < kDims; ++c) {
      int64_t acc = a[c][0];
      acc = ((acc * t) >> 16) + a[c][1];
      acc = ((acc * t) >> 16) + a[c][2];
      acc = ((acc * t) >> 16) + a[c][3];
      g_sink[c] = static_cast<int32_t>((acc + 32768) >> 16);
    }
  }
  PortMark();
  PutBenchLine("fixed-horner", kDims, kBenchSteps + 1u, 64);
}

}  // namespace

int64_t BenchControlRaw(int coordinate, int k, bool wide) {
  const int64_t quanta = kBenchControl[coordinate][k];
  // wide: × 2^11, so 60000 quanta become about 2^27.
  return quanta * (int64_t{1} << (wide ? 16 + 11 : 16));
}

#if FDSURF_IMAGE_SETUP
void SetupBenchCurve2(bool wide, PreparedCurve<2>* out) {
  CurveGeometry1 geometry[2];
  BenchCurveGeometry(wide, geometry);
  *out = PreparedCurve<2>{};
  const uint16_t steps = wide ? kBenchWideSteps : kBenchSteps;
  if (PrepareCurve(geometry, Basis::kBezier, steps, PrepareOptions(), out) != Status::kOk) {
    PortExit(3);
  }
}

void SetupBenchCurve3(PreparedCurve<3>* out) {
  CurveGeometry1 geometry[3];
  BenchCurveGeometry(false, geometry);
  *out = PreparedCurve<3>{};
  if (PrepareCurve(geometry, Basis::kBezier, kBenchSteps, PrepareOptions(), out) != Status::kOk) {
    PortExit(3);
  }
}

template <int kDims>
void SetupBenchPatch(PreparedPatch<kDims>* out) {
  PatchGeometry1 geometry[kDims];
  for (int c = 0; c < kDims; ++c) {
    for (int k = 0; k < 16; ++k) {
      geometry[c].g[k / 4][k % 4] = GeometryFixed::FromRaw(TeapotRaw(kBenchTeapotPatch, c, k));
    }
  }
  *out = PreparedPatch<kDims>{};
  if (PreparePatch(geometry, Basis::kBezier, kBenchGrid, kBenchGrid, PrepareOptions(), out) !=
      Status::kOk) {
    PortExit(3);
  }
}

void SetupBenchPatch2(PreparedPatch<2>* out) { SetupBenchPatch(out); }
void SetupBenchPatch3(PreparedPatch<3>* out) { SetupBenchPatch(out); }

void SetupBenchAdaptive2(PreparedAdaptiveCurve<2>* out) {
  CurveGeometry1 geometry[2];
  BenchCurveGeometry(false, geometry);
  PowerCurve1 power[2];
  AdaptiveSettings settings;
  settings.tolerance_q8 = 50 * 256;  // 0.05 mm at Q = 1 µm
  *out = PreparedAdaptiveCurve<2>{};
  if (CurvePowerCoefficients(geometry, Basis::kBezier, power) != Status::kOk ||
      PrepareAdaptiveCurve(power, settings, out) != Status::kOk) {
    PortExit(3);
  }
}

#endif  // FDSURF_IMAGE_SETUP

void RunBench(const BenchSource& source) {
#if FDSURF_IMAGE_SETUP
  if (source.measure_setup) {
    // Set-up cost: one patch and one curve from geometry to table.
    PreparedPatch<3> patch;
    PortMark();
    SetupBenchPatch3(&patch);
    PortMark();
    PutBenchLine("setup-patch", 3, 1, patch.format.acc_bits);
    PreparedCurve<2> curve;
    PortMark();
    SetupBenchCurve2(false, &curve);
    PortMark();
    PutBenchLine("setup-curve", 2, 1, curve.format.acc_bits);
  }
#endif
  {
    PreparedCurve<2> curve;
    source.curve2(false, &curve);
    BenchEngineCurve("engine-curve", curve);
    BenchDeCasteljau<2>();
    BenchFloatHorner<2>();
    BenchFixedHorner<2>();
    source.curve2(true, &curve);
    BenchEngineCurve("engine-curve-wide", curve);
  }
  {
    PreparedCurve<3> curve;
    source.curve3(&curve);
    BenchEngineCurve("engine-curve", curve);
    BenchDeCasteljau<3>();
    BenchFloatHorner<3>();
    BenchFixedHorner<3>();
  }
  {
    PreparedPatch<2> patch;
    source.patch2(&patch);
    BenchEnginePatch(patch);
  }
  if (source.patch3 != nullptr) {
    PreparedPatch<3> patch;
    source.patch3(&patch);
    BenchEnginePatch(patch);
  }
  {
    PreparedAdaptiveCurve<2> curve;
    source.adaptive2(&curve);
    BenchEngineAdaptive(curve);
  }
}

}  // namespace image
}  // namespace fdsurf
