// SPDX-License-Identifier: MIT
#include "bench.h"

#include "port.h"
#include "report.h"

#if FDSURF_IMAGE_SETUP
#include "fdsurf/motion/path_generator.h"
#endif

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
  PutString(FDSURF_TEXT("bench "));
  PutString(name);
  PutString(dims == 2 ? FDSURF_TEXT(" 2d") : FDSURF_TEXT(" 3d"));
  PutString(FDSURF_TEXT(" points "));
  PutUnsigned(points);
  PutString(FDSURF_TEXT(" acc "));
  PutUnsigned(acc_bits);
  PutString(FDSURF_TEXT("\n"));
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
  } else if (!kImageWideAccumulators) {
    PortExit(4);
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
  } else if (!kImageWideAccumulators) {
    PortExit(4);
  } else {
    PatchStepper<Int128, kDims>(patch).ForEachSLinePoint(Sink<kDims>());
  }
  PortMark();
  PutBenchLine(FDSURF_TEXT("engine-patch"), kDims,
               static_cast<uint32_t>(patch.steps_s + 1u) * (patch.steps_t + 1u),
               patch.format.acc_bits);
}

void BenchEngineAdaptive(const PreparedAdaptiveCurve<2>& curve) {
  // The same stepping function as the report, without digests: per point a
  // store and a null-pointer test (report.cc).
  PortMark();
  const uint32_t points = StepAdaptive<2>(curve, nullptr, nullptr);
  PortMark();
  PutBenchLine(FDSURF_TEXT("engine-adaptive"), 2, points, curve.format.acc_bits);
}

// Where the engine's time goes, for the 2-D curve: the row-add update
// alone, and the rounding to whole quanta alone, per point (the engine's own
// inline functions, on the same table in the stepper's format: word-aligned
// where the planner allows it, docs/precision.md).
#if !FDSURF_IMAGE_SMALL_BENCH
__attribute__((noinline)) void BenchEngineParts(const PreparedCurve<2>& curve) {
  if (curve.format.acc_bits != 64) return;
  int64_t d[2][4];
  for (int c = 0; c < 2; ++c) {
    for (int k = 0; k < 4; ++k) internal::Load(curve.d[c][k], curve.format, k == 0, &d[c][k]);
  }
  PortMark();
  for (uint16_t i = 0; i <= curve.steps; ++i) {
    for (int c = 0; c < 2; ++c) {
      internal::Step(d[c]);
      g_sink[c] = static_cast<int32_t>(d[c][0]);
    }
  }
  PortMark();
  PutBenchLine(FDSURF_TEXT("engine-step-only"), 2, curve.steps + 1u, 64);
  const int frac_bits = curve.format.frac_bits;
  const bool word_aligned = curve.format.word_aligned != 0;
  PortMark();
  for (uint16_t i = 0; i <= curve.steps; ++i) {
    for (int c = 0; c < 2; ++c) {
      g_sink[c] = internal::PositionQuanta(d[c][0] + i, word_aligned, frac_bits);
    }
  }
  PortMark();
  PutBenchLine(FDSURF_TEXT("engine-round-only"), 2, curve.steps + 1u, 64);
}
#endif

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
  PutBenchLine(FDSURF_TEXT("float-de-casteljau"), kDims, kBenchSteps + 1u, 0);
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
  PutBenchLine(FDSURF_TEXT("float-horner"), kDims, kBenchSteps + 1u, 0);
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
  PutBenchLine(FDSURF_TEXT("fixed-horner"), kDims, kBenchSteps + 1u, 64);
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
  const uint16_t steps = wide ? kBenchWideSteps : kBenchSteps;
  if (PrepareCurve(geometry, Basis::kBezier, steps, PrepareOptions(), out) != Status::kOk) {
    PortExit(3);
  }
}

void SetupBenchCurve3(PreparedCurve<3>* out) {
  CurveGeometry1 geometry[3];
  BenchCurveGeometry(false, geometry);
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
  if (CurvePowerCoefficients(geometry, Basis::kBezier, power) != Status::kOk ||
      PrepareAdaptiveCurve(power, settings, out) != Status::kOk) {
    PortExit(3);
  }
}

