// SPDX-License-Identifier: MIT
// Option parsing and output staging shared by the fdsurf commands.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "fdsurf/host/toolpath.h"

namespace CLI {
class App;
}

namespace fdsurf::host {

/// --grid: steps per patch along s and t.
struct Grid {
  int steps_s = 0;
  int steps_t = 0;
};

/// "N" or "NxM", each 1..kMaxPatchSteps; InputError naming --grid otherwise.
Grid ParseGrid(const std::string& text);

/// The options of `sample` and `check`: a file evaluated on a grid.
struct GridOptions {
  std::string file;
  std::string grid;
  std::string engine = "fixed";
  std::string quantum = "0.001";
};

/// Adds FILE, --grid and --quantum (the options `sample` and `check` share).
void AddGridOptions(CLI::App* command, GridOptions* options);

/// A number > 0 (or ≥ 0 with allow_zero); InputError naming `what` otherwise.
double ParsePositive(const std::string& text, const std::string& what, bool allow_zero = false);

/// --lines: "U" or "UxV", each 0 (family left out) or 2..kMaxPatchSteps + 1.
std::array<int, 2> ParseLines(const std::string& text);

/// "WxH" with both > 0; `what` names the option in errors.
std::array<double, 2> ParsePage(const std::string& text, const std::string& what = "--fit");

/// --view: "top", "front", "side", "iso" or "AZ,EL" in degrees (azimuth
/// from +x towards +y of the eye's direction, elevation above the xy plane).
/// Throws InputError or OptionError ("view").
View ParseView(const std::string& text);

/// The command-line flag of a library option field (OptionError::field):
/// "tolerance" is --tolerance, "pen delay" --pen-delay, "travel X" --travel X.
std::string FlagFor(const std::string& field);

/// The drawing of `plot`, `render` and `stream`: ReadPatchFile, then only
/// the layer `layer` names when it is not empty (--layer NAME|N,
/// SelectLayer); the reader's "left out: ..." notes go to stderr unless
/// `quiet`. Throws InputError as those do.
PatchSet ReadDrawing(const std::string& file, const std::string& layer, bool quiet);

/// A drawing in the xy plane (no patches, every curve at z = 0: SVG,
/// G-code without Z): drawn from the top unless --view says otherwise.
bool IsFlatDrawing(const PatchSet& set);

/// Whether to draw a progress line: stderr is a terminal, not quiet, not CI.
bool ShowProgress(bool quiet);

// Every output is written to a temporary file beside its destination first;
// only when all of them are complete are they renamed into place.
class StagedOutputs {
 public:
  StagedOutputs() = default;
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  /// Removes whatever was staged and not committed.
  ~StagedOutputs();
  /// The temporary name to write `file` to.
  std::string Stage(const std::string& file);
  /// Renames every staged file into place; OutputError naming the file.
  void Commit();

 private:
  std::vector<std::pair<std::string, std::string>> staged_;
};

}  // namespace fdsurf::host
