// SPDX-License-Identifier: MIT
// fdsurf: the command-line tool. Every command validates its whole input
// before it writes anything, so an error leaves stdout empty.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "cli_options.h"
#include "construct_commands.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quantum.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/toolpath.h"
#include "fdsurf/host/writers.h"
#include "fdsurf_version.h"
#include "stream_command.h"

namespace fdsurf::host {
namespace {

struct Grid {
  int steps_s = 0;
  int steps_t = 0;
};

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

struct SampleOptions {
  std::string file;
  std::string grid;
  std::string engine = "fixed";
  std::string quantum = "0.001";
};

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

std::string FormatDouble(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

int RunSample(const SampleOptions& options) {
  const Grid grid = ParseGrid(options.grid);
  const Quantum quantum = Quantum::Parse(options.quantum);
  const PatchSet set = ReadPatchFile(options.file);
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
                     FormatDouble(v[0]) + "," + FormatDouble(v[1]) + "," + FormatDouble(v[2]) +
                     "\n");
        }
      }
    }
  }
  curves.Write([&](const std::string& text) { out.Append(text); });
  return 0;
}

int RunCheck(const SampleOptions& options) {
  const Grid grid = ParseGrid(options.grid);
  const Quantum quantum = Quantum::Parse(options.quantum);
  const PatchSet set = ReadPatchFile(options.file);
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
  const double curve_worst = CheckCurves(set, quantum, grid.steps_s);
  std::printf("overall: max error %.6f quanta (%.3g %s) in patch %zu, %zu patches: %s\n", worst,
              worst * q, units.c_str(), worst_patch, set.patches.size(),
              worst <= 0.51 ? "within the 0.51-quantum bound" : "BOUND VIOLATED");
  return worst <= 0.51 && curve_worst <= 0.51 ? 0 : 1;
}

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

struct PlotOptions {
  std::string file;
  std::string format;
  std::string output = "-";
  std::string png;
  int png_width = 1600;
  std::string tolerance;
  std::string lines = "8";
  std::string view = "iso";
  std::string units = "mm";
  std::string fit;
  std::string margin;
  std::string quantum;
  std::string mode = "adaptive";
  int dims = 2;
  bool plan = true;
  bool quiet = false;
  GcodeOptions gcode;
};

std::string FormatFromName(const std::string& name) {
  const auto ends_with = [&](const char* ext) {
    const std::string e(ext);
    return name.size() > e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
  };
  if (ends_with(".gcode") || ends_with(".nc") || ends_with(".ngc")) return "gcode";
  if (ends_with(".hpgl") || ends_with(".plt")) return "hpgl";
  if (ends_with(".json")) return "json";
  return "svg";
}

