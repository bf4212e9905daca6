// SPDX-License-Identifier: MIT
// The simulated plotter as the device: the job runs in virtual time, then
// the drawing is compared with the exact curves and the recorded steps with
// the machine's limits.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "../cli_options.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/writers.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/sim/checks.h"
#include "fdsurf/sim/plotter.h"
#include "fdsurf/sim/waveform.h"
#include "runner.h"

namespace fdsurf::host {
namespace {

// ", travel V units/s" when the pen-up speed limit differs from --speed,
// else nothing (the summaries then read as before --travel-speed).
std::string TravelSpeedNote(const StreamOptions& o, const std::string& units) {
  if (o.travel_speed <= 0 || o.travel_speed == o.speed) return "";
  return ", travel " + FormatNumber(o.travel_speed) + " " + units + "/s";
}

// Each axis's acceleration limit: "4000" when the driven axes share one,
// else "X 4000, Y 3000".
std::string AxisAccelText(const std::array<double, 3>& axis_accel, int axes) {
  bool same = true;
  for (int a = 1; a < axes; ++a) same = same && axis_accel[a] == axis_accel[0];
  if (same) return FormatNumber(axis_accel[0]);
  std::string text;
  for (int a = 0; a < axes; ++a) {
    text += std::string(a == 0 ? "" : ", ") + "XYZ"[a] + " " + FormatNumber(axis_accel[a]);
  }
  return text;
}

// The drawn paths as a toolpath on the job's page, for the writers. A point
// between two unit moves in the same direction lies on the line through its
// neighbours: leaving it out draws exactly the same path with far fewer
// points (the teapot's SVG: 14.8 MB instead of 26; it stays the exact step path).
Toolpath DrawnToolpath(const StreamJob& job, const std::vector<sim::DrawnPath>& paths) {
  Toolpath drawn = job.page;
  drawn.quantum = PageQuantum(job);
  drawn.strokes.clear();
  for (const sim::DrawnPath& path : paths) {
    Stroke stroke;
    const auto& p = path.points;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const bool straight_through = k > 0 && k + 1 < p.size() &&
                                    p[k][0] - p[k - 1][0] == p[k + 1][0] - p[k][0] &&
                                    p[k][1] - p[k - 1][1] == p[k + 1][1] - p[k][1] &&
                                    p[k][2] - p[k - 1][2] == p[k + 1][2] - p[k][2];
      if (!straight_through) stroke.points.push_back(PagePosition(job, p[k]));
    }
    drawn.strokes.push_back(std::move(stroke));
  }
  return drawn;
}

// The same drawing as G-code line segments at the same tolerance: what a
// host would send a G-code controller instead of patches.
std::size_t GcodeBytes(const PatchSet& set, const ToolpathOptions& drawing,
                       const std::string& units) {
  ToolpathOptions t = drawing;
  t.mode = StepMode::kAdaptive;
  t.quantum = Quantum::Parse(units == "in" ? "0.0001" : "0.001");
  Toolpath path = BuildToolpath(set, t, units);
  PlanStrokes(set, &path);
  return WriteGcode(path, GcodeOptions{}, {}).size();
}

std::size_t CommandBytes(const StreamJob& job) {
  std::size_t bytes = 0;
  std::vector<std::uint8_t> frame(protocol::kMaxEncodedFrameBytes);
  for (const protocol::Command& command : job.commands) {
    bytes += protocol::EncodeCommand(command, frame.data(), frame.size());
  }
  return bytes;
}

sim::PlotterOptions PlotterOptionsFor(const StreamOptions& o, std::uint32_t tick_hz) {
  sim::PlotterOptions options;
  options.axes = o.dims;
  if (tick_hz != 0) options.tick_hz = tick_hz;
  options.bytes_per_second = o.link_bytes_per_second;
  options.to_device = sim::FaultRates::All(o.faults);
  options.to_host = sim::FaultRates::All(o.faults);
  options.fault_seed = o.seed;
  if (o.sim_cost == "atmega2560") options.device_cost = sim::DeviceCost::Atmega2560();
  return options;
}

// How StreamToPlotter runs the job: a run on the sim device shows the
// progress line and pauses for the pen change; a dry run pauses for
// nothing; a schedule for a real device's progress line shows nothing.
struct PlotterRun {
  bool show_progress = true;
  bool pause_between_layers = true;
  /// When set, filled with the machine time by which each command was
  /// executed (to the millisecond of virtual time).
  MachineSchedule* schedule = nullptr;
};

// Extends the schedule to `p.executed` commands, all done by `p.time_us`.
void RecordExecuted(std::uint64_t executed, std::uint64_t time_us, MachineSchedule* schedule) {
  while (schedule->executed_s.size() < executed) schedule->executed_s.push_back(time_us * 1e-6);
}

// Streams the job to the plotter until every command ran (or the link gave
// up), with the progress line. Layer by layer: the commands of one layer are
// sent, and only when the link reports them all executed and the device idle
// (the pen is up before every layer start) is the pen change asked for and
// the next layer sent. The machine's clock does not run during the pause.
sim::RunResult StreamToPlotter(const StreamOptions& o, const StreamJob& job,
                               sim::SimulatedPlotter* plotter, const PlotterRun& how) {
  HostLink link(LinkOptions());
  ProgressLine progress(how.show_progress && ShowProgress(o.quiet));
  constexpr std::uint64_t kTimeLimitUs = 24ull * 3600 * 1'000'000;  // a day of machine time
  // The progress line redraws at most 10 times a second of wall time anyway.
  const std::uint64_t interval_us = how.schedule != nullptr ? 1'000 : 250'000;
  sim::RunResult run;
  for (std::size_t from = 0;;) {
    const std::size_t to = NextLayerBoundary(job, from);
    progress.SetLayer(LayerLabel(job, from));
    Enqueue(job, &link, from, to);
    run = plotter->Run(
        link, kTimeLimitUs,
        [&](const sim::RunProgress& p) {
          if (how.schedule != nullptr) RecordExecuted(p.executed, p.time_us, how.schedule);
          progress.Show(p.executed, job.commands.size(), p.frames_sent, p.time_us * 1e-6);
        },
        interval_us);
    if (!run.finished || to == job.commands.size()) break;
    progress.Finish();
    if (how.pause_between_layers) PauseForLayer(o.no_pause, job, to, run.executed);
    from = to;
  }
  if (how.schedule != nullptr) RecordExecuted(run.executed, run.time_us, how.schedule);
  progress.Show(run.executed, job.commands.size(), run.host.frames_sent, run.time_us * 1e-6, true);
  progress.Finish();
  return run;
}

// How a step event becomes output units. With one step for every axis the
// figures are counted in steps (a step of two axes at once √2) and scaled by
// the step once, as they always were; a machine whose axes step differently
// counts each event as √(Σ step_a²) of the axes in it, in output units.
struct StepLengths {
  bool uniform = true;
  double scale = 1;                 // output units per counted unit
  std::array<double, 8> of_mask{};  // counted units of a step of the axes in the mask
  std::array<double, 3> axis{};     // each axis's step, output units
  double coarsest = 0;              // the longest step: a deviation bound's
};

StepLengths StepLengthsOf(const StreamJob& job) {
  StepLengths l;
  const int dims = job.page.dims;
  for (std::size_t a = 0; a < 3; ++a) l.axis[a] = job.steps[a].value();
  for (int a = 0; a < dims; ++a) {
    l.uniform = l.uniform && l.axis[static_cast<std::size_t>(a)] == l.axis[0];
    l.coarsest = std::max(l.coarsest, l.axis[static_cast<std::size_t>(a)]);
  }
  l.scale = l.uniform ? l.axis[0] : 1;
  for (unsigned mask = 0; mask < 8; ++mask) {
    double squares = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      if ((mask >> a & 1u) != 0) squares += l.uniform ? 1 : l.axis[a] * l.axis[a];
    }
    l.of_mask[mask] = std::sqrt(squares);
  }
  return l;
}

