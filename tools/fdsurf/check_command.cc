// SPDX-License-Identifier: MIT
// `fdsurf check`: the fixed engine against the double reference, per patch.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_options.h"
#include "commands.h"
#include "construct_commands.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quantum.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {

int RunCheck(const GridOptions& options) {
  const Grid grid = ParseGrid(options.grid);
  const Quantum quantum = Quantum::Parse(options.quantum, "--quantum");
  const PatchSet set = ReadInput(options.file, options.input_format, options.reader);
  std::vector<PreparedPatch<3>> prepared;
  for (const Patch& patch : set.patches) {
    prepared.push_back(PrepareFixedPatch(patch, quantum, grid.steps_s, grid.steps_t));
  }
  const double q = quantum.value();
  const std::string units = set.units.empty() ? "file units" : set.units;
  double worst = 0;
  std::size_t worst_patch = 0;
  std::printf("grid %dx%d, quantum %s %s, bound 0.51 quanta\n", grid.steps_s, grid.steps_t,
              quantum.Format(1).c_str(), units.c_str());
  if (!set.patches.empty()) {
    std::printf("patch  acc  frac  exact  max error (quanta)  max error (%s)  at (i,j)\n",
                units.c_str());
  }
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    double patch_worst = 0;
    std::uint32_t at_i = 0;
    std::uint32_t at_j = 0;
    ForEachGridPoint(prepared[p], [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      const Point3 exact = EvaluateReference(set.patches[p], static_cast<double>(i) / grid.steps_s,
                                             static_cast<double>(j) / grid.steps_t);
      for (int c = 0; c < 3; ++c) {
        const double error = std::fabs(k[c] - quantum.ToQuanta(exact[c]));
        if (error > patch_worst) {
          patch_worst = error;
          at_i = i;
          at_j = j;
        }
      }
    });
    std::printf("%5zu  %3d  %4d  %5s  %18.6f  %*.3g  (%u,%u)\n", p, prepared[p].format.acc_bits,
                prepared[p].format.frac_bits, prepared[p].exact ? "yes" : "no", patch_worst,
                static_cast<int>(units.size()) + 13, patch_worst * q, at_i, at_j);
    if (patch_worst > worst) {
      worst = patch_worst;
      worst_patch = p;
    }
  }
  std::size_t worst_curve = 0;
  const double curve_worst = CheckCurves(set, quantum, grid.steps_s, &worst_curve);
  // The worst over the patches and the curves, named by where it is.
  const bool in_curve = curve_worst > worst || set.patches.empty();
  const double overall = std::max(worst, curve_worst);
  const std::string where = set.patches.empty() && set.curves.empty() ? ""
                            : in_curve ? " in curve " + std::to_string(worst_curve)
                                       : " in patch " + std::to_string(worst_patch);
  std::printf("overall: max error %.6f quanta (%.3g %s)%s, %s: %s\n", overall, overall * q,
              units.c_str(), where.c_str(),
              DescribeDrawing(set.patches.size(), set.curves.size()).c_str(),
              overall <= 0.51 ? "within the 0.51-quantum bound" : "BOUND VIOLATED");
  return overall <= 0.51 ? 0 : 1;
}

}  // namespace fdsurf::host
