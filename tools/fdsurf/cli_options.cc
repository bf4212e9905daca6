// SPDX-License-Identifier: MIT
#include "cli_options.h"

#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <utility>
#include <vector>

#include "fdsurf/forward_difference.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/svg_io.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {

Grid ParseGrid(const std::string& text) {
  const auto fail = [&](const std::string& why) {
    return InputError("--grid: '" + text + "' " + why);
  };
  const std::size_t x = text.find('x');
  const auto parse = [&](std::string_view part) {
    int value = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size()) {
      throw fail("is not N or NxM with whole numbers N, M");
    }
    if (value < 1 || value > kMaxPatchSteps) {
      throw fail("is out of range: each dimension must be between 1 and " +
                 std::to_string(kMaxPatchSteps));
    }
    return value;
  };
  const std::string_view all(text);
  Grid grid;
  grid.steps_s = parse(all.substr(0, x));
  grid.steps_t = x == std::string::npos ? grid.steps_s : parse(all.substr(x + 1));
  return grid;
}

void AddInputOptions(CLI::App* command, std::string* file, std::string* input_format,
                     ReaderFlags* reader) {
  command
      ->add_option("FILE", *file,
                   "drawing: patches (.bpt, .json), an SVG drawing (.svg), a G-code program "
                   "(.gcode, .nc, .ngc) or a triangle mesh (.obj, .ply); - reads standard "
                   "input; see docs/formats.md")
      ->required();
  command
      ->add_option("--input-format", *input_format,
                   "the drawing's format when neither its suffix nor its content tells")
      ->check(CLI::IsMember({"bpt", "json", "obj", "ply", "svg", "gcode"}));
  command->add_option("--arc-tolerance", reader->arc_tolerance,
                      "SVG and G-code input: the largest distance of the cubic pieces of an arc "
                      "from the exact arc, in the input's unit (mm for SVG; default 1e-6)");
  command->add_option("--pen-z-below", reader->pen_z_below,
                      "G-code input with Z words: the pen is down while Z <= this (default 0)");
  command->add_option("--servo-down-below", reader->servo_down_below,
                      "G-code input with M280 (servo): the pen is down while the angle is below "
                      "this, degrees (default 50)");
  command->add_flag("--no-block-delete", reader->no_block_delete,
                    "G-code input: run the lines that start with / (skipped by default, as with "
                    "a controller's block-delete switch on)");
}

void AddGridOptions(CLI::App* command, GridOptions* options) {
  AddInputOptions(command, &options->file, &options->input_format, &options->reader);
  command
      ->add_option("--grid", options->grid,
                   "steps per patch: N (NxN) or NxM, each 1.." + std::to_string(kMaxPatchSteps))
      ->required();
  command
      ->add_option("--quantum", options->quantum,
                   "output quantum Q in file units; positions are whole multiples of Q")
      ->capture_default_str();
}

double ParseNumber(const std::string& text, const std::string& what) {
  double value = 0;
  std::size_t used = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value)) {
    throw InputError(what + ": '" + text + "' is not a number");
  }
  return value;
}

double ParsePositive(const std::string& text, const std::string& what, bool allow_zero) {
  const double value = ParseNumber(text, what);
  if (value < 0 || (value == 0 && !allow_zero)) {
    throw InputError(what + ": '" + text + "' must be " +
                     (allow_zero ? "zero or more" : "greater than zero"));
  }
  return value;
}

double MmPerUnit(const std::string& units) { return units == "in" ? 25.4 : 1.0; }

double DefaultIn(double mm, const std::string& units) { return mm / MmPerUnit(units); }

Quantum DefaultResolutionIn(const Quantum& mm, const std::string& units) {
  if (units != "in") return mm;
  // The largest 10^-k <= value: k = ceil(-log10(value)), nudged so that a
  // value that is a power of ten itself keeps its k.
  const double value = mm.value() / 25.4;
  const int decimals = static_cast<int>(std::ceil(-std::log10(value) - 1e-9));
  if (decimals < 1) return Quantum::Parse("1");
  return Quantum::Parse("0." + std::string(static_cast<std::size_t>(decimals - 1), '0') + "1");
}

Quantum DefaultStepIn(const Quantum& mm, const std::string& units) {
  if (units != "in") return mm;
  char text[32];
  std::snprintf(text, sizeof text, "%.9f", mm.value() / 25.4);
  return Quantum::Parse(text, "--step");
}

std::string DefaultInMmHelp(double mm, const std::string& unit) {
  return "(default " + FormatNumber(mm) + " " + unit + "; converted for --units in)";
}

std::array<int, 2> ParseLines(const std::string& text) {
  const std::size_t x = text.find('x');
  const auto parse = [&](std::string_view part) {
    int value = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size() || value == 1 ||
        value < 0 || value > kMaxPatchSteps + 1) {
      throw InputError("--lines: '" + text +
                       "' is not U or UxV with each count 0 (left out) or 2.." +
                       std::to_string(kMaxPatchSteps + 1));
    }
    return value;
  };
  const std::string_view all(text);
  const int u = parse(all.substr(0, x));
  return {u, x == std::string::npos ? u : parse(all.substr(x + 1))};
}

