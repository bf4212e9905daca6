// SPDX-License-Identifier: MIT
// `fdsurf sample`: every grid point of every patch (and curve) as CSV.
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
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

// Buffered stdout writer; CSV rows are many and small.
class Output {
 public:
  Output() { buffer_.reserve(1 << 16); }
  ~Output() { Flush(); }
  Output(const Output&) = delete;
  Output& operator=(const Output&) = delete;
  void Append(const std::string& s) {
    buffer_ += s;
    if (buffer_.size() > (1 << 16)) Flush();
  }
  void Flush() {
    std::fwrite(buffer_.data(), 1, buffer_.size(), stdout);
    buffer_.clear();
  }

 private:
  std::string buffer_;
};

}  // namespace

int RunSample(const GridOptions& options) {
  const Grid grid = ParseGrid(options.grid);
  const Quantum quantum = Quantum::Parse(options.quantum, "--quantum");
  const PatchSet set = ReadInput(options.file, options.input_format, options.reader);
  const bool fixed = options.engine == "fixed";
  std::vector<PreparedPatch<3>> prepared;
  if (fixed) {
    prepared.reserve(set.patches.size());
    for (const Patch& patch : set.patches) {
      prepared.push_back(PrepareFixedPatch(patch, quantum, grid.steps_s, grid.steps_t));
    }
  }
  const CurveSamples curves(set, quantum, grid.steps_s, fixed);
  Output out;
  if (!set.patches.empty()) out.Append("patch,i,j,x,y,z\n");
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    const std::string prefix = std::to_string(p) + ",";
    if (fixed) {
      ForEachGridPoint(prepared[p],
                       [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&q)[3]) {
                         out.Append(prefix + std::to_string(i) + "," + std::to_string(j) + "," +
                                    quantum.Format(q[0]) + "," + quantum.Format(q[1]) + "," +
                                    quantum.Format(q[2]) + "\n");
                       });
    } else {
      for (int i = 0; i <= grid.steps_s; ++i) {
        for (int j = 0; j <= grid.steps_t; ++j) {
          const Point3 v = EvaluateReference(set.patches[p], static_cast<double>(i) / grid.steps_s,
                                             static_cast<double>(j) / grid.steps_t);
          out.Append(prefix + std::to_string(i) + "," + std::to_string(j) + "," +
                     FormatNumber(v[0], 17) + "," + FormatNumber(v[1], 17) + "," +
                     FormatNumber(v[2], 17) + "\n");
        }
      }
    }
  }
  curves.Write([&](const std::string& text) { out.Append(text); });
  return 0;
}

}  // namespace fdsurf::host
