// SPDX-License-Identifier: MIT
// `fdsurf plot` and `fdsurf render`: the patches' isolines as SVG, G-code,
// HPGL, JSON strokes or a PNG picture.
#include <CLI/CLI.hpp>
#include <array>
#include <cctype>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_options.h"
#include "commands.h"
#include "fdsurf/host/gcode_estimate.h"
#include "fdsurf/host/hidden_lines.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/toolpath.h"
#include "fdsurf/host/writers.h"
#include "runners/machine_schedule.h"

namespace fdsurf::host {
namespace {

std::string LowerSuffix(const std::string& name) {
  const std::size_t slash = name.find_last_of('/');
  const std::size_t dot = name.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string suffix = name.substr(dot);
  for (char& c : suffix) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return suffix;
}

// The format an output's suffix says, "" for a suffix no format has.
std::string FormatFromSuffix(const std::string& name) {
  const std::string suffix = LowerSuffix(name);
  if (suffix == ".svg") return "svg";
  if (suffix == ".gcode" || suffix == ".nc" || suffix == ".ngc") return "gcode";
  if (suffix == ".hpgl" || suffix == ".plt") return "hpgl";
  if (suffix == ".json") return "json";
  return "";
}

// The output format: --format, or -o's suffix, or SVG for stdout. A file
// whose suffix says another format, or no known one, is refused before
// anything is drawn: `-o x.pdf` would otherwise be an SVG named .pdf.
std::string OutputFormat(const PlotOptions& o, bool render_only) {
  const auto require_png = [](const std::string& file, const std::string& flag) {
    if (LowerSuffix(file) != ".png") {
      throw InputError(flag + ": '" + file + "' does not end in .png; the picture is PNG");
    }
  };
  if (!o.png.empty()) require_png(o.png, "--png");
  if (render_only) {
    require_png(o.output, "-o");
    return "png";
  }
  if (o.output == "-") return o.format.empty() ? "svg" : o.format;
  std::string by_suffix = FormatFromSuffix(o.output);
  if (by_suffix.empty()) {
    throw InputError("-o: '" + o.output +
                     "' has no suffix of a format fdsurf writes (.svg, .gcode, .nc, .ngc, "
                     ".hpgl, .plt, .json)");
  }
  if (!o.format.empty() && o.format != by_suffix) {
    throw InputError("-o: '" + o.output + "' says " + by_suffix + " but --format is " + o.format);
  }
  return by_suffix;
}

// Working units per --units unit (HPGL works in mm).
double ToWork(const PlotOptions& o, const std::string& format) {
  return format == "hpgl" ? MmPerUnit(o.units) : 1.0;
}

// A drawing kept at its own coordinates may run past its page; the SVG and
// PNG then show more than the page (ViewOfPage), and the user is told so.
void NotePastPage(const std::string& svg_or_png, const Toolpath& path) {
  const PageView view = ViewOfPage(path);
  if (!view.past_page) return;
  const Quantum& q = path.quantum;
  std::fprintf(stderr,
               "fdsurf: note: the drawing runs past its %s x %s %s page; %s x %s..%s, y %s..%s "
               "%s\n",
               FormatNumber(path.width).c_str(), FormatNumber(path.height).c_str(),
               path.units.c_str(), svg_or_png.c_str(), q.Format(view.lo[0]).c_str(),
               q.Format(view.hi[0]).c_str(), q.Format(view.lo[1]).c_str(),
               q.Format(view.hi[1]).c_str(), path.units.c_str());
}

// The drawing options from the command line, in the job's working units
// (`work_units`): option values are in --units, but HPGL files are always
// in plotter units of 0.025 mm, so an HPGL job works in mm internally.
ToolpathOptions DrawingOptions(const PlotOptions& o, const std::string& format,
                               std::string* work_units) {
  const bool hpgl = format == "hpgl";
  const double to_work = ToWork(o, format);
  *work_units = hpgl ? "mm" : o.units;
  ToolpathOptions t;
  const ToolpathOptions mm;  // the library's defaults, in mm
  t.tolerance = to_work * (o.tolerance.empty() ? DefaultIn(mm.tolerance, o.units)
                                               : ParsePositive(o.tolerance, "--tolerance"));
  const auto lines = ParseLines(o.lines);
  t.lines_s = lines[0];
  t.lines_t = lines[1];
  t.view = ParseView(o.view.empty() ? "iso" : o.view);
  // Checked before the file is read; PlacePage sets the page after.
  if (!o.fit.empty()) (void)ParsePage(o.fit, o.units);
  if (!o.origin.empty()) (void)ParseOrigin(o.origin);
  t.margin = to_work * (o.margin.empty() ? DefaultIn(kDefaultMarginMm, o.units)
                                         : ParsePositive(o.margin, "--margin", true));
  if (hpgl) {
    if (!o.quantum.empty() && o.quantum != "0.025") {
      throw InputError(
          "--quantum: HPGL positions are plotter units of 0.025 mm; leave --quantum out");
    }
    t.quantum = Quantum::Parse("0.025");
  } else {
    t.quantum = o.quantum.empty() ? DefaultResolutionIn(mm.quantum, o.units)
                                  : Quantum::Parse(o.quantum, "--quantum");
  }
  if (o.dims == 3 && format != "gcode" && format != "json") {
    throw InputError("--dims 3: only G-code and JSON carry a third axis");
  }
  t.dims = o.dims;
  t.mode = o.mode == "fixed"        ? StepMode::kFixed
           : o.mode == "step-exact" ? StepMode::kStepExact
                                    : StepMode::kAdaptive;
  return t;
}

// Grbl's default junction deviation, mm (its $11 setting).
constexpr double kGrblJunctionDeviationMm = 0.01;

// The G-code options with the heights and rates as typed, or GcodeOptions'
// defaults (mm, mm/min) in --units: a G-code job works in --units.
GcodeOptions GcodeFor(const PlotOptions& o) {
  const GcodeOptions mm;
  const auto typed_or_default = [&](const std::optional<double>& typed, double default_mm) {
    return typed ? *typed : DefaultIn(default_mm, o.units);
  };
  GcodeOptions g = o.gcode;
  g.pen_up_z = typed_or_default(o.pen_up_z, mm.pen_up_z);
  g.pen_down_z = typed_or_default(o.pen_down_z, mm.pen_down_z);
  g.feed = typed_or_default(o.feed, mm.feed);
  g.plunge_feed = typed_or_default(o.plunge_feed, mm.plunge_feed);
  g.travel_rate = typed_or_default(o.travel_rate, mm.travel_rate);
  // The estimate's machine: stream's path acceleration, Grbl's default
  // junction deviation ($11 = 0.010 mm).
  g.accel = typed_or_default(o.accel, MachineOptions{}.accel);
  g.junction_deviation = typed_or_default(o.junction_deviation, kGrblJunctionDeviationMm);
  g.axis_accel = o.axis_accel;
  g.estimate_in_header = true;
  return g;
}

// ", X 500, Y 400 UNITS/s² per axis" for the axes with a limit, else "".
std::string AxisLimits(const std::array<double, 3>& axis_accel, const char* units) {
  std::string text;
  for (std::size_t a = 0; a < 3; ++a) {
    if (axis_accel[a] > 0) text += std::string(", ") + "XYZ"[a] + " " + FormatNumber(axis_accel[a]);
  }
  return text.empty() ? text : text + " " + units + "/s² per axis";
}

// Counts of the drawing as drawn, before planning joins strokes.
struct DrawnCounts {
  std::size_t curves = 0;
  std::size_t points = 0;
  std::size_t longest = 0;
};

DrawnCounts CountDrawn(const Toolpath& path) {
  DrawnCounts counts;
  counts.curves = path.strokes.size();
  for (const Stroke& s : path.strokes) {
    counts.points += s.points.size();
    counts.longest = std::max(counts.longest, s.points.size());
  }
  return counts;
}

// The G-code header: what was drawn, from what, how.
std::vector<std::string> GcodeHeader(const PlotOptions& o, const PatchSet& set,
                                     const ToolpathOptions& t, const Toolpath& path,
                                     const std::string& work_units, std::size_t points) {
  return {"generated by fdsurf plot (fixed-point forward differences)",
          "source: " + o.file + " (" + DescribeDrawing(set.patches.size(), set.curves.size()) + ")",
          "view " + t.view.name + ", lines " + std::to_string(t.lines_s) + "x" +
              std::to_string(t.lines_t) + ", mode " + o.mode + ", tolerance " +
              FormatNumber(t.tolerance) + " " + work_units + ", quantum " + t.quantum.Format(1) +
              " " + work_units,
          "page " + FormatNumber(path.width) + " x " + FormatNumber(path.height) + " " +
              work_units + ", " + std::to_string(path.strokes.size()) + " strokes, " +
              std::to_string(points) + " points"};
}

void PrintSummary(const PlotOptions& o, const PatchSet& set, const ToolpathOptions& t,
                  const Toolpath& path, const std::string& work_units, const DrawnCounts& counts,
                  const PlanReport& plan, const std::string& format, bool wrote_output,
                  const std::string& png) {
  std::fprintf(stderr,
               "%s: %zu patches, %zu curves, %zu points, longest curve %zu (%s, tolerance %s %s)\n",
               o.file.c_str(), set.patches.size(), counts.curves, counts.points, counts.longest,
               o.mode.c_str(), FormatNumber(t.tolerance).c_str(), work_units.c_str());
  if (o.plan) {
    std::fprintf(stderr,
                 "plan: %zu strokes -> %zu (%zu drawn twice removed); pen-down %.1f -> %.1f %s; "
                 "pen-up %.1f -> %.1f %s\n",
                 plan.strokes_before, plan.strokes_after, plan.duplicates_removed,
                 plan.pen_down_before, plan.pen_down_after, work_units.c_str(), plan.pen_up_before,
                 plan.pen_up_after, work_units.c_str());
  }
  if (wrote_output) {
    std::fprintf(stderr, "wrote %s (%s, page %s x %s %s)\n", o.output.c_str(), format.c_str(),
                 FormatNumber(path.width).c_str(), FormatNumber(path.height).c_str(),
                 work_units.c_str());
  }
  if (!png.empty()) std::fprintf(stderr, "wrote %s (png, %d px wide)\n", png.c_str(), o.png_width);
}

// The G-code machine estimate on stderr, as `stream --dry-run` prints its
// own: machine time, distances, lifts, extent, the machine assumed.
void PrintGcodeEstimate(const Toolpath& path, const GcodeOptions& g) {
  const GcodeEstimate e = EstimateGcode(path, g);
  const char* units = path.units.c_str();
  std::fprintf(stderr, "machine time: %.1f s (%s) on a G-code machine at these feeds\n", e.seconds,
               FormatClock(e.seconds).c_str());
  std::fprintf(stderr, "pen down: %.1f %s, travel (G0): %.1f %s, %zu pen lift%s\n",
               e.pen_down_length, units, e.travel_length, units, e.pen_lifts,
               e.pen_lifts == 1 ? "" : "s");
  if (e.drew) {
    std::string extent = "page extent drawn: x " + FormatNumber(e.lo[0]) + ".." +
                         FormatNumber(e.hi[0]) + ", y " + FormatNumber(e.lo[1]) + ".." +
                         FormatNumber(e.hi[1]);
    if (e.dims == 3) extent += ", z " + FormatNumber(e.lo[2]) + ".." + FormatNumber(e.hi[2]);
    std::fprintf(stderr, "%s %s\n", extent.c_str(), units);
  }
  std::fprintf(stderr,
               "estimate: feed %s, plunge %s, G0 %s %s/min; accel %s %s/s²%s, junction deviation "
               "%s %s (docs/toolpaths.md, \"Time estimate\")\n",
               FormatNumber(g.feed).c_str(), FormatNumber(g.plunge_feed).c_str(),
               FormatNumber(g.travel_rate).c_str(), units, FormatNumber(g.accel).c_str(), units,
               AxisLimits(g.axis_accel, units).c_str(), FormatNumber(g.junction_deviation).c_str(),
               units);
}

// --flavor and the options that only some flavours use (docs/toolpaths.md).
void AddGcodeFlavorOptions(CLI::App* command, PlotOptions* o) {
  GcodeOptions* g = &o->gcode;
  command
      ->add_option("--flavor", g->flavor,
                   "G-code dialect: generic, grbl, marlin (G5, G4 P in ms, M280) or linuxcnc (G5)")
      ->check(CLI::IsMember({"generic", "grbl", "marlin", "linuxcnc"}))
      ->capture_default_str();
  command->add_flag("!--no-g5", g->g5, "G1 segments even where the flavour has G5 cubics");
  command->add_option("--servo-up", g->servo_up, "--pen servo: the angle with the pen up")
      ->check(CLI::Range(0.0, 360.0))
      ->capture_default_str();
  command->add_option("--servo-down", g->servo_down, "--pen servo: the angle with the pen down")
      ->check(CLI::Range(0.0, 360.0))
      ->capture_default_str();
  command->add_option("--servo-index", g->servo_index, "--pen servo: M280's servo index P")
      ->check(CLI::Range(0, 15))
      ->capture_default_str();
  command
      ->add_option("--travel-rate", o->travel_rate,
                   "G0 rate assumed by the time estimate, --units per minute " +
                       DefaultInMmHelp(GcodeOptions{}.travel_rate, "mm/min"))
      ->check(CLI::PositiveNumber);
  command
      ->add_option("--accel", o->accel,
                   "acceleration of every move in the time estimate, --units per second² " +
                       DefaultInMmHelp(MachineOptions{}.accel, "mm/s²"))
      ->check(CLI::PositiveNumber);
  for (std::size_t a = 0; a < 3; ++a) {
    const std::string flag = std::string("--accel-") + "xyz"[a];
    command
        ->add_option(flag, o->axis_accel[a],
                     std::string("the ") + "XYZ"[a] +
                         " axis's acceleration limit in the time estimate (Grbl's $12" + "012"[a] +
                         "), --units per second² (default: none)")
        ->check(CLI::PositiveNumber);
  }
  command
      ->add_option("--junction-deviation", o->junction_deviation,
                   "Grbl's junction deviation in the time estimate, in --units " +
                       DefaultInMmHelp(kGrblJunctionDeviationMm, "mm"))
      ->check(CLI::NonNegativeNumber);
}

// --pen-up, --pen-down, --feed and --plunge-feed: in --units, the defaults
// GcodeOptions' mm values converted (GcodeFor).
void AddGcodeHeightAndFeedOptions(CLI::App* command, PlotOptions* o) {
  const GcodeOptions mm;  // the defaults, in mm and mm/min
  command->add_option("--pen-up", o->pen_up_z,
                      "G-code Z with the pen up (also 3-D travel height), in --units " +
                          DefaultInMmHelp(mm.pen_up_z, "mm"));
  command->add_option(
      "--pen-down", o->pen_down_z,
      "G-code Z with the pen down, in --units " + DefaultInMmHelp(mm.pen_down_z, "mm"));
  command
      ->add_option("--feed", o->feed,
                   "G-code drawing feed, --units per minute " + DefaultInMmHelp(mm.feed, "mm/min"))
      ->check(CLI::PositiveNumber);
  command
      ->add_option(
          "--plunge-feed", o->plunge_feed,
          "G-code pen-down feed, --units per minute " + DefaultInMmHelp(mm.plunge_feed, "mm/min"))
      ->check(CLI::PositiveNumber);
}

// --hidden remove: only the visible pieces of the lines, with the tolerances
// stated on stderr.
void RemoveHidden(const PlotOptions& o, const PatchSet& set, const ToolpathOptions& t,
                  const std::string& work_units, Toolpath* path) {
  const HiddenLineOptions hidden = HiddenLineDefaults(t.tolerance);
  const HiddenLineReport r = RemoveHiddenLines(set, hidden, path);
  if (!o.quiet) std::fprintf(stderr, "%s\n", DescribeHiddenLines(r, hidden, work_units).c_str());
}

}  // namespace

int RunPlot(const PlotOptions& options, bool render_only) {
  // Messages name standard input "<stdin>", as the reader does.
  PlotOptions o = options;
  if (o.file == "-") o.file = "<stdin>";
  const std::string format = OutputFormat(o, render_only);
  std::string work_units;
  ToolpathOptions t = DrawingOptions(o, format, &work_units);
  const PatchSet set = ReadDrawing(options.file, o.input_format, o.reader, o.layer, o.quiet);
  if (o.view.empty() && IsFlatDrawing(set)) t.view = ParseView("top");
  const std::string file_units = set.units.empty() ? "mm" : set.units;
  t.units_scale = file_units == work_units ? 1.0 : MmPerUnit(file_units) / MmPerUnit(work_units);
  PlacePage(o.fit, o.origin, o.units, ToWork(o, format), set, &t);

  const bool progress = ShowProgress(o.quiet);
  Toolpath path =
      BuildToolpath(set, t, work_units, [&](std::size_t done, std::size_t all, std::size_t points) {
        if (progress) {
          std::fprintf(stderr, "\rfdsurf: patch %zu/%zu (%3zu%%), %zu points", done, all,
                       done * 100 / all, points);
        }
      });
  if (progress) std::fputc('\n', stderr);
  if (o.hidden == "remove") RemoveHidden(o, set, t, work_units, &path);
  const DrawnCounts counts = CountDrawn(path);
  PlanReport plan;
  if (o.plan) plan = PlanStrokes(set, &path);

  // Every output complete before any is renamed into place.
  StagedOutputs outputs;
  std::string content;
  const GcodeOptions gcode = GcodeFor(o);
  if (format == "svg") content = WriteSvg(path, o.file + " drawn by fdsurf");
  if (format == "gcode") {
    content = WriteGcode(path, gcode, GcodeHeader(o, set, t, path, work_units, counts.points));
  }
  if (format == "hpgl") content = WriteHpgl(path);
  if (format == "json") content = WriteStrokesJson(path);
  const std::string png = render_only ? o.output : o.png;
  if (!png.empty()) RenderPng(path, o.png_width, outputs.Stage(png));
  const bool to_stdout = !render_only && o.output == "-";
  if (!render_only && !to_stdout) WriteFile(outputs.Stage(o.output), content);
  outputs.Commit();
  if (to_stdout) std::fwrite(content.data(), 1, content.size(), stdout);
  const bool svg = format == "svg";
  if (!o.quiet && (svg || !png.empty())) {
    NotePastPage(svg && !png.empty() ? "the SVG and the PNG show"
                 : svg               ? "the SVG shows"
                                     : "the PNG shows",
                 path);
  }
  if (!o.quiet) {
    PrintSummary(o, set, t, path, work_units, counts, plan, format, !render_only && !to_stdout,
                 png);
    if (format == "gcode") PrintGcodeEstimate(path, gcode);
  }
  return 0;
}

void AddPlotOptions(CLI::App* command, PlotOptions* o, bool render_only) {
  AddInputOptions(command, &o->file, &o->input_format, &o->reader);
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
  command->add_option("--tolerance", o->tolerance,
                      "largest distance of the drawing from the exact curves, in --units " +
                          DefaultInMmHelp(ToolpathOptions{}.tolerance, "mm"));
  command
      ->add_option("--lines", o->lines, "isolines per patch: U (UxU) or UxV, 0 leaves a family out")
      ->capture_default_str();
  command->add_option("--view", o->view,
                      "top, front, side, iso or AZ,EL (degrees); default iso, top for a flat "
                      "drawing (SVG)");
  command->add_option("--layer", o->layer, "draw only this layer: its name or number (1, 2, ...)");
  command->add_option("--units", o->units, "units of the output and of these options")
      ->check(CLI::IsMember({"mm", "in"}))
      ->capture_default_str();
  AddPageOptions(command, &o->fit, &o->origin, &o->margin);
  command->add_option(
      "--quantum", o->quantum,
      "output resolution, in --units (default " + ToolpathOptions{}.quantum.Format(1) +
          " mm; for --units in the largest power of ten no coarser, " +
          DefaultResolutionIn(ToolpathOptions{}.quantum, "in").Format(1) + " in; HPGL 0.025 mm)");
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
                     "G-code pen control: z (Z moves), m3 (M3/M5 and a dwell) or servo (Marlin "
                     "M280 and a dwell)")
        ->check(CLI::IsMember({"z", "m3", "servo"}))
        ->capture_default_str();
    AddGcodeFlavorOptions(command, o);
    AddGcodeHeightAndFeedOptions(command, o);
    command->add_option("--dwell", o->gcode.dwell, "G-code dwell after M3/M5, seconds")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    command->add_flag("!--no-plan", o->plan,
                      "keep the curves as drawn, without joining or ordering");
  }
  command
      ->add_option("--hidden", o->hidden,
                   "show (every line) or remove (only what is visible from the view, against "
                   "the exact patches)")
      ->check(CLI::IsMember({"show", "remove"}))
      ->capture_default_str();
  command->add_flag("-q,--quiet", o->quiet, "no summary or progress on stderr");
}

}  // namespace fdsurf::host
