// SPDX-License-Identifier: MIT
// Nanoseconds per point for the teapot's bicubic grids: the fixed-point
// engine against the strongest like-for-like baselines, all in one run, with
// set-up and stepping timed apart:
//
// - HornerFma, HornerFmaQuanta: power coefficients per patch (set-up), then a
//   Horner in s and t per point, inline, with fused multiply-adds where the
//   CPU has them; doubles out, and rounded to whole quanta.
// - HornerRowsFmaQuanta: the same, the s-polynomial evaluated once per row.
// - DoubleFdQuanta: the engine's own algorithm in double (the difference
//   table in floating point, additions per point), rounded to quanta.
// - OcctD0, OcctIsoCache: OpenCASCADE's Geom_BezierSurface::D0 per point, and
//   its grid path (an iso curve per row by BSplSLib::Iso, BSplCLib_Cache::D0
//   along it). Built when OCCT is found (FDSURF_BENCH_OCCT).
// - SislS1506: SISL's grid evaluator on the patch as a B-spline surface.
//   Built when SISL is found (FDSURF_BENCH_SISL).
//
// OCCT (LGPL) and SISL (AGPL) are linked into this executable only, never
// into anything installed.
//
// Before timing anything, main() checks every method's points against the
// double reference (de Casteljau, host/reference) and the rounded ones
// against the engine's integers, and exits non-zero if one disagrees.
//
// Run: build/bench/fdsurf_bench, or bench/report.py for the tables in
// docs/performance.md.
#include <benchmark/benchmark.h>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"

#if FDSURF_BENCH_OCCT
#include <BSplCLib_Cache.hxx>
#include <BSplSLib.hxx>
#include <Geom_BezierSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <gp_Pnt.hxx>
#endif

#if FDSURF_BENCH_SISL
#include <sisl.h>
#endif

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

std::int64_t PointsPerPatch(int n) { return static_cast<std::int64_t>(n + 1) * (n + 1); }

// Every method M provides
//   using Coordinate = double or std::int32_t (whole quanta);
//   struct Prepared;  static Prepared Prepare(const Patch&, int n);
//   template <typename Sink> static void Step(Prepared&, int n, Sink&&),
// where Step calls sink(i, j, const Coordinate (&)[3]) for every grid point
// (i along s, j along t, n steps each way).

// ---------------------------------------------------------------------------
// The engine.

struct FixedEngine {
  using Coordinate = std::int32_t;
  using Prepared = PreparedPatch<3>;
  static Prepared Prepare(const Patch& patch, int n) {
    return PrepareFixedPatch(patch, DefaultQuantum(), n, n);
  }
  template <typename Sink>
  static void Step(const Prepared& p, int /*n*/, Sink&& sink) {
    ForEachGridPoint(p, sink);
  }
};

// ---------------------------------------------------------------------------
// Rounding a double in quanta to the nearest whole quantum by the current
// rounding mode (to nearest, ties to even, unless a program changes it):
// one cvtsd2si (SSE2, part of x86-64). std::llround (ties away from zero) and
// std::lrint are library calls here (math-errno); adding 0.5 and truncating
// is no cheaper, rounds 0.49999999999999994 up and needs a floor for
// negatives. Ties may go either way: the engine itself promises only 0.51
// quanta, and the check below compares away from ties. The FMA kernels round
// by std::nearbyint and a truncating conversion instead (roundsd, cvttsd2si),
// which the compiler can vectorise with the rest of the loop; the intrinsic
// would keep it scalar.
inline std::int32_t RoundToQuantum(double quanta) {
#if defined(__x86_64__)
  return _mm_cvtsd_si32(_mm_set_sd(quanta));
#else
  return static_cast<std::int32_t>(std::lrint(quanta));
#endif
}

// ---------------------------------------------------------------------------
// Horner in double. This translation unit is compiled with
// -ffp-contract=fast (bench/CMakeLists.txt; the project's default is off), so
// a*b + c becomes one fused multiply-add wherever the target allows it. The
// kernels are instantiated twice: for target("fma") and for the baseline
// x86-64, and the first is taken when the CPU reports FMA at run time.

#if defined(__x86_64__)
#define FDSURF_TARGET_FMA __attribute__((target("fma")))
bool CpuHasFma() {
  static const bool has = __builtin_cpu_supports("fma");
  return has;
}
#else
#define FDSURF_TARGET_FMA
bool CpuHasFma() { return false; }
#endif