// What the plotter drew, checked against the exact curves and the limits.
struct CheckedDrawing {
  std::vector<sim::DrawnPath> drawn;
  /// The path's length, pen up and down, output units.
  double path_length = 0;
  sim::DrawingComparison comparison;
  sim::MotionReport motion;
  /// The deviation bound in steps: the tolerance, plus what the reference
  /// polyline itself may be off the exact curve (0.005 steps).
  double bound = 0;
  bool within = false;
  bool limits_kept = false;
};

CheckedDrawing CheckDrawing(const sim::SimulatedPlotter& plotter, const PatchSet& set,
                            const StreamJob& job, std::uint32_t tick_hz, int dims) {
  CheckedDrawing checked;
  checked.drawn = plotter.DrawnPaths();
  std::vector<sim::ReferenceLine> reference;
  for (auto& line : ReferenceLines(set, job)) {
    reference.push_back(sim::ReferenceLine{std::move(line)});
  }
  checked.comparison = sim::CompareDrawing(checked.drawn, reference, dims);
  sim::MotionLimitsSi limits;
  limits.tick_hz = tick_hz;
  limits.max_rate = job.config.max_rate;
  limits.travel_rate = job.config.travel_rate;
  limits.accel = job.config.accel;
  for (std::size_t a = 0; a < 3; ++a) limits.axis_accel_each[a] = job.config.axis_accel[a];
  limits.pen_delay_s = job.config.pen_delay_ms * 1e-3;
  checked.motion = sim::CheckMotion(plotter.step_events(), plotter.pen_events(), limits);
  const StepLengths lengths = StepLengthsOf(job);
  if (lengths.uniform) {
    checked.path_length = checked.motion.path_length * lengths.scale;
  } else {
    for (const hal::StepDirEvent& e : plotter.step_events()) {
      checked.path_length += lengths.of_mask[e.axis_mask & 7u];
    }
  }
  checked.bound = job.tolerance_steps + 0.005;
  checked.within = checked.comparison.max_deviation <= checked.bound &&
                   checked.comparison.max_gap <= checked.bound;
  checked.limits_kept = checked.motion.violations == 0;
  return checked;
}

