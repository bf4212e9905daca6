// SPDX-License-Identifier: MIT
#include "cli_options.h"

#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "fdsurf/forward_difference.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/svg_io.h"

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

void AddGridOptions(CLI::App* command, GridOptions* options) {
  command
      ->add_option(
          "FILE", options->file,
          "drawing: patches (.bpt, .json) or a triangle mesh (.obj, .ply); see docs/formats.md")
      ->required();
  command
      ->add_option("--grid", options->grid,
                   "steps per patch: N (NxN) or NxM, each 1.." + std::to_string(kMaxPatchSteps))
      ->required();
  command
      ->add_option("--quantum", options->quantum,
                   "output quantum Q in file units; positions are whole multiples of Q")
      ->capture_default_str();
}

double ParsePositive(const std::string& text, const std::string& what, bool allow_zero) {
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
  if (value < 0 || (value == 0 && !allow_zero)) {
    throw InputError(what + ": '" + text + "' must be " +
                     (allow_zero ? "zero or more" : "greater than zero"));
  }
  return value;
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

std::array<double, 2> ParsePage(const std::string& text, const std::string& what) {
  const std::size_t x = text.find('x');
  if (x == std::string::npos) throw InputError(what + ": '" + text + "' is not WxH (like 200x150)");
  return {ParsePositive(text.substr(0, x), what + " width"),
          ParsePositive(text.substr(x + 1), what + " height")};
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

PatchSet ReadDrawing(const std::string& file, const std::string& layer, bool quiet) {
  PatchSet set = ReadPatchFile(file);
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
  return std::all_of(set.curves.begin(), set.curves.end(), [](const Curve& curve) {
    return std::all_of(curve.g.begin(), curve.g.end(), [](const Point3& p) { return p[2] == 0; });
  });
}

bool ShowProgress(bool quiet) {
  return !quiet && isatty(STDERR_FILENO) != 0 && std::getenv("CI") == nullptr;
}

}  // namespace fdsurf::host