// c[a][b][k]: the coefficient of s^(3-a)·t^(3-b) of coordinate k, scaled by
// `scale` (1, or 1/Q for the rounded variants, so that no multiply is left
// per point).
struct PowerTable {
  double c[4][4][3];
};

PowerTable PowerTableOf(const Patch& patch, double scale) {
  const PowerCoefficients power = CoefficientsOf(patch);
  PowerTable table{};
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      for (int k = 0; k < 3; ++k) table.c[a][b][k] = power.c[a][b][k] * scale;
    }
  }
  return table;
}

template <typename Coordinate, bool kFma>
__attribute__((always_inline)) inline void Emit(const double (&p)[3], Coordinate (&out)[3]) {
  for (int k = 0; k < 3; ++k) {
    if constexpr (std::is_same_v<Coordinate, double>) {
      out[k] = p[k];
    } else if constexpr (kFma) {
      out[k] = static_cast<std::int32_t>(std::nearbyint(p[k]));
    } else {
      out[k] = RoundToQuantum(p[k]);
    }
  }
}

// Per point: four cubics in t, then one in s, per coordinate (15 multiply-adds).
template <typename Coordinate, bool kFma, typename Sink>
__attribute__((always_inline)) inline void HornerGrid(const PowerTable& table, int n, Sink& sink) {
  const double inverse_n = 1.0 / n;
  const auto& c = table.c;
  for (int i = 0; i <= n; ++i) {
    const double s = i * inverse_n;
    for (int j = 0; j <= n; ++j) {
      const double t = j * inverse_n;
      double p[3];
      for (int k = 0; k < 3; ++k) {
        double r[4];
        for (int a = 0; a < 4; ++a) {
          r[a] = ((c[a][0][k] * t + c[a][1][k]) * t + c[a][2][k]) * t + c[a][3][k];
        }
        p[k] = ((r[0] * s + r[1]) * s + r[2]) * s + r[3];
      }
      Coordinate out[3];
      Emit<Coordinate, kFma>(p, out);
      sink(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), out);
    }
  }
}

// Per row: the t-cubic's coefficients by Horner in s; per point one cubic in
// t per coordinate (3 multiply-adds).
template <typename Coordinate, bool kFma, typename Sink>
__attribute__((always_inline)) inline void HornerRowsGrid(const PowerTable& table, int n,
                                                          Sink& sink) {
  const double inverse_n = 1.0 / n;
  const auto& c = table.c;
  for (int i = 0; i <= n; ++i) {
    const double s = i * inverse_n;
    double row[4][3];
    for (int b = 0; b < 4; ++b) {
      for (int k = 0; k < 3; ++k) {
        row[b][k] = ((c[0][b][k] * s + c[1][b][k]) * s + c[2][b][k]) * s + c[3][b][k];
      }
    }
    for (int j = 0; j <= n; ++j) {
      const double t = j * inverse_n;
      double p[3];
      for (int k = 0; k < 3; ++k)
        p[k] = ((row[0][k] * t + row[1][k]) * t + row[2][k]) * t + row[3][k];
      Coordinate out[3];
      Emit<Coordinate, kFma>(p, out);
      sink(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), out);
    }
  }
}

template <typename Coordinate, typename Sink>
FDSURF_TARGET_FMA void HornerGridFma(const PowerTable& table, int n, Sink& sink) {
  HornerGrid<Coordinate, true>(table, n, sink);
}
template <typename Coordinate, typename Sink>
void HornerGridPlain(const PowerTable& table, int n, Sink& sink) {
  HornerGrid<Coordinate, false>(table, n, sink);
}
template <typename Coordinate, typename Sink>
FDSURF_TARGET_FMA void HornerRowsGridFma(const PowerTable& table, int n, Sink& sink) {
  HornerRowsGrid<Coordinate, true>(table, n, sink);
}
template <typename Coordinate, typename Sink>
void HornerRowsGridPlain(const PowerTable& table, int n, Sink& sink) {
  HornerRowsGrid<Coordinate, false>(table, n, sink);
}

template <typename Out>
struct HornerFmaT {
  using Coordinate = Out;
  using Prepared = PowerTable;
  static Prepared Prepare(const Patch& patch, int /*n*/) {
    return PowerTableOf(patch, std::is_same_v<Out, double> ? 1.0 : 1.0 / DefaultQuantum().value());
  }
  template <typename Sink>
  static void Step(const Prepared& p, int n, Sink&& sink) {
    if (CpuHasFma()) {
      HornerGridFma<Out>(p, n, sink);
    } else {
      HornerGridPlain<Out>(p, n, sink);
    }
  }
};
using HornerFma = HornerFmaT<double>;
using HornerFmaQuanta = HornerFmaT<std::int32_t>;

