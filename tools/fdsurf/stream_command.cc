// SPDX-License-Identifier: MIT
#include "stream_command.h"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli_options.h"
#include "fdsurf/device/device.h"
#include "fdsurf/hal/gpiod_outputs.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/hal/usb_transport.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/link.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/writers.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/sim/checks.h"
#include "fdsurf/sim/plotter.h"

namespace fdsurf::host {
namespace {

// Status queries four times a second: enough for the progress line and for
// noticing the end, few enough to leave the link to the commands.
HostLinkOptions LinkOptions() {
  HostLinkOptions options;
  options.status_interval_us = 250'000;
  return options;
}

// A device-side failure or a link that could not be recovered.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The progress line: frames, patches, percent, rate.
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled) : enabled_(enabled), start_(Clock::now()) {}
  ~ProgressLine() { Finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// Redraws at most 10 times a second (and always when `force`).
  void Show(std::uint64_t executed, std::uint64_t total, std::uint64_t frames,
            double machine_seconds, bool force = false) {
    if (!enabled_) return;
    const auto now = Clock::now();
    if (!force && shown_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double wall = std::chrono::duration<double>(now - start_).count();
    const int percent = total == 0 ? 100 : static_cast<int>(executed * 100 / total);
    constexpr int kWidth = 24;
    std::string bar(kWidth, '.');
    for (int i = 0; i < percent * kWidth / 100; ++i) bar[static_cast<std::size_t>(i)] = '#';
    // The simulator reports its machine time: show how much faster than
    // real time it runs; a real device runs in real time, so show the rate.
    char rate[64];
    if (machine_seconds > 0) {
      std::snprintf(rate, sizeof rate, "%.1f s machine time, %.0fx real time", machine_seconds,
                    wall > 0 ? machine_seconds / wall : 0.0);
    } else {
      std::snprintf(rate, sizeof rate, "%.2f commands/s",
                    wall > 0 ? static_cast<double>(executed) / wall : 0.0);
    }
    std::fprintf(
        stderr, "\rfdsurf: [%s] %3d%%  %llu/%llu commands executed, %llu frames sent, %s   ",
        bar.c_str(), percent, static_cast<unsigned long long>(executed),
        static_cast<unsigned long long>(total), static_cast<unsigned long long>(frames), rate);
    shown_ = true;
  }
  void Finish() {
    if (shown_) std::fputc('\n', stderr);
    shown_ = false;
  }

 private:
  using Clock = std::chrono::steady_clock;
  bool enabled_;
  bool shown_ = false;
  Clock::time_point start_;
  Clock::time_point last_;
};

ToolpathOptions DrawingOptions(const StreamOptions& o) {
  ToolpathOptions t;
  t.tolerance = o.tolerance.empty() ? (o.units == "in" ? 0.002 : 0.05)
                                    : ParsePositive(o.tolerance, "--tolerance");
  const auto lines = ParseLines(o.lines);
  t.lines_s = lines[0];
  t.lines_t = lines[1];
  t.view = ParseView(o.view);
  if (!o.fit.empty() && o.fit != "none") {
    const auto page = ParsePage(o.fit);
    t.fit = std::array<double, 2>{page[0], page[1]};
  }
  t.margin =
      o.margin.empty() ? (o.units == "in" ? 0.2 : 5.0) : ParsePositive(o.margin, "--margin", true);
  t.dims = o.dims;
  t.mode = StepMode::kStepExact;
  return t;
}

MachineOptions Machine(const StreamOptions& o) {
  MachineOptions m;
  m.step =
      Quantum::Parse(o.step.empty() ? (o.units == "in" ? "0.0005" : "0.0125") : o.step, "--step");
  if (!o.travel.empty()) {
    const std::size_t x1 = o.travel.find('x');
    const std::size_t x2 = x1 == std::string::npos ? x1 : o.travel.find('x', x1 + 1);
    if (x1 == std::string::npos) {
      throw InputError("--travel: '" + o.travel + "' is not WxH or WxHxD (like 300x200)");
    }
    m.travel[0] = ParsePositive(o.travel.substr(0, x1), "--travel width");
    m.travel[1] = ParsePositive(o.travel.substr(x1 + 1, x2 == std::string::npos ? x2 : x2 - x1 - 1),
                                "--travel height");
    if (x2 != std::string::npos)
      m.travel[2] = ParsePositive(o.travel.substr(x2 + 1), "--travel depth");
  }
  if (!(o.speed > 0) || !(o.accel > 0)) throw InputError("--speed and --accel must be above 0");
  m.speed = o.speed;
  m.accel = o.accel;
  m.pen_delay_ms = o.pen_delay_ms;
  return m;
}

// The drawn paths as a toolpath on the job's page, for the writers. A point
// between two unit moves in the same direction lies on the line through its
// neighbours: leaving it out draws exactly the same path with far fewer
// points (the teapot's SVG: 14.8 MB instead of 26; it stays the exact step path).
Toolpath DrawnToolpath(const StreamJob& job, const std::vector<sim::DrawnPath>& paths) {
  Toolpath drawn = job.page;
  drawn.strokes.clear();
  for (const sim::DrawnPath& path : paths) {
    Stroke stroke;
    const auto& p = path.points;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const bool straight_through = k > 0 && k + 1 < p.size() &&
                                    p[k][0] - p[k - 1][0] == p[k + 1][0] - p[k][0] &&
                                    p[k][1] - p[k - 1][1] == p[k + 1][1] - p[k][1] &&
                                    p[k][2] - p[k - 1][2] == p[k + 1][2] - p[k][2];
      if (!straight_through) stroke.points.push_back(p[k]);
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

void Enqueue(const StreamJob& job, HostLink* link) {
  for (std::size_t k = 0; k < job.commands.size(); ++k) {
    const protocol::DecodeResult result = link->Enqueue(job.commands[k], job.labels[k]);
    if (!result.ok()) {
      throw EngineError(job.labels[k] + ": cannot be sent: " + protocol::ErrorName(result.code) +
                        " (field " + std::to_string(result.field) + ", docs/protocol.md)");
    }
  }
}

std::size_t CommandBytes(const StreamJob& job) {
  std::size_t bytes = 0;
  std::vector<std::uint8_t> frame(protocol::kMaxEncodedFrameBytes);
  for (const protocol::Command& command : job.commands) {
    bytes += protocol::EncodeCommand(command, frame.data(), frame.size());
  }
  return bytes;
}

// A device moves at most one step per axis per tick.
void CheckSpeedAgainstTicks(const StreamJob& job, std::uint32_t tick_hz, const StreamOptions& o) {
  if (job.config.max_rate > tick_hz) {
    throw InputError("--speed " + std::to_string(static_cast<int>(o.speed)) + " " + o.units +
                     "/s is " + std::to_string(job.config.max_rate) +
                     " steps/s, more than the device's " + std::to_string(tick_hz) +
                     " ticks/s (one step per tick at most): lower --speed or raise --tick-hz");
  }
}

int RunSimulated(const StreamOptions& o, const PatchSet& set, const StreamJob& job,
                 const ToolpathOptions& drawing, const std::string& units) {
  sim::PlotterOptions plotter_options;
  plotter_options.axes = o.dims;
  if (o.tick_hz != 0) plotter_options.tick_hz = o.tick_hz;
  CheckSpeedAgainstTicks(job, plotter_options.tick_hz, o);
  plotter_options.bytes_per_second = o.link_bytes_per_second;
  plotter_options.to_device = sim::FaultRates::All(o.faults);
  plotter_options.to_host = sim::FaultRates::All(o.faults);
  plotter_options.fault_seed = o.seed;
  sim::SimulatedPlotter plotter(plotter_options);
  HostLink link(LinkOptions());
  Enqueue(job, &link);

  ProgressLine progress(ShowProgress(o.quiet));
  constexpr std::uint64_t kTimeLimitUs = 24ull * 3600 * 1'000'000;  // a day of machine time
  const sim::RunResult run = plotter.Run(
      link, kTimeLimitUs,
      [&](const sim::RunProgress& p) {
        progress.Show(p.executed, p.total, p.frames_sent, p.time_us * 1e-6);
      },
      250'000);
  progress.Show(run.executed, job.commands.size(), run.host.frames_sent, run.time_us * 1e-6, true);
  progress.Finish();
  if (!run.finished) throw DeviceError("sim device: " + run.error);

  const std::vector<sim::DrawnPath> drawn = plotter.DrawnPaths();
  std::vector<sim::ReferenceLine> reference;
  for (auto& line : ReferenceLines(set, job))
    reference.push_back(sim::ReferenceLine{std::move(line)});
  const sim::DrawingComparison comparison = sim::CompareDrawing(drawn, reference, o.dims);
  sim::MotionLimitsSi limits;
  limits.tick_hz = plotter_options.tick_hz;
  limits.max_rate = job.config.max_rate;
  limits.accel = job.config.accel;
  limits.pen_delay_s = job.config.pen_delay_ms * 1e-3;
  const sim::MotionReport motion =
      sim::CheckMotion(plotter.step_events(), plotter.pen_events(), limits);

  // Outputs: every one complete before any is renamed into place.
  const Toolpath drawn_path = DrawnToolpath(job, drawn);
  StagedOutputs outputs;
  if (!o.svg.empty()) {
    WriteFile(outputs.Stage(o.svg),
              WriteSvg(drawn_path, o.file + " drawn by the simulated plotter"));
  }
  if (!o.png.empty()) RenderPng(drawn_path, o.png_width, outputs.Stage(o.png));
  outputs.Commit();

  const double step = job.page.quantum.value();
  // The deviation bound: the tolerance, plus what the reference polyline
  // itself may be off the exact curve (0.005 steps).
  const double bound = job.tolerance_steps + 0.005;
  const bool within = comparison.max_deviation <= bound && comparison.max_gap <= bound;
  const bool limits_kept = motion.violations == 0;
  if (!o.quiet) {
    std::size_t points = 0;
    for (const sim::DrawnPath& p : drawn) points += p.points.size();
    const std::size_t command_bytes = CommandBytes(job);
    const std::size_t gcode_bytes = GcodeBytes(set, drawing, units);
    const std::string what =
        std::to_string(job.patches.size()) + " patches" +
        (job.curves.empty() ? std::string()
                            : " and " + std::to_string(job.curves.size()) + " curves");
    std::fprintf(
        stderr,
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
    std::fprintf(stderr,
                 "wire: %zu bytes of command frames vs %zu bytes of G-code for the same drawing at "
                 "the same tolerance (%.1fx smaller)\n",
                 command_bytes, gcode_bytes,
                 static_cast<double>(gcode_bytes) / static_cast<double>(command_bytes));
    std::fprintf(stderr,
                 "machine: %.1f s, %zu moves, %.0f %s of path (%zu pen-down strokes, %zu points), "
                 "top speed %.1f %s/s\n",
                 motion.duration_s, motion.moves, motion.path_length * step, units.c_str(),
                 drawn.size(), points, motion.max_speed * step, units.c_str());
    std::fprintf(stderr,
                 "drawing vs exact curves: max deviation %.3f steps (%.4f %s), max gap %.3f steps; "
                 "bound %.3f steps (--tolerance): %s\n",
                 comparison.max_deviation, comparison.max_deviation * step, units.c_str(),
                 comparison.max_gap, bound, within ? "within" : "BOUND VIOLATED");
    std::fprintf(stderr, "motion limits (%.0f %s/s, %.0f %s/s², pen delay %d ms): %s\n", o.speed,
                 units.c_str(), o.accel, units.c_str(), o.pen_delay_ms,
                 limits_kept ? "kept"
                             : (std::to_string(motion.violations) +
                                " violations, first: " + motion.first_violation)
                                   .c_str());
    if (!o.svg.empty()) std::fprintf(stderr, "wrote %s (svg)\n", o.svg.c_str());
    if (!o.png.empty())
      std::fprintf(stderr, "wrote %s (png, %d px wide)\n", o.png.c_str(), o.png_width);
  }
  return within && limits_kept ? 0 : 1;
}

// A real-time loop against a USB controller: the host link over bulk
// transfers, reconnecting and resuming after an unplug.
int RunUsb(const StreamOptions& o, const StreamJob& job) {
  hal::UsbSelector selector;
  std::string error;
  if (!hal::ParseUsbDevice(o.device, &selector, &error)) throw InputError("--device: " + error);
  std::unique_ptr<hal::UsbTransport> usb;
  if (hal::UsbTransport::Open(selector, hal::UsbOptions{}, &usb, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  HostLink link(LinkOptions());
  Enqueue(job, &link);
  ProgressLine progress(ShowProgress(o.quiet));
  std::vector<std::uint8_t> out;
  std::uint8_t in[512];
  std::uint64_t last_progress = 0;
  while (!link.Finished() && !link.Failed()) {
    const std::uint64_t now = hal::MonotonicClock::Now();
    std::size_t got = 0;
    hal::IoStatus status = usb->Read(in, sizeof in, &got, 2);
    if (status == hal::IoStatus::kOk) link.OnBytes(in, got, now);
    out.clear();
    link.Poll(now, &out);
    if (status != hal::IoStatus::kDisconnected && !out.empty()) {
      status = usb->Write(out.data(), out.size(), 1000);
    }
    if (status == hal::IoStatus::kDisconnected) {
      if (!o.quiet)
        std::fprintf(stderr, "\nfdsurf: %s; waiting for it to come back\n", usb->LastError());
      if (usb->Reconnect(30'000) != hal::IoStatus::kOk) {
        throw DeviceError(std::string(usb->LastError()) + "; gave up after 30 s");
      }
      link.Resume();
    } else if (status != hal::IoStatus::kOk && status != hal::IoStatus::kTimeout) {
      throw DeviceError(usb->LastError());
    }
    if (now - last_progress > 250'000) {
      last_progress = now;
      progress.Show(link.status() ? link.status()->executed : 0, job.commands.size(),
                    link.stats().frames_sent, 0);
    }
  }
  progress.Finish();
  if (link.Failed()) throw DeviceError(selector.ToString() + ": " + link.error());
  if (!o.quiet) {
    std::fprintf(stderr, "%s: %zu patches drawn by usb %s; %llu frames sent (%llu resent)\n",
                 o.file.c_str(), job.patches.size(), selector.ToString().c_str(),
                 static_cast<unsigned long long>(link.stats().frames_sent),
                 static_cast<unsigned long long>(link.stats().retransmitted));
  }
  return 0;
}

// This host is the controller: the firmware's Device runs here, in real time,
// on GPIO lines. Ticks can only come late (never early), so speeds and
// accelerations can only come out below the configured limits.
int RunGpio(const StreamOptions& o, const StreamJob& job) {
  hal::GpiodConfig config;
  std::string error;
  if (!hal::ParseGpioDevice(o.device, &config, &error)) throw InputError("--device: " + error);
  if (config.axes != o.dims) {
    throw InputError("--device: " + std::to_string(config.axes) +
                     " axes of lines given for --dims " + std::to_string(o.dims));
  }
  const std::uint32_t tick_hz = o.tick_hz != 0 ? o.tick_hz : 10000;
  CheckSpeedAgainstTicks(job, tick_hz, o);
  std::unique_ptr<hal::GpiodOutputs> outputs;
  if (hal::GpiodOutputs::Open(config, &outputs, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  HostLink link(LinkOptions());
  Enqueue(job, &link);
  ProgressLine progress(ShowProgress(o.quiet));
  hal::MonotonicClock clock;
  const auto run = [&](auto& device) {
    std::vector<std::uint8_t> out;
    std::uint8_t in[256];
    const std::uint64_t tick_us = 1'000'000 / tick_hz;
    std::uint64_t next_tick = clock.NowMicros();
    std::uint64_t last_progress = 0;
    std::uint64_t ticks = 0;
    while (!link.Finished() && !link.Failed()) {
      if (ticks++ % 16 == 0) {
        const std::uint64_t now = clock.NowMicros();
        out.clear();
        link.Poll(now, &out);
        for (const std::uint8_t byte : out) device.OnByte(byte);
        for (std::size_t n; (n = device.ReadOutput(in, sizeof in)) > 0;) link.OnBytes(in, n, now);
        device.Fill();
        if (now - last_progress > 250'000) {
          last_progress = now;
          progress.Show(device.executed(), job.commands.size(), link.stats().frames_sent, 0);
        }
      }
      next_tick += tick_us;
      clock.SleepUntilMicros(next_tick);
      if (device.Tick(*outputs, *outputs) != hal::IoStatus::kOk) {
        throw DeviceError(std::string("gpio: ") + outputs->StepDirOutputs::LastError());
      }
    }
  };
  if (o.dims == 3) {
    auto device = std::make_unique<device::Device<3>>(tick_hz);
    run(*device);
  } else {
    auto device = std::make_unique<device::Device<2>>(tick_hz);
    run(*device);
  }
  progress.Finish();
  if (link.Failed()) throw DeviceError("gpio device: " + link.error());
  if (!o.quiet) {
    std::fprintf(stderr, "%s: %zu patches drawn on %s at %u Hz ticks\n", o.file.c_str(),
                 job.patches.size(), o.device.c_str(), tick_hz);
  }
  return 0;
}

}  // namespace

void AddStreamOptions(CLI::App* command, StreamOptions* o) {
  command->add_option("FILE", o->file, "patch file (.bpt or .json, see docs/formats.md)")
      ->required();
  command
      ->add_option("--device", o->device,
                   "sim (the simulated plotter), usb[:VID:PID|:BUS-PORT.PORT] or "
                   "gpio:CHIP:STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN")
      ->capture_default_str();
  command
      ->add_option("--lines", o->lines, "isolines per patch: U (UxU) or UxV, 0 leaves a family out")
      ->capture_default_str();
  command->add_option("--view", o->view, "top, front, side, iso or AZ,EL (degrees)")
      ->capture_default_str();
  command->add_option("--units", o->units, "units of the drawing and of these options")
      ->check(CLI::IsMember({"mm", "in"}))
      ->capture_default_str();
  command->add_option("--fit", o->fit, "scale the drawing to fit a WxH page (none: file units)")
      ->capture_default_str();
  command->add_option("--margin", o->margin, "space around the drawing (default 5 mm / 0.2 in)");
  command->add_option("--tolerance", o->tolerance,
                      "largest distance of the drawing from the exact curves (default 0.05 mm / "
                      "0.002 in)");
  command->add_option("--dims", o->dims, "2 (pen plotter) or 3 (with Z, for CNC)")
      ->check(CLI::IsMember({2, 3}))
      ->capture_default_str();
  command->add_option("--step", o->step,
                      "length of one motor step (default 0.0125 mm / 0.0005 in)");
  command->add_option("--travel", o->travel, "machine travel WxH[xD] (default: the page)");
  command->add_option("--speed", o->speed, "path speed limit, units per second")
      ->capture_default_str();
  command->add_option("--accel", o->accel, "path acceleration limit, units per second²")
      ->capture_default_str();
  command->add_option("--pen-delay", o->pen_delay_ms, "rest after each pen change, milliseconds")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  command->add_option("--tick-hz", o->tick_hz,
                      "the device's step timer (sim: 40000 by default, must divide 1000000; "
                      "gpio: 10000)");
  command
      ->add_option("--link-rate", o->link_bytes_per_second,
                   "sim: bytes per second each way on the link (1000000 ~ USB full speed)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--faults", o->faults,
                   "sim: drop, corrupt, duplicate, reorder and truncate each frame with this "
                   "probability (0..0.5)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  command->add_option("--seed", o->seed, "sim: seed of the fault injection")->capture_default_str();
  command->add_option("--svg", o->svg, "sim: write what the plotter drew as SVG");
  command->add_option("--png", o->png, "sim: draw what the plotter drew as a PNG picture");
  command->add_option("--size", o->png_width, "PNG width in pixels")
      ->check(CLI::Range(16, 20000))
      ->capture_default_str();
  command->add_flag("-q,--quiet", o->quiet, "no summary or progress on stderr");
}

int RunStream(const StreamOptions& o) {
  const bool sim = o.device == "sim";
  const bool usb = o.device == "usb" || o.device.rfind("usb:", 0) == 0;
  const bool gpio = o.device.rfind("gpio:", 0) == 0;
  if (!sim && !usb && !gpio) {
    throw InputError("--device: '" + o.device +
                     "' is not sim, usb[:VID:PID|:BUS-PORT] or gpio:CHIP:LINES");
  }
  if (!sim && (!o.svg.empty() || !o.png.empty() || o.faults > 0)) {
    throw InputError("--svg, --png and --faults are for --device sim");
  }
  if (sim && o.tick_hz != 0 && 1'000'000 % o.tick_hz != 0) {
    throw InputError("--tick-hz: " + std::to_string(o.tick_hz) + " does not divide 1000000");
  }
  const ToolpathOptions drawing = DrawingOptions(o);
  const MachineOptions machine = Machine(o);
  const PatchSet set = ReadPatchFile(o.file);
  const std::string file_units = set.units.empty() ? "mm" : set.units;
  ToolpathOptions scaled = drawing;
  scaled.units_scale = file_units == o.units ? 1.0 : (file_units == "in" ? 25.4 : 1 / 25.4);
  const StreamJob job = BuildStreamJob(set, scaled, machine, o.units);
  try {
    if (sim) return RunSimulated(o, set, job, scaled, o.units);
    if (usb) return RunUsb(o, job);
    return RunGpio(o, job);
  } catch (const DeviceError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 3;
  }
}

}  // namespace fdsurf::host