int RunPlot(const PlotOptions& o, bool render_only) {
  const std::string format =
      render_only ? "png" : (o.format.empty() ? FormatFromName(o.output) : o.format);
  const bool hpgl = format == "hpgl";
  // Option values are in --units; HPGL files are always in plotter units of
  // 0.025 mm, so an HPGL job works in mm internally.
  const double to_work = hpgl && o.units == "in" ? 25.4 : 1.0;
  const std::string work_units = hpgl ? "mm" : o.units;
  ToolpathOptions t;
  t.tolerance = to_work * (o.tolerance.empty() ? (o.units == "in" ? 0.002 : 0.05)
                                               : ParsePositive(o.tolerance, "--tolerance"));
  const auto lines = ParseLines(o.lines);
  t.lines_s = lines[0];
  t.lines_t = lines[1];
  t.view = ParseView(o.view);
  if (!o.fit.empty()) {
    auto page = ParsePage(o.fit);
    t.fit = std::array<double, 2>{page[0] * to_work, page[1] * to_work};
  }
  t.margin = to_work * (o.margin.empty() ? (o.units == "in" ? 0.2 : 5.0)
                                         : ParsePositive(o.margin, "--margin", true));
  if (hpgl) {
    if (!o.quantum.empty() && o.quantum != "0.025") {
      throw InputError(
          "--quantum: HPGL positions are plotter units of 0.025 mm; leave --quantum out");
    }
    t.quantum = Quantum::Parse("0.025");
  } else {
    t.quantum =
        Quantum::Parse(o.quantum.empty() ? (o.units == "in" ? "0.0001" : "0.001") : o.quantum);
  }
  if (o.dims == 3 && format != "gcode" && format != "json") {
    throw InputError("--dims 3: only G-code and JSON carry a third axis");
  }
  t.dims = o.dims;
  t.mode = o.mode == "fixed"        ? StepMode::kFixed
           : o.mode == "step-exact" ? StepMode::kStepExact
                                    : StepMode::kAdaptive;

  const PatchSet set = ReadPatchFile(o.file);
  const std::string file_units = set.units.empty() ? "mm" : set.units;
  t.units_scale = file_units == work_units ? 1.0 : (file_units == "in" ? 25.4 : 1 / 25.4);

  const bool progress = ShowProgress(o.quiet);
  Toolpath path =
      BuildToolpath(set, t, work_units, [&](std::size_t done, std::size_t all, std::size_t points) {
        if (progress) {
          std::fprintf(stderr, "\rfdsurf: patch %zu/%zu (%3zu%%), %zu points", done, all,
                       done * 100 / all, points);
        }
      });
  if (progress) std::fputc('\n', stderr);
  std::size_t points = 0;
  std::size_t longest = 0;
  for (const Stroke& s : path.strokes) {
    points += s.points.size();
    longest = std::max(longest, s.points.size());
  }
  const std::size_t curves = path.strokes.size();
  PlanReport plan;
  if (o.plan) plan = PlanStrokes(&path);

  std::vector<std::string> header = {
      "generated by fdsurf plot (fixed-point forward differences)",
      "source: " + o.file + " (" + std::to_string(set.patches.size()) + " patches)",
      "view " + t.view.name + ", lines " + std::to_string(t.lines_s) + "x" +
          std::to_string(t.lines_t) + ", mode " + o.mode + ", tolerance " + Number(t.tolerance) +
          " " + work_units + ", quantum " + t.quantum.Format(1) + " " + work_units,
      "page " + Number(path.width) + " x " + Number(path.height) + " " + work_units + ", " +
          std::to_string(path.strokes.size()) + " strokes, " + std::to_string(points) + " points"};

  StagedOutputs outputs;
  std::string content;
  if (format == "svg") content = WriteSvg(path, o.file + " drawn by fdsurf");
  if (format == "gcode") content = WriteGcode(path, o.gcode, header);
  if (format == "hpgl") content = WriteHpgl(path);
  if (format == "json") content = WriteStrokesJson(path);
  const std::string png = render_only ? o.output : o.png;
  if (!png.empty()) RenderPng(path, o.png_width, outputs.Stage(png));
  const bool to_stdout = !render_only && o.output == "-";
  if (!render_only && !to_stdout) WriteFile(outputs.Stage(o.output), content);
  outputs.Commit();
  if (to_stdout) std::fwrite(content.data(), 1, content.size(), stdout);
  if (!o.quiet) {
    std::fprintf(
        stderr,
        "%s: %zu patches, %zu curves, %zu points, longest curve %zu (%s, tolerance %s %s)\n",
        o.file.c_str(), set.patches.size(), curves, points, longest, o.mode.c_str(),
        Number(t.tolerance).c_str(), work_units.c_str());
    if (o.plan) {
      std::fprintf(stderr,
                   "plan: %zu strokes -> %zu (%zu drawn twice removed); pen-down %.1f -> %.1f %s; "
                   "pen-up %.1f -> %.1f %s\n",
                   plan.strokes_before, plan.strokes_after, plan.duplicates_removed,
                   plan.pen_down_before, plan.pen_down_after, work_units.c_str(),
                   plan.pen_up_before, plan.pen_up_after, work_units.c_str());
    }
    if (!render_only && !to_stdout) {
      std::fprintf(stderr, "wrote %s (%s, page %s x %s %s)\n", o.output.c_str(), format.c_str(),
                   Number(path.width).c_str(), Number(path.height).c_str(), work_units.c_str());
    }
    if (!png.empty())
      std::fprintf(stderr, "wrote %s (png, %d px wide)\n", png.c_str(), o.png_width);
  }
  return 0;
}

