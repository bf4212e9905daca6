// SPDX-License-Identifier: MIT
#include "image.h"

#include "bench.h"
#include "port.h"
#include "report.h"

#if FDSURF_IMAGE_SETUP
#include "cases.h"
#else
#include "rom_tables.h"
#endif

namespace fdsurf {
namespace image {
namespace {

#if !FDSURF_IMAGE_SETUP
// One item at a time in RAM: the largest is a 2-D patch table (about 540 bytes).
union RomBuffer {
  RomPatch2 patch2;
  RomCurve2 curve2;
  RomCurve3 curve3;
  RomAdaptive2 adaptive2;
  RomCoefficients2 coefficients2;
  RomBuffer() : patch2() {}
};
RomBuffer g_rom;

template <typename T>
void Load(const T& from, T* to) {
  PortReadRom(to, &from, sizeof(T));
}

void RunRomCases(Reporter& reporter) {
  for (uint16_t i = 0; i < kRomOrderCount; ++i) {
    RomItem item;
    Load(kRomOrder[i], &item);
    switch (item.kind) {
      case RomKind::kPatch2:
        Load(kRomPatch2[item.index], &g_rom.patch2);
        reporter.Patch(true, kRomPatch2[item.index].name, g_rom.patch2.index, g_rom.patch2.status,
                       g_rom.patch2.prepared);
        break;
      case RomKind::kCurve2:
        Load(kRomCurve2[item.index], &g_rom.curve2);
        reporter.Curve(true, kRomCurve2[item.index].name, g_rom.curve2.index, g_rom.curve2.status,
                       g_rom.curve2.prepared);
        break;
      case RomKind::kCurve3:
        Load(kRomCurve3[item.index], &g_rom.curve3);
        reporter.Curve(true, kRomCurve3[item.index].name, g_rom.curve3.index, g_rom.curve3.status,
                       g_rom.curve3.prepared);
        break;
      case RomKind::kAdaptive2:
        Load(kRomAdaptive2[item.index], &g_rom.adaptive2);
        reporter.Adaptive(true, kRomAdaptive2[item.index].name, g_rom.adaptive2.index,
                          g_rom.adaptive2.status, g_rom.adaptive2.prepared);
        break;
      case RomKind::kCoefficients2:
        Load(kRomCoefficients2[item.index], &g_rom.coefficients2);
        reporter.Coefficients(true, kRomCoefficients2[item.index].name, g_rom.coefficients2.index,
                              g_rom.coefficients2.curve);
        break;
    }
  }
}

void LoadBenchCurve2(bool wide, PreparedCurve<2>* out) { Load(kRomBenchCurve2[wide ? 1 : 0], out); }
void LoadBenchPatch2(PreparedPatch<2>* out) { Load(kRomBenchPatch2, out); }
void LoadBenchAdaptive2(PreparedAdaptiveCurve<2>* out) { Load(kRomBenchAdaptive2, out); }
#endif

}  // namespace

int RunImage(bool small_only) {
  PutString(FDSURF_TEXT("fdsurf test image 1\n"));
  Reporter reporter;
#if FDSURF_IMAGE_SETUP
  reporter.small_only = small_only;
  RunCases(reporter);
  PutString(FDSURF_TEXT("# stack-after-cases "));
  PutUnsigned(PortStackUsed());
  PutString(FDSURF_TEXT("\n"));
  BenchSource source = {SetupBenchCurve2,
                        SetupBenchCurve3,
                        SetupBenchPatch2,
                        SetupBenchPatch3,
                        SetupBenchAdaptive2,
                        true,
                        true,
                        true};
  if (small_only) {  // What the ATmega328P image measures.
    source.curve3 = nullptr;
    source.patch3 = nullptr;
    source.measure_setup = false;
    source.wide = false;
    source.parts = false;
  }
#else
  static_cast<void>(small_only);
  RunRomCases(reporter);
  const BenchSource source = {LoadBenchCurve2,    nullptr, LoadBenchPatch2, nullptr,
                              LoadBenchAdaptive2, false,   false,           false};
#endif
  RunBench(source);
  PutString(FDSURF_TEXT("end\n"));
  // Lines starting with '#' describe the target, not the results: the
  // comparison with the host leaves them out.
  PutString(FDSURF_TEXT("# stack "));
  PutUnsigned(PortStackUsed());
  PutString(FDSURF_TEXT("\n"));
  return 0;
}

}  // namespace image
}  // namespace fdsurf