struct HornerRowsFmaQuanta {
  using Coordinate = std::int32_t;
  using Prepared = PowerTable;
  static Prepared Prepare(const Patch& patch, int /*n*/) {
    return PowerTableOf(patch, 1.0 / DefaultQuantum().value());
  }
  template <typename Sink>
  static void Step(const Prepared& p, int n, Sink&& sink) {
    if (CpuHasFma()) {
      HornerRowsGridFma<Coordinate>(p, n, sink);
    } else {
      HornerRowsGridPlain<Coordinate>(p, n, sink);
    }
  }
};

// ---------------------------------------------------------------------------
// Forward differences in double: the engine's algorithm without the exact
// arithmetic. The table DD = E(1/n)·C·E(1/n)ᵀ in quanta, where E(h) maps
// power coefficients (u³, u², u, 1) to the value and the first three forward
// differences at u = 0 for step h.

struct DoubleFdQuanta {
  using Coordinate = std::int32_t;
  struct Prepared {
    double dd[3][4][4];
  };
  static Prepared Prepare(const Patch& patch, int n) {
    const PowerTable power = PowerTableOf(patch, 1.0 / DefaultQuantum().value());
    const double h = 1.0 / n;
    const double h2 = h * h;
    const double h3 = h2 * h;
    const double e[4][4] = {
        {0, 0, 0, 1}, {h3, h2, h, 0}, {6 * h3, 2 * h2, 0, 0}, {6 * h3, 0, 0, 0}};
    Prepared p{};
    for (int k = 0; k < 3; ++k) {
      double ec[4][4] = {};
      for (int r = 0; r < 4; ++r) {
        for (int b = 0; b < 4; ++b) {
          for (int a = 0; a < 4; ++a) ec[r][b] += e[r][a] * power.c[a][b][k];
        }
      }
      for (int r = 0; r < 4; ++r) {
        for (int l = 0; l < 4; ++l) {
          for (int b = 0; b < 4; ++b) p.dd[k][r][l] += ec[r][b] * e[l][b];
        }
      }
    }
    return p;
  }
  template <typename Sink>
  static void Step(const Prepared& p, int n, Sink&& sink) {
    double dd[3][4][4];
    std::copy(&p.dd[0][0][0], &p.dd[0][0][0] + 48, &dd[0][0][0]);
    for (int i = 0;; ++i) {
      double line[3][4];
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 4; ++l) line[k][l] = dd[k][0][l];
      }
      for (int j = 0;; ++j) {
        const Coordinate out[3] = {RoundToQuantum(line[0][0]), RoundToQuantum(line[1][0]),
                                   RoundToQuantum(line[2][0])};
        sink(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), out);
        if (j == n) break;
        for (int k = 0; k < 3; ++k) {
          line[k][0] += line[k][1];
          line[k][1] += line[k][2];
          line[k][2] += line[k][3];
        }
      }
      if (i == n) break;
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 4; ++l) {
          dd[k][0][l] += dd[k][1][l];
          dd[k][1][l] += dd[k][2][l];
          dd[k][2][l] += dd[k][3][l];
        }
      }
    }
  }
};

// ---------------------------------------------------------------------------
// OpenCASCADE 7.6: the patch's control points are the surface's poles, pole
// (i+1, j+1) = g[i][j], so U is s and V is t.

#if FDSURF_BENCH_OCCT
TColgp_Array2OfPnt PolesOf(const Patch& patch) {
  TColgp_Array2OfPnt poles(1, 4, 1, 4);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const Point3& g = patch.g[i][j];
      poles(i + 1, j + 1) = gp_Pnt(g[0], g[1], g[2]);
    }
  }
  return poles;
}

struct OcctD0 {
  using Coordinate = double;
  using Prepared = Handle(Geom_BezierSurface);
  static Prepared Prepare(const Patch& patch, int /*n*/) {
    return new Geom_BezierSurface(PolesOf(patch));
  }
  template <typename Sink>
  static void Step(const Prepared& surface, int n, Sink&& sink) {
    const double inverse_n = 1.0 / n;
    gp_Pnt point;
    for (int i = 0; i <= n; ++i) {
      const double s = i * inverse_n;
      for (int j = 0; j <= n; ++j) {
        surface->D0(s, j * inverse_n, point);
        const double out[3] = {point.X(), point.Y(), point.Z()};
        sink(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), out);
      }
    }
  }
};