// The plotter's pins as a waveform (docs/boards.md), with the job's limits
// in the header for the checker: a PEN line, DIR high towards negative,
// ENABLE active low (as A4988/DRV8825 boards).
void WriteWaveformFile(const std::string& path, const std::string& name, const StreamJob& job,
                       const sim::SimulatedPlotter& plotter) {
  sim::WaveformHeader header;
  header.board = "sim";
  header.extra["axes"] = std::to_string(plotter.options().axes);
  header.extra["tick_hz"] = std::to_string(plotter.options().tick_hz);
  header.extra["max_rate"] = std::to_string(job.config.max_rate);
  // Only when it differs, so a job with one speed writes the same header as
  // before --travel-speed (the checker takes max_rate when it is absent).
  if (job.config.travel_rate != job.config.max_rate) {
    header.extra["travel_rate"] = std::to_string(job.config.travel_rate);
  }
  header.extra["accel"] = std::to_string(job.config.accel);
  header.extra["pen_delay_ms"] = std::to_string(job.config.pen_delay_ms);
  header.extra["commands"] = std::to_string(job.commands.size());
  sim::WaveformWriteOptions write;
  write.axes = plotter.options().axes;
  std::ofstream out(path, std::ios::binary);
  sim::WriteWaveform(
      out, header,
      sim::TransitionsFromEvents(header, plotter.step_events(), plotter.pen_events(), write));
  out.close();
  if (!out) throw OutputError(name + ": cannot write the waveform");
}

// SVG, PNG and waveform of what was drawn: every one complete before any is
// renamed into place.
void WriteDrawing(const StreamOptions& o, const StreamJob& job,
                  const sim::SimulatedPlotter& plotter, const std::vector<sim::DrawnPath>& drawn) {
  const Toolpath drawn_path = DrawnToolpath(job, drawn);
  StagedOutputs outputs;
  if (!o.waveform.empty()) WriteWaveformFile(outputs.Stage(o.waveform), o.waveform, job, plotter);
  if (!o.svg.empty()) {
    WriteFile(outputs.Stage(o.svg),
              WriteSvg(drawn_path, o.file + " drawn by the simulated plotter"));
  }
  if (!o.png.empty()) RenderPng(drawn_path, o.png_width, outputs.Stage(o.png));
  outputs.Commit();
}

