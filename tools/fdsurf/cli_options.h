// SPDX-License-Identifier: MIT
// Option parsing and output staging shared by the fdsurf commands.
#pragma once

#include <array>
#include <optional>
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

/// The readers' options as typed, "" (or false) when left out
/// (docs/formats.md): --arc-tolerance for SVG and G-code input, in the
/// input's unit (mm for SVG); --pen-z-below, --servo-down-below and
/// --no-block-delete for G-code input (GcodeReadOptions).
struct ReaderFlags {
  std::string arc_tolerance;
  std::string pen_z_below;
  std::string servo_down_below;
  bool no_block_delete = false;
};

/// The options of `sample` and `check`: a file evaluated on a grid.
struct GridOptions {
  std::string file;
  std::string input_format;
  ReaderFlags reader;
  std::string grid;
  std::string engine = "fixed";
  std::string quantum = "0.001";
};

/// Adds FILE (a path, or - for standard input), --input-format (bpt,
/// json, obj, ply, svg, gcode: for when neither the suffix nor the content
/// tells) and the reader flags, as every command that reads a drawing has them.
void AddInputOptions(CLI::App* command, std::string* file, std::string* input_format,
                     ReaderFlags* reader);

/// Reads FILE (ReadPatchFile, with --input-format when given) with the
/// reader flags. InputError naming the flag for a value that is not a number
/// or an --arc-tolerance that is not > 0, and for a flag the format read does
/// not take (--arc-tolerance but bpt, json, obj, ply; a G-code flag but not
/// G-code): a flag that would change nothing is refused, not ignored.
/// OptionError ("arc tolerance") and InputError as the readers throw them.
PatchSet ReadInput(const std::string& file, const std::string& input_format,
                   const ReaderFlags& reader);

/// Adds FILE, --grid and --quantum (the options `sample` and `check` share).
void AddGridOptions(CLI::App* command, GridOptions* options);

/// A finite number; InputError naming `what` otherwise.
double ParseNumber(const std::string& text, const std::string& what);

/// A number > 0 (or ≥ 0 with allow_zero); InputError naming `what` otherwise.
double ParsePositive(const std::string& text, const std::string& what, bool allow_zero = false);

/// Millimetres in one unit of --units ("mm" or "in"): 1, or 25.4 exactly.
double MmPerUnit(const std::string& units);

/// The space kept around a fitted drawing when --margin is left out, mm.
constexpr double kDefaultMarginMm = 5;

/// A default that carries a length (mm, mm/s, mm/s², mm/min) in `units`:
/// mm / MmPerUnit(units), not rounded (only printing rounds it).
double DefaultIn(double mm, const std::string& units);

/// A default resolution (a quantum, given in mm) in `units`: itself in mm;
/// in inches the largest power of ten no coarser than it (0.001 mm is
/// 0.00001 in), so an inch job is never drawn coarser than the mm one and
/// every bound in quanta stays exactly as derived for that quantum.
Quantum DefaultResolutionIn(const Quantum& mm, const std::string& units);

/// A default motor step (given in mm) in `units`: itself in mm; in inches
/// the nearest value with 9 decimals, Quantum's limit (0.0125 mm is
/// 0.000492126 in, 3.3e-8 relative: the step grid, and every bound in steps,
/// is the inch one exactly; the drawing's physical size is off by 3.3e-8).
Quantum DefaultStepIn(const Quantum& mm, const std::string& units);

/// The help text's note of a default given in mm: "(default 5 mm; converted
/// for --units in)", `unit` "mm", "mm/s", ...
std::string DefaultInMmHelp(double mm, const std::string& unit);

/// --lines: "U" or "UxV", each 0 (family left out) or 2..kMaxPatchSteps + 1.
std::array<int, 2> ParseLines(const std::string& text);

/// A page for --fit: "WxH" with both > 0 (in `units`), or a paper name, A3,
/// A4, A5 (ISO 216), letter or legal (US), in any case and optionally with
/// ":landscape", portrait by default, converted to `units` ("mm" or "in").
/// nullopt for "none" (no page: file units, no scaling). InputError naming
/// `what` otherwise.
std::optional<std::array<double, 2>> ParsePage(const std::string& text, const std::string& units,
                                               const std::string& what = "--fit");

/// Adds --fit, --origin and --margin with the one help text `plot`, `render`
/// and `stream` share (the values are parsed by PlacePage).
void AddPageOptions(CLI::App* command, std::string* fit, std::string* origin, std::string* margin);

/// --origin: "keep", "center" or "min"; InputError otherwise.
PageOrigin ParseOrigin(const std::string& text);

/// The page when --fit is left out for a drawing that is fitted: 200 x 150 mm
/// (in inches for units "in").
std::array<double, 2> DefaultPage(const std::string& units);

/// --fit and --origin as typed ("" when left out), one rule for `plot`,
/// `render` and `stream` (docs/toolpaths.md, "The page"): a file with its own
/// page (PatchSet::page) or a program (PatchSet::keep_order) keeps its
/// coordinates (origin keep, on its page or --fit's); any other drawing is
/// centred and scaled to fit --fit, by default its own page or else
/// 200 x 150 mm. `to_work` converts --units to the job's working units (HPGL
/// works in mm); t->units_scale must already be set (file to working units).
/// Sets t->fit and t->origin; InputError for a bad --fit or --origin.
void PlacePage(const std::string& fit, const std::string& origin, const std::string& units,
               double to_work, const PatchSet& set, ToolpathOptions* t);

/// --view: "top", "front", "side", "iso" or "AZ,EL" in degrees (azimuth
/// from +x towards +y of the eye's direction, elevation above the xy plane).
/// Throws InputError or OptionError ("view").
View ParseView(const std::string& text);

/// The command-line flag of a library option field (OptionError::field):
/// "tolerance" is --tolerance, "pen delay" --pen-delay, "travel X" --travel X.
std::string FlagFor(const std::string& field);

/// The drawing of `plot`, `render` and `stream`: ReadInput, then only the
/// layer `layer` names when it is not empty (--layer NAME|N, SelectLayer);
/// the reader's "left out: ..." notes go to stderr unless `quiet`. Throws
/// InputError as those do.
PatchSet ReadDrawing(const std::string& file, const std::string& input_format,
                     const ReaderFlags& reader, const std::string& layer, bool quiet);

/// A drawing in the xy plane (no patches; a page of its own (SVG), a program
/// (G-code, whose Z is the pen) or every curve at z = 0): drawn from the top
/// unless --view says otherwise.
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

/// What a drawing holds, for headers and summaries: "32 patches", "1 curve",
/// "2 patches and 4 curves", "no patches or curves".
std::string DescribeDrawing(std::size_t patches, std::size_t curves);

}  // namespace fdsurf::host