// One iso curve per row: BSplSLib::Iso gives the V-curve's poles at U = s
// (the Bézier knots 0, 1 with multiplicity 4), BSplCLib_Cache turns them into
// the curve's polynomial once per row, and its D0 evaluates it per point.
struct OcctIsoCache {
  using Coordinate = double;
  struct Prepared {
    TColgp_Array2OfPnt poles;
    TColStd_Array1OfReal knots{1, 2};
    TColStd_Array1OfInteger mults{1, 2};
    TColStd_Array1OfReal flat_knots{1, 8};
    TColgp_Array1OfPnt curve_poles{1, 4};
    Handle(BSplCLib_Cache) cache{};
  };
  static Prepared Prepare(const Patch& patch, int /*n*/) {
    Prepared p{PolesOf(patch)};
    p.knots(1) = 0.0;
    p.knots(2) = 1.0;
    p.mults.Init(4);
    for (int k = 1; k <= 8; ++k) p.flat_knots(k) = k <= 4 ? 0.0 : 1.0;
    p.cache = new BSplCLib_Cache(3, Standard_False, p.flat_knots, p.curve_poles);
    return p;
  }
  template <typename Sink>
  static void Step(Prepared& p, int n, Sink&& sink) {
    const double inverse_n = 1.0 / n;
    gp_Pnt point;
    for (int i = 0; i <= n; ++i) {
      BSplSLib::Iso(i * inverse_n, Standard_True, p.poles, BSplSLib::NoWeights(), p.knots, &p.mults,
                    3, Standard_False, p.curve_poles, nullptr);
      p.cache->BuildCache(0.0, p.flat_knots, p.curve_poles);
      for (int j = 0; j <= n; ++j) {
        p.cache->D0(j * inverse_n, point);
        const double out[3] = {point.X(), point.Y(), point.Z()};
        sink(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), out);
      }
    }
  }
};
#endif

// ---------------------------------------------------------------------------
// SISL 4.6: the patch as a polynomial B-spline surface of order 4 × 4 on the
// knots 0,0,0,0,1,1,1,1, evaluated on the grid by s1506 (all points in one
// call, into a buffer, first parameter running fastest).

#if FDSURF_BENCH_SISL
struct SislS1506 {
  using Coordinate = double;
  struct Surface {
    void operator()(SISLSurf* s) const { freeSurf(s); }
  };
  struct Prepared {
    std::unique_ptr<SISLSurf, Surface> surface;
    std::vector<double> parameters;
  };
  static Prepared Prepare(const Patch& patch, int n) {
    double knots[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    double coefficients[4 * 4 * 3];
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        for (int k = 0; k < 3; ++k) coefficients[(j * 4 + i) * 3 + k] = patch.g[i][j][k];
      }
    }
    Prepared p;
    // kind 1 (polynomial B-spline), dimension 3, copy 1 (SISL copies the arrays).
    p.surface.reset(newSurf(4, 4, 4, 4, knots, knots, coefficients, 1, 3, 1));
    p.parameters.resize(n + 1);
    for (int i = 0; i <= n; ++i) p.parameters[i] = static_cast<double>(i) / n;
    return p;
  }
  // One output buffer for all patches (3·(n+1)² doubles; its size is set
  // once per n, outside the timed loop in practice).
  static std::vector<double>& Buffer(std::size_t size) {
    static std::vector<double> buffer;
    if (buffer.size() < size) buffer.resize(size);
    return buffer;
  }
  template <typename Sink>
  static void Step(Prepared& p, int n, Sink&& sink) {
    const std::size_t m = static_cast<std::size_t>(n) + 1;
    std::vector<double>& points = Buffer(2 * 3 * m * m);
    int status = 0;
    s1506(p.surface.get(), 0, n + 1, p.parameters.data(), n + 1, p.parameters.data(), points.data(),
          points.data() + 3 * m * m, &status);
    if (status < 0) std::abort();
    const double* point = points.data();
    for (std::size_t j = 0; j < m; ++j) {
      for (std::size_t i = 0; i < m; ++i, point += 3) {
        const double out[3] = {point[0], point[1], point[2]};
        sink(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), out);
      }
    }
  }
};
#endif

// ---------------------------------------------------------------------------
// The benchmarks: stepping with everything prepared outside the timed loop,
// and the set-up alone, for every method at the same grids.

