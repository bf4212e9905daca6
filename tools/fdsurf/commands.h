// SPDX-License-Identifier: MIT
// The commands of the fdsurf tool, one file each: sample_command.cc,
// check_command.cc, plot_command.cc (plot and render), stream_command.cc,
// construct_commands.cc (joins), ports_command.cc. Each Run* returns the exit code: 0 done,
// 1 a bound broken, 2 bad input; they throw InputError, OptionError,
// OutputError and EngineError, which fdsurf.cc reports.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cli_options.h"
#include "fdsurf/host/writers.h"

namespace CLI {
class App;
}

namespace fdsurf::host {

/// `sample`: prints patch,i,j,x,y,z for every grid point (and the curves).
int RunSample(const GridOptions& options);

/// `check`: per patch, the accumulator, the exactness and the largest error
/// in quanta; 1 when a point is outside 0.51 quanta.
int RunCheck(const GridOptions& options);

struct PlotOptions {
  std::string file;
  std::string input_format;
  ReaderFlags reader;
  std::string format;
  std::string output = "-";
  std::string png;
  int png_width = 1600;
  std::string tolerance;
  std::string lines = "8";
  std::string view;  // empty: iso, or top for a flat drawing (IsFlatDrawing)
  std::string units = "mm";
  std::string layer;  // --layer NAME|N, empty: all
  std::string fit;
  std::string origin;
  std::string margin;
  std::string quantum;
  std::string mode = "adaptive";
  int dims = 2;
  bool plan = true;
  bool quiet = false;
  /// --hidden: "show" (every line) or "remove" (hidden_lines.h).
  std::string hidden = "show";
  GcodeOptions gcode;
  /// The G-code heights (--pen-up, --pen-down, in --units) and rates
  /// (--feed, --plunge-feed, --travel-rate, --units per minute) as typed;
  /// nullopt when left out: GcodeOptions' defaults, which are mm and mm/min,
  /// converted to --units (GcodeFor, plot_command.cc).
  std::optional<double> pen_up_z;
  std::optional<double> pen_down_z;
  std::optional<double> feed;
  std::optional<double> plunge_feed;
  std::optional<double> travel_rate;
  /// The time estimate's machine (--accel, --units/s²; --junction-deviation,
  /// --units), as typed; nullopt: stream's 2000 mm/s² and Grbl's 0.01 mm
  /// converted to --units.
  std::optional<double> accel;
  std::optional<double> junction_deviation;
  /// --accel-x, --accel-y, --accel-z: each axis's limit in the estimate,
  /// --units/s² (GcodeOptions::axis_accel); 0 (the default): none.
  std::array<double, 3> axis_accel{0, 0, 0};
};

struct PortsOptions {
  std::vector<std::string> paths;
  bool probe = false;
  std::uint32_t baud = 115200;
  double timeout_s = 3;
};

/// Adds the options of `ports`.
void AddPortsOptions(CLI::App* command, PortsOptions* options);

/// `ports`: a table of the serial ports (and the PATHs given), with --probe
/// what answered HELLO on each (only on the PATHs, when some are given). 0,
/// or 3 for a PATH that does not exist, or when --probe found no port that
/// answers.
int RunPorts(const PortsOptions& options);

/// Adds the options of `plot` (or, with `render_only`, of `render`).
void AddPlotOptions(CLI::App* command, PlotOptions* options, bool render_only);

/// `plot` and `render`: draws the isolines and writes them.
int RunPlot(const PlotOptions& options, bool render_only);

}  // namespace fdsurf::host