#endif  // FDSURF_IMAGE_SETUP

// The table under measurement lives here rather than on the stack: the
// set-up below it needs about 6 KB of stack on AVR, and the ATmega2560 has
// 8 KB of RAM for everything.
union BenchTable {
  PreparedCurve<2> curve2;
  PreparedCurve<3> curve3;
  PreparedPatch<2> patch2;
#if FDSURF_IMAGE_SETUP
  PreparedPatch<3> patch3;
#endif
  PreparedAdaptiveCurve<2> adaptive2;
  BenchTable() : curve2() {}
};
BenchTable g_table;
#if FDSURF_IMAGE_SETUP
__attribute__((noinline)) void BenchSetup() {
  // Set-up cost: one patch and one curve from geometry to table.
  PreparedPatch<3>& patch = g_table.patch3;
  PortMark();
  SetupBenchPatch3(&patch);
  PortMark();
  PutBenchLine(FDSURF_TEXT("setup-patch"), 3, 1, patch.format.acc_bits);
  PreparedCurve<2>& curve = g_table.curve2;
  PortMark();
  SetupBenchCurve2(false, &curve);
  PortMark();
  PutBenchLine(FDSURF_TEXT("setup-curve"), 2, 1, curve.format.acc_bits);
}
#endif

__attribute__((noinline)) void BenchCurves2(const BenchSource& source) {
  PreparedCurve<2>& curve = g_table.curve2;
  source.curve2(false, &curve);
  BenchEngineCurve(FDSURF_TEXT("engine-curve"), curve);
#if !FDSURF_IMAGE_SMALL_BENCH
  if (source.parts) BenchEngineParts(curve);
#endif
  BenchDeCasteljau<2>();
  BenchFloatHorner<2>();
  BenchFixedHorner<2>();
  if (source.wide) {
    source.curve2(true, &curve);
    BenchEngineCurve(FDSURF_TEXT("engine-curve-wide"), curve);
  }
}

#if !FDSURF_IMAGE_SMALL_BENCH
__attribute__((noinline)) void BenchCurves3(const BenchSource& source) {
  PreparedCurve<3>& curve = g_table.curve3;
  source.curve3(&curve);
  BenchEngineCurve(FDSURF_TEXT("engine-curve"), curve);
  BenchDeCasteljau<3>();
  BenchFloatHorner<3>();
  BenchFixedHorner<3>();
}
#endif

__attribute__((noinline)) void BenchPatch2(const BenchSource& source) {
  PreparedPatch<2>& patch = g_table.patch2;
  source.patch2(&patch);
  BenchEnginePatch(patch);
}

#if FDSURF_IMAGE_SETUP
__attribute__((noinline)) void BenchPatch3(const BenchSource& source) {
  PreparedPatch<3>& patch = g_table.patch3;
  source.patch3(&patch);
  BenchEnginePatch(patch);
}
#endif

__attribute__((noinline)) void BenchAdaptive(const BenchSource& source) {
  PreparedAdaptiveCurve<2>& curve = g_table.adaptive2;
  source.adaptive2(&curve);
  BenchEngineAdaptive(curve);
}

#if FDSURF_IMAGE_SETUP
// The device's validation on arrival (motion::ValidateCommand), its worst
// cases: a PATCH frame whose every line's hull crosses the travel (x rises
// and falls along one parameter, y along the other: control points at
// 20 000 steps, lines below 15 250, travel 16 000), and one CURVE grazing the
// edge, which takes many hull tests.
// "points" is the lines planned, "acc" the hull tests.
protocol::MachineConfig g_validate_config;
protocol::Command g_validate_command;

__attribute__((noinline)) void BenchValidateOne(const char* name) {
  motion::ValidationWork work = {0, 0, 0};
  uint8_t detail = 0;
  PortMark();
  const protocol::ErrorCode error =
      motion::ValidateCommand<2>(g_validate_command, g_validate_config, &detail, &work);
  PortMark();
  if (error != protocol::ErrorCode::kNone) PortExit(5);
  PutBenchLine(name, 2, work.lines + work.prepared_lines, work.hull_tests);
}