void PrintReport(const StreamOptions& o, const PatchSet& set, const StreamJob& job,
                 const ToolpathOptions& drawing, const std::string& units,
                 const sim::PlotterOptions& plotter_options, const sim::RunResult& run,
                 const CheckedDrawing& checked) {
  const StepLengths lengths = StepLengthsOf(job);
  // Speeds and deviations in steps are bounded in output units by the
  // coarsest step (exact when the axes agree).
  const double step = lengths.coarsest;
  const char* at_most = lengths.uniform ? "" : "at most ";
  const sim::DrawingComparison& comparison = checked.comparison;
  const sim::MotionReport& motion = checked.motion;
  std::size_t points = 0;
  for (const sim::DrawnPath& p : checked.drawn) points += p.points.size();
  const std::size_t command_bytes = CommandBytes(job);
  const std::size_t gcode_bytes = GcodeBytes(set, drawing, units);
  const std::string what = JobContents(job);
  std::fprintf(stderr,
               "%s: %s streamed to the simulated plotter (%u axes, %u Hz ticks); %zu shared edges "
               "drawn once\n",
               o.file.c_str(), what.c_str(), plotter_options.axes, plotter_options.tick_hz,
               job.shared_edges_skipped);
  std::fprintf(stderr,
               "link: %llu frames sent (%llu commands, %llu resent), %llu bytes to the device, "
               "%llu NAKs, %llu timeouts; all acknowledged after %.2f s\n",
               static_cast<unsigned long long>(run.host.frames_sent),
               static_cast<unsigned long long>(run.host.commands_sent),
               static_cast<unsigned long long>(run.host.retransmitted),
               static_cast<unsigned long long>(run.host.bytes_sent),
               static_cast<unsigned long long>(run.host.naks),
               static_cast<unsigned long long>(run.host.timeouts), run.acknowledged_us * 1e-6);
  if (o.sim_cost == "atmega2560") {
    std::fprintf(stderr,
                 "device: %.2f s of its main loop validating commands (--sim-cost atmega2560)\n",
                 run.validation_us * 1e-6);
  }
  std::fprintf(stderr,
               "wire: %zu bytes of command frames vs %zu bytes of G-code for the same drawing at "
               "the same tolerance (%.1fx smaller)\n",
               command_bytes, gcode_bytes,
               static_cast<double>(gcode_bytes) / static_cast<double>(command_bytes));
  const auto& axis_accel = motion.max_axis_accel;
  const int fastest_axis =
      static_cast<int>(std::max_element(axis_accel.begin(), axis_accel.end()) - axis_accel.begin());
  std::fprintf(stderr,
               "machine: %.1f s, %zu moves, %.0f %s of path (%zu pen-down strokes, %zu points), "
               "top speed %s%.1f %s/s, top axis acceleration %s %s/s² (%c)\n",
               motion.duration_s, motion.moves, checked.path_length, units.c_str(),
               checked.drawn.size(), points, at_most, motion.max_speed * step, units.c_str(),
               FormatNumber(axis_accel[fastest_axis] * lengths.axis[fastest_axis], 4).c_str(),
               units.c_str(), "XYZ"[fastest_axis]);
  std::fprintf(stderr,
               "drawing vs exact curves: max deviation %.3f steps (%s%.4f %s), max gap %.3f steps; "
               "bound %.3f steps (--tolerance): %s\n",
               comparison.max_deviation, at_most, comparison.max_deviation * step, units.c_str(),
               comparison.max_gap, checked.bound, checked.within ? "within" : "BOUND VIOLATED");
  const std::string limits =
      checked.limits_kept
          ? std::string("kept")
          : std::to_string(motion.violations) + " violations, first: " + motion.first_violation;
  std::fprintf(stderr,
               "motion limits (%s %s/s%s, %s %s/s² on the path, %s %s/s² per axis, pen delay %d "
               "ms): %s\n",
               FormatNumber(o.speed).c_str(), units.c_str(), TravelSpeedNote(o, units).c_str(),
               FormatNumber(o.accel).c_str(), units.c_str(),
               AxisAccelText(o.axis_accel, job.config.axes).c_str(), units.c_str(), o.pen_delay_ms,
               limits.c_str());
  if (!o.svg.empty()) std::fprintf(stderr, "wrote %s (svg)\n", o.svg.c_str());
  if (!o.waveform.empty()) std::fprintf(stderr, "wrote %s (waveform)\n", o.waveform.c_str());
  if (!o.png.empty()) {
    std::fprintf(stderr, "wrote %s (png, %d px wide)\n", o.png.c_str(), o.png_width);
  }
}

}  // namespace