// The checksum adds every coordinate's bits as an integer: a double sum
// would chain three 4-cycle floating-point additions per point (about 4 ns
// here), a floor that would slow the doubles-out methods and not the engine.
inline std::uint64_t Bits(double x) { return std::bit_cast<std::uint64_t>(x); }
inline std::uint64_t Bits(std::int32_t k) { return static_cast<std::uint64_t>(k); }

template <typename Method>
void BM_Stepping(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<typename Method::Prepared> prepared;
  for (const Patch& patch : Teapot().patches) prepared.push_back(Method::Prepare(patch, n));
  for (auto _ : state) {
    std::uint64_t checksum = 0;
    for (auto& p : prepared) {
      Method::Step(p, n,
                   [&](std::uint32_t, std::uint32_t, const typename Method::Coordinate(&k)[3]) {
                     checksum += Bits(k[0]) + Bits(k[1]) + Bits(k[2]);
                   });
    }
    benchmark::DoNotOptimize(checksum);
  }
  const auto points = static_cast<double>(prepared.size() * PointsPerPatch(n));
  // Seconds per point (the inverse of the rate): "1.7n" on the console, 1.7e-09 in JSON.
  state.counters["per_point"] = benchmark::Counter(
      points, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  if constexpr (std::is_same_v<Method, FixedEngine>) {
    state.counters["acc_bits"] = prepared[0].format.acc_bits;
  }
}

template <typename Method>
void BM_Setup(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) {
    for (const Patch& patch : Teapot().patches) {
      auto prepared = Method::Prepare(patch, n);
      benchmark::DoNotOptimize(prepared);
    }
  }
  state.counters["per_patch"] = benchmark::Counter(
      static_cast<double>(Teapot().patches.size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void Grids(benchmark::internal::Benchmark* b) {
  for (const int n : {16, 64, 256, 1024}) b->Arg(n);
  b->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMicrosecond);
}

#define FDSURF_METHOD(M)                            \
  BENCHMARK_TEMPLATE(BM_Stepping, M)->Apply(Grids); \
  BENCHMARK_TEMPLATE(BM_Setup, M)->Apply(Grids)

FDSURF_METHOD(FixedEngine);
FDSURF_METHOD(HornerFma);
FDSURF_METHOD(HornerFmaQuanta);
FDSURF_METHOD(HornerRowsFmaQuanta);
FDSURF_METHOD(DoubleFdQuanta);
#if FDSURF_BENCH_OCCT
FDSURF_METHOD(OcctD0);
FDSURF_METHOD(OcctIsoCache);
#endif
#if FDSURF_BENCH_SISL
FDSURF_METHOD(SislS1506);
#endif

// ---------------------------------------------------------------------------
// The start-up check: every method computes the teapot, or nothing is timed.
//
// Doubles out: every coordinate within 1e-9 of the patch's size (the largest
// control-point coordinate) of the reference. Whole quanta out: equal to the
// engine's integer, except where the exact value lies within the engine's
// pre-rounding bound (ErrorBoundBeforeRounding, about 0.01 quanta) of a tie,
// where the two may differ by one; and always within 0.5 quanta (plus the
// same 1e-9 of the size) of the reference.

struct Failures {
  int count = 0;
  void Report(const char* method, int n, const Patch& patch, std::uint32_t i, std::uint32_t j,
              int k, const std::string& what) {
    if (++count <= 5) {
      std::fprintf(stderr, "fdsurf_bench: %s, N = %d, %s, point (%u, %u), coordinate %d: %s\n",
                   method, n, patch.origin.c_str(), i, j, k, what.c_str());
    }
  }
};

double SizeOf(const Patch& patch) {
  double size = 1.0;
  for (const auto& row : patch.g) {
    for (const Point3& g : row) {
      for (const double x : g) size = std::max(size, std::fabs(x));
    }
  }
  return size;
}

template <typename Method>
void Check(const char* name, int n, std::size_t patches, Failures& failures, int& near_ties) {
  const double q = DefaultQuantum().value();
  for (std::size_t index = 0; index < patches; ++index) {
    const Patch& patch = Teapot().patches[index];
    const double size = SizeOf(patch);
    const auto m = static_cast<std::size_t>(n) + 1;
    std::vector<Point3> reference(m * m);
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t j = 0; j < m; ++j) {
        reference[i * m + j] =
            EvaluateReference(patch, static_cast<double>(i) / n, static_cast<double>(j) / n);
      }
    }
    const PreparedPatch<3> fixed = FixedEngine::Prepare(patch, n);
    const double tie_window = ErrorBoundBeforeRounding(fixed, patch.basis);
    std::vector<std::array<std::int32_t, 3>> engine(m * m);
    FixedEngine::Step(fixed, n, [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      engine[i * m + j] = {k[0], k[1], k[2]};
    });
    std::vector<int> seen(m * m, 0);
    auto prepared = Method::Prepare(patch, n);
    Method::Step(prepared, n,
                 [&](std::uint32_t i, std::uint32_t j, const typename Method::Coordinate(&p)[3]) {
                   if (i > static_cast<std::uint32_t>(n) || j > static_cast<std::uint32_t>(n)) {
                     failures.Report(name, n, patch, i, j, 0, "outside the grid");
                     return;
                   }
                   ++seen[i * m + j];
                   for (int k = 0; k < 3; ++k) {
                     const double exact = reference[i * m + j][k];
                     char what[160];
                     if constexpr (std::is_same_v<typename Method::Coordinate, double>) {
                       if (!(std::fabs(p[k] - exact) <= 1e-9 * size)) {
                         std::snprintf(what, sizeof what, "%.17g, reference %.17g", p[k], exact);
                         failures.Report(name, n, patch, i, j, k, what);
                       }
                     } else {
                       const double quanta = exact / q;
                       const double from_tie = std::fabs(quanta - std::floor(quanta) - 0.5);
                       const std::int32_t e = engine[i * m + j][k];
                       // The engine itself is within its own bound of the exact value.
                       const double allowed = std::is_same_v<Method, FixedEngine>
                                                  ? 0.5 + tie_window
                                                  : 0.5 + 1e-9 * size / q;
                       const bool agrees = p[k] == e || (from_tie <= tie_window + 1e-9 * size / q &&
                                                         std::abs(p[k] - e) == 1);
                       if (p[k] != e && agrees) ++near_ties;
                       if (!agrees || !(std::fabs(p[k] - quanta) <= allowed)) {
                         std::snprintf(what, sizeof what, "%d quanta, engine %d, exact %.6f", p[k],
                                       e, quanta);
                         failures.Report(name, n, patch, i, j, k, what);
                       }
                     }
                   }
                 });
    for (std::size_t i = 0; i < m * m; ++i) {
      if (seen[i] != 1) {
        failures.Report(name, n, patch, i / m, i % m, 0,
                        "emitted " + std::to_string(seen[i]) + " times");
      }
    }
  }
}

