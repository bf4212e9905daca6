// SPDX-License-Identifier: MIT
// The teapot through the whole host path (file → quanta → engine) against the
// double reference, and the engine's refusals as the host reports them.
#include <gtest/gtest.h>

#include <cmath>

#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {
namespace {

double WorstError(const PatchSet& set, const Quantum& q, int n, int m) {
  double worst = 0;
  for (const Patch& patch : set.patches) {
    const PreparedPatch<3> prepared = PrepareFixedPatch(patch, q, n, m);
    EXPECT_LE(ErrorBoundBeforeRounding(prepared, patch.basis), 0.01);
    ForEachGridPoint(prepared, [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      const Point3 exact =
          EvaluateReference(patch, static_cast<double>(i) / n, static_cast<double>(j) / m);
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(k[c] - q.ToQuanta(exact[c])));
    });
  }
  return worst;
}

TEST(Teapot, SampledAt64x64WithinTheBound) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/teapot.bpt");
  EXPECT_LE(WorstError(set, Quantum::Parse("0.001"), 64, 64), 0.51);
}

TEST(Teapot, FinerQuantaAndOddGridsWithinTheBound) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/teapot.bpt");
  EXPECT_LE(WorstError(set, Quantum::Parse("0.0000001"), 100, 37), 0.51);
  EXPECT_LE(WorstError(set, Quantum::Parse("0.025"), 1, 999), 0.51);
}

TEST(FixedEngineHost, RefusalsNameThePatchAndTheReason) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/teapot.bpt");
  const auto message = [&](const Quantum& q, int n, int m) -> std::string {
    try {
      PrepareFixedPatch(set.patches[3], q, n, m);
    } catch (const EngineError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  // 3 units at 1e-9 is 3·10^9 quanta, beyond 2^31.
  EXPECT_NE(message(Quantum::Parse("0.000000001"), 4, 4).find("out of range"), std::string::npos);
  EXPECT_NE(message(Quantum::Parse("0.000000001"), 4, 4).find("teapot.bpt:"), std::string::npos);
  EXPECT_NE(message(Quantum::Parse("0.001"), 1025, 4).find("between 1 and 1024"),
            std::string::npos);
  PrepareOptions narrow;
  narrow.max_acc_bits = 64;
  try {
    PrepareFixedPatch(set.patches[3], Quantum::Parse("0.001"), 1024, 1024, narrow);
    ADD_FAILURE() << "accepted";
  } catch (const EngineError& e) {
    EXPECT_NE(std::string(e.what()).find("more than 64 accumulator bits"), std::string::npos);
  }
  Patch nan_patch = set.patches[0];
  nan_patch.g[1][2][1] = std::nan("");
  try {
    PrepareFixedPatch(nan_patch, Quantum::Parse("0.001"), 4, 4);
    ADD_FAILURE() << "accepted";
  } catch (const EngineError& e) {
    EXPECT_NE(std::string(e.what()).find("geometry [1][2].y = nan is not finite"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace fdsurf::host