void AddPlotOptions(CLI::App* command, PlotOptions* o, bool render_only) {
  command->add_option("FILE", o->file, "patch file (.bpt or .json, see docs/formats.md)")
      ->required();
  if (render_only) {
    command->add_option("-o,--output", o->output, "the PNG file to write")->required();
  } else {
    command
        ->add_option("--format", o->format,
                     "svg, gcode, hpgl or json (default: from -o's extension, else svg)")
        ->check(CLI::IsMember({"svg", "gcode", "hpgl", "json"}));
    command->add_option("-o,--output", o->output, "output file, - for stdout")
        ->capture_default_str();
    command->add_option("--png", o->png, "also draw the result as a PNG picture");
  }
  command->add_option("--size", o->png_width, "PNG width in pixels")
      ->check(CLI::Range(16, 20000))
      ->capture_default_str();
  command->add_option(
      "--tolerance", o->tolerance,
      "largest distance of the drawing from the exact curves, in --units (default 0.05 mm / "
      "0.002 in)");
  command
      ->add_option("--lines", o->lines, "isolines per patch: U (UxU) or UxV, 0 leaves a family out")
      ->capture_default_str();
  command->add_option("--view", o->view, "top, front, side, iso or AZ,EL (degrees)")
      ->capture_default_str();
  command->add_option("--units", o->units, "units of the output and of these options")
      ->check(CLI::IsMember({"mm", "in"}))
      ->capture_default_str();
  command->add_option("--fit", o->fit, "scale the drawing to fit a WxH page");
  command->add_option("--margin", o->margin, "space around the drawing (default 5 mm / 0.2 in)");
  command->add_option("--quantum", o->quantum,
                      "output resolution (default 0.001 mm / 0.0001 in; HPGL 0.025 mm)");
  command
      ->add_option("--mode", o->mode,
                   "adaptive, fixed (uniform steps) or step-exact (≤ 1 quantum per axis)")
      ->check(CLI::IsMember({"adaptive", "fixed", "step-exact"}))
      ->capture_default_str();
  if (!render_only) {
    command->add_option("--dims", o->dims, "2 (the view plane) or 3 (with depth, for CNC G-code)")
        ->check(CLI::IsMember({2, 3}))
        ->capture_default_str();
    command
        ->add_option("--pen", o->gcode.pen,
                     "G-code pen control: z (Z moves) or m3 (M3/M5 and a dwell)")
        ->check(CLI::IsMember({"z", "m3"}))
        ->capture_default_str();
    command
        ->add_option("--pen-up", o->gcode.pen_up_z,
                     "G-code Z with the pen up (also 3-D travel height)")
        ->capture_default_str();
    command->add_option("--pen-down", o->gcode.pen_down_z, "G-code Z with the pen down")
        ->capture_default_str();
    command->add_option("--feed", o->gcode.feed, "G-code drawing feed, units per minute")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    command->add_option("--plunge-feed", o->gcode.plunge_feed, "G-code pen-down feed")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    command->add_option("--dwell", o->gcode.dwell, "G-code dwell after M3/M5, seconds")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    command->add_flag("!--no-plan", o->plan,
                      "keep the curves as drawn, without joining or ordering");
  }
  command->add_flag("-q,--quiet", o->quiet, "no summary or progress on stderr");
}

void AddCommonOptions(CLI::App* command, SampleOptions* options) {
  command->add_option("FILE", options->file, "patch file (.bpt or .json, see docs/formats.md)")
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

int Main(int argc, char** argv) {
  CLI::App app{
      "fdsurf: bicubic patches evaluated by fixed-point forward differences, with a proven "
      "0.51-quantum error bound."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("fdsurf ") + FDSURF_VERSION,
                       "Print the version and exit");

  SampleOptions sample_options;
  CLI::App* sample = app.add_subcommand(
      "sample",
      "Print every grid point of every patch as CSV: patch,i,j,x,y,z (s = i/N, t = j/M).");
  AddCommonOptions(sample, &sample_options);
  sample
      ->add_option("--engine", sample_options.engine,
                   "fixed: forward differences, exact multiples of Q; double: the reference")
      ->check(CLI::IsMember({"fixed", "double"}))
      ->capture_default_str();

  SampleOptions check_options;
  CLI::App* check = app.add_subcommand(
      "check", "Compare the fixed engine with the double reference on every grid point.");
  AddCommonOptions(check, &check_options);

  PlotOptions plot_options;
  CLI::App* plot = app.add_subcommand(
      "plot",
      "Draw the patches as a wireframe of isolines for a plotter or CNC: SVG, G-code, HPGL.");
  AddPlotOptions(plot, &plot_options, false);
  PlotOptions render_options;
  CLI::App* render = app.add_subcommand("render", "Draw the patches' isolines as a PNG picture.");
  AddPlotOptions(render, &render_options, true);

  StreamOptions stream_options;
  CLI::App* stream = app.add_subcommand(
      "stream",
      "Stream the patches to a plotter (default: the simulated one), which evaluates them by "
      "forward differences and draws them; report what it drew.");
  AddStreamOptions(stream, &stream_options);

  JoinsOptions joins_options;
  CLI::App* joins = app.add_subcommand(
      "joins", "Report for every shared edge of the patches whether the join is C0, G1 or C1.");
  AddJoinsOptions(joins, &joins_options);

  // CLI11 would only say "a subcommand is required" for a mistyped command.
  const std::string first = argc > 1 ? argv[1] : "";
  if (argc > 1 && argv[1][0] != '-' && first != "sample" && first != "check" && first != "plot" &&
      first != "render" && first != "stream" && first != "joins") {
    std::fprintf(
        stderr,
        "fdsurf: error: unknown command '%s' (expected sample, check, plot, render, stream or "
        "joins)\n",
        argv[1]);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (sample->parsed()) return RunSample(sample_options);
    if (check->parsed()) return RunCheck(check_options);
    if (plot->parsed()) return RunPlot(plot_options, false);
    if (render->parsed()) return RunPlot(render_options, true);
    if (stream->parsed()) return RunStream(stream_options);
    if (joins->parsed()) return RunJoins(joins_options);
  } catch (const InputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 2;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 2;
  } catch (const EngineError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 3;
  }
  return 1;
}

}  // namespace
}  // namespace fdsurf::host

int main(int argc, char** argv) {
  try {
    return fdsurf::host::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fdsurf: internal error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "fdsurf: internal error\n");
  }
  return 4;
}