template <typename Method>
int CheckMethod(const char* name) {
  Failures failures;
  int near_ties = 0;
  const std::size_t all = Teapot().patches.size();
  for (const int n : {16, 64, 256}) Check<Method>(name, n, all, failures, near_ties);
  // 1024 × 1024 on two patches: the accumulated error of the double
  // difference table is largest at the finest grid.
  Check<Method>(name, 1024, std::min<std::size_t>(2, all), failures, near_ties);
  if (failures.count > 0) {
    std::fprintf(stderr, "fdsurf_bench: %s computes something else (%d disagreements)\n", name,
                 failures.count);
  } else if (near_ties > 0) {
    std::fprintf(stderr,
                 "fdsurf_bench: %s checked (%d coordinates a quantum off the engine's, "
                 "all at ties)\n",
                 name, near_ties);
  }
  return failures.count;
}

int CheckAll() {
  int failures = 0;
  failures += CheckMethod<FixedEngine>("FixedEngine");
  failures += CheckMethod<HornerFma>("HornerFma");
  failures += CheckMethod<HornerFmaQuanta>("HornerFmaQuanta");
  failures += CheckMethod<HornerRowsFmaQuanta>("HornerRowsFmaQuanta");
  failures += CheckMethod<DoubleFdQuanta>("DoubleFdQuanta");
#if FDSURF_BENCH_OCCT
  failures += CheckMethod<OcctD0>("OcctD0");
  failures += CheckMethod<OcctIsoCache>("OcctIsoCache");
#endif
#if FDSURF_BENCH_SISL
  failures += CheckMethod<SislS1506>("SislS1506");
#endif
  return failures;
}

}  // namespace
}  // namespace fdsurf::host

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  if (fdsurf::host::CheckAll() != 0) return 1;
  benchmark::AddCustomContext("horner_fma", fdsurf::host::CpuHasFma() ? "yes" : "no");
  benchmark::AddCustomContext("occt", FDSURF_BENCH_OCCT ? "yes" : "no");
  benchmark::AddCustomContext("sisl", FDSURF_BENCH_SISL ? "yes" : "no");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
