// SPDX-License-Identifier: MIT
// Points per second for the teapot's bicubic grids: the fixed-point engine
// against, in the same run, the double reference by Horner per point and by
// de Casteljau per point, and the engine's own set-up cost.
//
// Run: build/bench/fdsurf_bench (or bench/report.py for the table in
// docs/performance.md).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {
namespace {

const PatchSet& Teapot() {
  static const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/teapot.bpt");
  return set;
}

const Quantum& DefaultQuantum() {
  static const Quantum q = Quantum::Parse("0.001");
  return q;
}

std::int64_t PointsPerRun(int n) {
  return static_cast<std::int64_t>(Teapot().patches.size()) * (n + 1) * (n + 1);
}

// Stepping only: the tables are prepared once, outside the timed loop.
void BM_FixedStepping(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<PreparedPatch<3>> prepared;
  for (const Patch& patch : Teapot().patches) {
    prepared.push_back(PrepareFixedPatch(patch, DefaultQuantum(), n, n));
  }
  for (auto _ : state) {
    std::int64_t checksum = 0;
    for (const auto& p : prepared) {
      ForEachGridPoint(p, [&](std::uint32_t, std::uint32_t, const std::int32_t(&k)[3]) {
        checksum += k[0] + k[1] + k[2];
      });
    }
    benchmark::DoNotOptimize(checksum);
  }
  state.SetItemsProcessed(state.iterations() * PointsPerRun(n));
  state.counters["acc_bits"] = prepared[0].format.acc_bits;
}

// Set-up included: what one patch costs from geometry to the last point.
void BM_FixedSetupAndStepping(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) {
    std::int64_t checksum = 0;
    for (const Patch& patch : Teapot().patches) {
      const PreparedPatch<3> p = PrepareFixedPatch(patch, DefaultQuantum(), n, n);
      ForEachGridPoint(p, [&](std::uint32_t, std::uint32_t, const std::int32_t(&k)[3]) {
        checksum += k[0] + k[1] + k[2];
      });
    }
    benchmark::DoNotOptimize(checksum);
  }
  state.SetItemsProcessed(state.iterations() * PointsPerRun(n));
}

// Set-up alone, per patch (items are patches here, not points).
void BM_FixedSetupOnly(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) {
    for (const Patch& patch : Teapot().patches) {
      benchmark::DoNotOptimize(PrepareFixedPatch(patch, DefaultQuantum(), n, n));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(Teapot().patches.size()));
}

// The baselines round to whole quanta too, so every variant produces the same
// kind of output.
void BM_DoubleHorner(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<PowerCoefficients> coefficients;
  for (const Patch& patch : Teapot().patches) coefficients.push_back(CoefficientsOf(patch));
  const double inverse_q = 1.0 / DefaultQuantum().value();
  for (auto _ : state) {
    std::int64_t checksum = 0;
    for (const auto& c : coefficients) {
      for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
          const Point3 p =
              EvaluateHorner(c, static_cast<double>(i) / n, static_cast<double>(j) / n);
          checksum += std::llround(p[0] * inverse_q) + std::llround(p[1] * inverse_q) +
                      std::llround(p[2] * inverse_q);
        }
      }
    }
    benchmark::DoNotOptimize(checksum);
  }
  state.SetItemsProcessed(state.iterations() * PointsPerRun(n));
}

void BM_DoubleDeCasteljau(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double inverse_q = 1.0 / DefaultQuantum().value();
  for (auto _ : state) {
    std::int64_t checksum = 0;
    for (const Patch& patch : Teapot().patches) {
      for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
          const Point3 p =
              EvaluateDeCasteljau(patch, static_cast<double>(i) / n, static_cast<double>(j) / n);
          checksum += std::llround(p[0] * inverse_q) + std::llround(p[1] * inverse_q) +
                      std::llround(p[2] * inverse_q);
        }
      }
    }
    benchmark::DoNotOptimize(checksum);
  }
  state.SetItemsProcessed(state.iterations() * PointsPerRun(n));
}

BENCHMARK(BM_FixedStepping)->Arg(64)->Arg(256)->Arg(1024)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FixedSetupAndStepping)->Arg(64)->Arg(256)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FixedSetupOnly)->Arg(64)->Arg(256)->Arg(1024)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DoubleHorner)->Arg(64)->Arg(256)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DoubleDeCasteljau)->Arg(64)->Arg(256)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace fdsurf::host

BENCHMARK_MAIN();