namespace {

struct Paper {
  const char* name;
  double width;
  double height;
  bool inches;
};

// ISO 216 (mm) and the US sizes (inches), portrait.
constexpr Paper kPapers[] = {
    {"a3", 297, 420, false},   {"a4", 210, 297, false},  {"a5", 148, 210, false},
    {"letter", 8.5, 11, true}, {"legal", 8.5, 14, true},
};

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

}  // namespace

std::optional<std::array<double, 2>> ParsePage(const std::string& text, const std::string& units,
                                               const std::string& what) {
  if (text == "none") return std::nullopt;
  std::string name = Lower(text);
  bool landscape = false;
  const std::string kLandscape = ":landscape";
  if (name.size() > kLandscape.size() &&
      name.compare(name.size() - kLandscape.size(), kLandscape.size(), kLandscape) == 0) {
    landscape = true;
    name.resize(name.size() - kLandscape.size());
  }
  for (const Paper& paper : kPapers) {
    if (name != paper.name) continue;
    const bool in = units == "in";
    const double to_units = paper.inches == in ? 1.0 : (paper.inches ? 25.4 : 1 / 25.4);
    std::array<double, 2> page{paper.width * to_units, paper.height * to_units};
    if (landscape) std::swap(page[0], page[1]);
    return page;
  }
  const std::size_t x = text.find('x');
  // Both sides must read as numbers for a WxH; ParsePositive then says which
  // one is out of range.
  const auto is_number = [](const std::string& part) {
    std::size_t used = 0;
    try {
      (void)std::stod(part, &used);
    } catch (const std::exception&) {
      return false;
    }
    return used == part.size();
  };
  if (landscape || x == std::string::npos || !is_number(text.substr(0, x)) ||
      !is_number(text.substr(x + 1))) {
    throw InputError(what + ": '" + text +
                     "' is not WxH (like 200x150) or a paper name (A3, A4, A5, letter, legal, "
                     "optionally :landscape)");
  }
  return std::array<double, 2>{ParsePositive(text.substr(0, x), what + " width"),
                               ParsePositive(text.substr(x + 1), what + " height")};
}

void AddPageOptions(CLI::App* command, std::string* fit, std::string* origin, std::string* margin) {
  command->add_option("--fit", *fit,
                      "the page: WxH in --units, A3, A4, A5, letter or legal (:landscape for "
                      "landscape), or none (no page: file units, no scaling); default: the "
                      "file's own page, else 200x150 mm for a drawing that is fitted");
  command->add_option("--origin", *origin,
                      "keep (the file's coordinates are the machine's: not scaled or moved), "
                      "center (scaled to fit, centred) or min (scaled to fit, lower-left corner "
                      "at the margin); default: keep for a file with its own page or a G-code "
                      "program, center otherwise");
  command->add_option(
      "--margin", *margin,
      "space around the drawing, in --units " + DefaultInMmHelp(kDefaultMarginMm, "mm"));
}

PageOrigin ParseOrigin(const std::string& text) {
  if (text == "keep") return PageOrigin::kKeep;
  if (text == "center") return PageOrigin::kCenter;
  if (text == "min") return PageOrigin::kMin;
  throw InputError("--origin: '" + text + "' is not keep, center or min");
}

std::array<double, 2> DefaultPage(const std::string& units) {
  return {DefaultIn(200, units), DefaultIn(150, units)};
}

void PlacePage(const std::string& fit, const std::string& origin, const std::string& units,
               double to_work, const PatchSet& set, ToolpathOptions* t) {
  const bool placed_by_author = set.page.has_value() || set.keep_order;
  t->origin = origin.empty() ? (placed_by_author ? PageOrigin::kKeep : PageOrigin::kCenter)
                             : ParseOrigin(origin);
  t->fit.reset();
  if (!fit.empty()) {
    if (const auto page = ParsePage(fit, units)) {
      t->fit = std::array<double, 2>{(*page)[0] * to_work, (*page)[1] * to_work};
    }
  } else if (set.page && t->origin != PageOrigin::kKeep) {
    // The file's own page, in working units (PlanPage takes it itself under keep).
    t->fit =
        std::array<double, 2>{(*set.page)[0] * t->units_scale, (*set.page)[1] * t->units_scale};
  } else if (t->origin != PageOrigin::kKeep) {
    // A drawing that is moved anyway is fitted to the common page; one that
    // keeps its coordinates keeps its size.
    const auto page = DefaultPage(units);
    t->fit = std::array<double, 2>{page[0] * to_work, page[1] * to_work};
  }
}
View ParseView(const std::string& text) {
  if (const std::optional<View> named = NamedView(text)) return *named;
  const std::size_t comma = text.find(',');
  double az = 0;
  double el = 0;
  std::size_t used_az = 0;
  std::size_t used_el = 0;
  bool ok = comma != std::string::npos;
  try {
    if (ok) {
      az = std::stod(text.substr(0, comma), &used_az);
      el = std::stod(text.substr(comma + 1), &used_el);
    }
  } catch (const std::exception&) {
    ok = false;
  }
  ok = ok && used_az == comma && used_el == text.size() - comma - 1 && std::isfinite(az) &&
       std::isfinite(el);
  if (!ok) {
    throw InputError("--view: '" + text +
                     "' is not a view: use top, front, side, iso or AZ,EL in degrees");
  }
  return ViewFromAngles(text, az, el);
}