int RunSimulated(const StreamOptions& o, const PatchSet& set, const StreamJob& job,
                 const ToolpathOptions& drawing, const std::string& units) {
  // As a board of 64-bit tables is sent it (FitJobToDevice): the same pieces.
  StreamJob sent = job;
  if (o.sim_64bit_tables) SplitForSixtyFourBitTables(&sent);
  const sim::PlotterOptions plotter_options = PlotterOptionsFor(o, o.tick_hz);
  CheckSpeedAgainstTicks(sent, plotter_options.tick_hz, o);
  sim::SimulatedPlotter plotter(plotter_options);
  const sim::RunResult run = StreamToPlotter(o, sent, &plotter, PlotterRun{});
  if (!run.finished) throw DeviceError("sim device: " + DecodeDeviceError(run.error));
  const CheckedDrawing checked = CheckDrawing(plotter, set, sent, plotter_options.tick_hz, o.dims);
  WriteDrawing(o, sent, plotter, checked.drawn);
  if (!o.quiet) PrintReport(o, set, sent, drawing, units, plotter_options, run, checked);
  return checked.within && checked.limits_kept ? 0 : 1;
}

namespace {

// What a dry run measures of the recorded motion. Distances are the motors':
// a step of two axes at once counts √2 steps (as the summary's path length).
struct DryRunFigures {
  double machine_s = 0;       // the last step, as CheckMotion's duration
  double pen_down_steps = 0;  // in StepLengths' counted units
  double pen_up_steps = 0;
  std::size_t pen_lifts = 0;
  std::array<std::int64_t, 3> lo{}, hi{};  // the positions drawn (pen down)
  bool drew = false;
};

DryRunFigures MeasureDryRun(const StreamJob& job, const sim::SimulatedPlotter& plotter,
                            const std::vector<sim::DrawnPath>& drawn) {
  DryRunFigures f;
  const StepLengths lengths = StepLengthsOf(job);
  const std::array<double, 3> counted =
      lengths.uniform ? std::array<double, 3>{1, 1, 1} : lengths.axis;
  double total = 0;
  for (const hal::StepDirEvent& e : plotter.step_events()) {
    if (e.axis_mask == 0) continue;
    total += lengths.of_mask[e.axis_mask & 7u];
    f.machine_s = e.time_us * 1e-6;
  }
  for (const sim::DrawnPath& path : drawn) {
    for (std::size_t k = 0; k < path.points.size(); ++k) {
      const auto& p = path.points[k];
      const std::array<std::int64_t, 3> on_page = PageSteps(job, p);
      for (int c = 0; c < 3; ++c) {
        f.lo[c] = f.drew ? std::min(f.lo[c], on_page[c]) : on_page[c];
        f.hi[c] = f.drew ? std::max(f.hi[c], on_page[c]) : on_page[c];
      }
      f.drew = true;
      if (k == 0) continue;
      const auto& q = path.points[k - 1];
      f.pen_down_steps += std::hypot(static_cast<double>(p[0] - q[0]) * counted[0],
                                     static_cast<double>(p[1] - q[1]) * counted[1],
                                     static_cast<double>(p[2] - q[2]) * counted[2]);
    }
  }
  f.pen_up_steps = std::max(0.0, total - f.pen_down_steps);
  for (const hal::PenEvent& pen : plotter.pen_events()) f.pen_lifts += pen.down ? 0 : 1;
  return f;
}

// Where the dry run's tick rate came from, for its first line.
std::string TickSource(const StreamOptions& o) {
  if (o.tick_hz != 0) return "--tick-hz";
  if (o.device == "sim") return "the simulator's default";
  if (o.device.rfind("gpio:", 0) == 0) return "the GPIO runner's default";
  return "assumed: a real device's own rate is known only after HELLO; give --tick-hz";
}

void PrintDryRun(const StreamOptions& o, const StreamJob& job, std::uint32_t tick_hz,
                 const DryRunFigures& f) {
  const StepLengths lengths = StepLengthsOf(job);
  const double step = lengths.scale;
  const auto& axis = lengths.axis;
  const char* units = o.units.c_str();
  std::printf(
      "%s: dry run of %s on the simulated plotter (%d axes, %u Hz ticks, %s); nothing "
      "sent to %s\n",
      o.file.c_str(), JobContents(job).c_str(), o.dims, tick_hz, TickSource(o).c_str(),
      o.device.c_str());
  std::printf("machine time: %.1f s (%s)\n", f.machine_s, FormatClock(f.machine_s).c_str());
  std::printf("pen down: %.1f %s, pen up (travel): %.1f %s, %zu pen lift%s\n",
              f.pen_down_steps * step, units, f.pen_up_steps * step, units, f.pen_lifts,
              f.pen_lifts == 1 ? "" : "s");
  if (f.drew) {
    std::string extent = "page extent drawn: x " + FormatNumber(f.lo[0] * axis[0]) + ".." +
                         FormatNumber(f.hi[0] * axis[0]) + ", y " +
                         FormatNumber(f.lo[1] * axis[1]) + ".." + FormatNumber(f.hi[1] * axis[1]);
    if (o.dims == 3) {
      extent += ", z " + FormatNumber(f.lo[2] * axis[2]) + ".." + FormatNumber(f.hi[2] * axis[2]);
    }
    std::printf("%s %s\n", extent.c_str(), units);
  } else {
    std::printf("page extent drawn: nothing drawn\n");
  }
  std::printf("commands: %zu; limits %s %s/s%s, %s %s/s², pen delay %d ms\n", job.commands.size(),
              FormatNumber(o.speed).c_str(), units, TravelSpeedNote(o, units).c_str(),
              FormatNumber(o.accel).c_str(), units, o.pen_delay_ms);
}

}  // namespace

