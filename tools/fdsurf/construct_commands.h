// SPDX-License-Identifier: MIT
// The parts of fdsurf sample/check that handle curves and construction notes,
// and the joins command (docs/constructions.md).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "fdsurf/forward_difference.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quantum.h"

namespace fdsurf::host {

/// The curves of a set, prepared (fixed) before anything is written, so that
/// a refusal leaves stdout empty.
class CurveSamples {
 public:
  /// Throws EngineError if the engine refuses a curve.
  CurveSamples(const PatchSet& set, const Quantum& quantum, int steps, bool fixed);
  /// Writes "curve,i,x,y,z" and one row per point (u = i/steps), if any curves.
  void Write(const std::function<void(const std::string&)>& out) const;

 private:
  const PatchSet& set_;
  Quantum quantum_;
  int steps_;
  bool fixed_;
  std::vector<PreparedCurve<3>> prepared_;
};

/// Prints the construction notes, then a table of the curves (if any)
/// compared with their double evaluation. Returns the worst curve error in
/// quanta (0 without curves), and the index of that curve in `worst_curve`
/// when it is given.
double CheckCurves(const PatchSet& set, const Quantum& quantum, int steps,
                   std::size_t* worst_curve = nullptr);

struct JoinsOptions {
  std::string file;
  double tolerance = 1e-9;
  double angle = 1e-6;
  double ratio = 1e-6;
};
void AddJoinsOptions(CLI::App* command, JoinsOptions* options);
/// Prints one line per shared edge and a summary; returns the exit code.
int RunJoins(const JoinsOptions& options);

}  // namespace fdsurf::host