std::string FlagFor(const std::string& field) {
  std::string flag = "--" + field;
  // "pen delay" is --pen-delay; "travel X" stays "--travel X" (the axis of
  // the one --travel option).
  if (field.find(' ') != std::string::npos && field.rfind("travel ", 0) != 0) {
    std::replace(flag.begin(), flag.end(), ' ', '-');
  }
  return flag;
}

StagedOutputs::~StagedOutputs() {
  for (const auto& [temporary, final_name] : staged_) std::remove(temporary.c_str());
}

std::string StagedOutputs::Stage(const std::string& file) {
  std::string temporary = file + ".fdsurf-" + std::to_string(getpid()) + ".tmp";
  staged_.emplace_back(temporary, file);
  return temporary;
}

void StagedOutputs::Commit() {
  for (const auto& [temporary, final_name] : staged_) {
    if (std::rename(temporary.c_str(), final_name.c_str()) != 0) {
      throw OutputError(final_name + ": cannot write: " + std::strerror(errno));
    }
  }
  staged_.clear();
}

PatchSet ReadInput(const std::string& file, const std::string& input_format,
                   const ReaderFlags& reader) {
  ReadOptions options;
  if (!reader.arc_tolerance.empty()) {
    const double tolerance = ParsePositive(reader.arc_tolerance, "--arc-tolerance");
    options.svg.arc_tolerance = tolerance;
    options.gcode.arc_tolerance = tolerance;
  }
  std::vector<std::string> gcode_flags;
  if (!reader.pen_z_below.empty()) {
    options.gcode.pen_z_threshold = ParseNumber(reader.pen_z_below, "--pen-z-below");
    gcode_flags.emplace_back("--pen-z-below");
  }
  if (!reader.servo_down_below.empty()) {
    options.gcode.servo_down_below = ParseNumber(reader.servo_down_below, "--servo-down-below");
    gcode_flags.emplace_back("--servo-down-below");
  }
  if (reader.no_block_delete) {
    options.gcode.skip_block_delete = false;
    gcode_flags.emplace_back("--no-block-delete");
  }
  std::string format;
  PatchSet set = ReadPatchFile(file, input_format, options, &format);
  const std::string name = file == "-" ? "<stdin>" : file;
  if (!reader.arc_tolerance.empty() && format != "svg" && format != "gcode") {
    throw InputError("--arc-tolerance: " + name + " is " + format +
                     " input, which has no arcs (the option is for SVG and G-code input)");
  }
  if (!gcode_flags.empty() && format != "gcode") {
    throw InputError(gcode_flags.front() + ": " + name + " is " + format +
                     " input (the option is for G-code input)");
  }
  return set;
}

PatchSet ReadDrawing(const std::string& file, const std::string& input_format,
                     const ReaderFlags& reader, const std::string& layer, bool quiet) {
  PatchSet set = ReadInput(file, input_format, reader);
  if (!layer.empty()) SelectLayer(&set, layer);
  if (!quiet) {
    for (const std::string& note : set.notes) {
      if (note.find(": left out: ") != std::string::npos) {
        std::fprintf(stderr, "fdsurf: note: %s\n", note.c_str());
      }
    }
  }
  return set;
}

bool IsFlatDrawing(const PatchSet& set) {
  if (!set.patches.empty() || set.curves.empty()) return false;
  // A page (SVG) or a program (G-code, whose Z is the pen) is drawn in plan.
  if (set.page || set.keep_order) return true;
  return std::all_of(set.curves.begin(), set.curves.end(), [](const Curve& curve) {
    return std::all_of(curve.g.begin(), curve.g.end(), [](const Point3& p) { return p[2] == 0; });
  });
}

bool ShowProgress(bool quiet) {
  return !quiet && isatty(STDERR_FILENO) != 0 && std::getenv("CI") == nullptr;
}

std::string DescribeDrawing(std::size_t patches, std::size_t curves) {
  const auto counted = [](std::size_t n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
  if (patches == 0 && curves == 0) return "no patches or curves";
  if (curves == 0) return counted(patches, "patch", "patches");
  if (patches == 0) return counted(curves, "curve", "curves");
  return counted(patches, "patch", "patches") + " and " + counted(curves, "curve", "curves");
}

}  // namespace fdsurf::host