std::uint32_t DryRunTickHz(const StreamOptions& o) {
  if (o.tick_hz != 0) return o.tick_hz;
  if (o.device.rfind("gpio:", 0) == 0) return 10000;
  return sim::PlotterOptions{}.tick_hz;
}

int RunDryRun(const StreamOptions& o, const StreamJob& job) {
  const std::uint32_t tick_hz = DryRunTickHz(o);
  const sim::PlotterOptions plotter_options = PlotterOptionsFor(o, tick_hz);
  CheckSpeedAgainstTicks(job, tick_hz, o);
  sim::SimulatedPlotter plotter(plotter_options);
  PlotterRun how;
  how.pause_between_layers = false;
  const sim::RunResult run = StreamToPlotter(o, job, &plotter, how);
  if (!run.finished) throw DeviceError("sim device: " + DecodeDeviceError(run.error));
  const std::vector<sim::DrawnPath> drawn = plotter.DrawnPaths();
  WriteDrawing(o, job, plotter, drawn);
  PrintDryRun(o, job, tick_hz, MeasureDryRun(job, plotter, drawn));
  return 0;
}

MachineSchedule ScheduleJob(const StreamOptions& o, const StreamJob& job, std::uint32_t tick_hz) {
  sim::SimulatedPlotter plotter(PlotterOptionsFor(o, tick_hz));
  MachineSchedule schedule;
  schedule.tick_hz = plotter.options().tick_hz;
  PlotterRun how;
  how.show_progress = false;
  how.pause_between_layers = false;
  how.schedule = &schedule;
  if (!StreamToPlotter(o, job, &plotter, how).finished) return {};
  return schedule;
}

}  // namespace fdsurf::host