__attribute__((noinline)) void BenchValidate() {
  protocol::MachineConfig& config = g_validate_config;
  config = protocol::MachineConfig();
  config.axes = 2;
  config.travel_steps[0] = config.travel_steps[1] = 16000;
  config.max_rate = 8000;
  config.accel = 160000;
  const int32_t bump[4] = {1000, 20000, 20000, 1000};
  protocol::Command& command = g_validate_command;
  command = protocol::Command();
  command.type = protocol::MessageType::kPatch;
  protocol::PatchCommand& patch = command.body.patch;
  patch.basis = Basis::kBezier;
  patch.dims = 2;
  patch.tolerance_q8 = 512;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      patch.geometry[0].g[i][j] = GeometryFixed::FromRaw(int64_t{bump[j]} * 65536);
      patch.geometry[1].g[i][j] = GeometryFixed::FromRaw(int64_t{bump[i]} * 65536);
    }
  }
  patch.lines_s = patch.lines_t = kBenchValidateLines;
  BenchValidateOne(FDSURF_TEXT("validate-frame"));
  // y = T + (0, 17 142, 64 269, 0) · 2^-16 steps in Bézier form: its top is
  // 0.22 · 2^-16 step inside T + 1/2; 19 hull tests (the most of 3000
  // random grazes within 3·2^-16 step of the edge is 29, device_motion_test).
  command = protocol::Command();
  command.type = protocol::MessageType::kCurve;
  protocol::CurveCommand& curve = command.body.curve;
  curve.basis = Basis::kBezier;
  curve.dims = 2;
  curve.tolerance_q8 = 512;
  const int64_t graze[4] = {0, 17142, 64269, 0};
  for (int k = 0; k < 4; ++k) {
    curve.geometry[0].g[k] = GeometryFixed::FromRaw((int64_t{1000} + 4000 * k) * 65536);
    curve.geometry[1].g[k] = GeometryFixed::FromRaw(int64_t{16000} * 65536 + graze[k]);
  }
  BenchValidateOne(FDSURF_TEXT("validate-graze"));
  // The same line with room to spare: the planner alone, no hull test, so
  // the difference is the 19 hull tests.
  config.travel_steps[1] = 17000;
  BenchValidateOne(FDSURF_TEXT("validate-inside"));
  // The same line as the host would send it (PREPARED_CURVE: its power
  // coefficients and the planner's level, found here outside the marks):
  // the check at that level instead of the planner, no hull test.
  CurveGeometry1 geometry[2] = {curve.geometry[0], curve.geometry[1]};
  PowerCurve1 power[2];
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = curve.tolerance_q8;
  PreparedAdaptiveCurve<2> planned;
  if (CurvePowerCoefficients(geometry, curve.basis, power) != Status::kOk ||
      PrepareAdaptiveCurve(power, settings, &planned) != Status::kOk) {
    PortExit(5);
  }
  command = protocol::Command();
  command.type = protocol::MessageType::kPreparedCurve;
  protocol::PreparedCurveCommand& prepared = command.body.prepared_curve;
  prepared.dims = 2;
  prepared.level = planned.finest_level;
  prepared.tolerance_q8 = settings.tolerance_q8;
  prepared.power[0] = power[0];
  prepared.power[1] = power[1];
  BenchValidateOne(FDSURF_TEXT("validate-prepared"));
}
#endif

void RunBench(const BenchSource& source) {
#if FDSURF_IMAGE_SETUP
  if (source.measure_setup) BenchSetup();
#endif
  BenchCurves2(source);
#if !FDSURF_IMAGE_SMALL_BENCH
  if (source.curve3 != nullptr) BenchCurves3(source);
#endif
  BenchPatch2(source);
#if FDSURF_IMAGE_SETUP
  if (source.patch3 != nullptr) BenchPatch3(source);
#endif
  BenchAdaptive(source);
#if FDSURF_IMAGE_SETUP
  // Validation plans every line (the set-up): not on the 328P, whose report
  // the host's --small reproduces.
  if (source.measure_setup) BenchValidate();
#endif
}

}  // namespace image
}  // namespace fdsurf
