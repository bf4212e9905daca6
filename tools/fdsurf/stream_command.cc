// SPDX-License-Identifier: MIT
#include "stream_command.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_options.h"
#include "fdsurf/host/hidden_lines.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/text.h"
#include "runners/journal.h"
#include "runners/machine_schedule.h"
#include "runners/runner.h"
#include "runners/serial_session.h"
#include "serve/gpio_server.h"

namespace fdsurf::host {
namespace {

// The flags of one axis's acceleration limit, x, y, z.
constexpr const char* kAxisAccelFlags[3] = {"--accel-x", "--accel-y", "--accel-z"};

ToolpathOptions DrawingOptions(const StreamOptions& o) {
  ToolpathOptions t;
  t.tolerance = o.tolerance.empty() ? DefaultIn(ToolpathOptions{}.tolerance, o.units)
                                    : ParsePositive(o.tolerance, "--tolerance");
  const auto lines = ParseLines(o.lines);
  t.lines_s = lines[0];
  t.lines_t = lines[1];
  t.view = ParseView(o.view.empty() ? "iso" : o.view);
  // Checked before the file is read; PlacePage sets the page after.
  if (!o.fit.empty()) (void)ParsePage(o.fit, o.units);
  if (!o.origin.empty()) (void)ParseOrigin(o.origin);
  t.margin = o.margin.empty() ? DefaultIn(kDefaultMarginMm, o.units)
                              : ParsePositive(o.margin, "--margin", true);
  t.dims = o.dims;
  t.mode = StepMode::kStepExact;
  return t;
}

// --step S (every axis) or SX,SY[,SZ] (each axis its own; an axis left
// out takes X's).
void SetSteps(const std::string& text, MachineOptions* m) {
  std::vector<std::string> items;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) items.push_back(item);
  if (items.empty() || items.size() > 3 || text.back() == ',') {
    throw InputError("--step: '" + text + "' is not S or SX,SY[,SZ]");
  }
  static const char* const kWhat[3] = {"--step (X)", "--step (Y)", "--step (Z)"};
  m->step = Quantum::Parse(items[0], items.size() == 1 ? "--step" : kWhat[0]);
  for (std::size_t a = 1; a < items.size(); ++a) {
    const Quantum own = Quantum::Parse(items[a], kWhat[a]);
    if (own.value() != m->step.value()) m->own_step[a] = own;
  }
}

MachineOptions Machine(const StreamOptions& o) {
  MachineOptions m;  // the defaults, in mm, mm/s and mm/s²
  if (o.step.empty()) {
    m.step = DefaultStepIn(m.step, o.units);
  } else {
    SetSteps(o.step, &m);
  }
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
  m.speed = o.speed_limit ? *o.speed_limit : DefaultIn(m.speed, o.units);
  m.accel = o.accel_limit ? *o.accel_limit : DefaultIn(m.accel, o.units);
  if (!(m.speed > 0) || !(m.accel > 0)) throw InputError("--speed and --accel must be above 0");
  m.travel_speed = o.travel_speed_limit ? *o.travel_speed_limit : m.speed;
  for (std::size_t a = 0; a < 3; ++a) {
    const std::optional<double>& own = o.axis_accel_each[a];
    m.axis_accel[a] = own ? *own : o.axis_accel_limit ? *o.axis_accel_limit : 2 * m.accel;
    if (!(m.axis_accel[a] > 0)) {
      throw InputError(std::string(own ? kAxisAccelFlags[a] : "--axis-accel") + " must be above 0");
    }
  }
  if (!(m.travel_speed > 0)) throw InputError("--travel-speed must be above 0");
  m.pen_delay_ms = o.pen_delay_ms;
  m.servo_up_us = o.servo_pulse_up_us;
  m.servo_down_us = o.servo_pulse_down_us;
  m.homing_required = o.require_homing;
  if (!o.machine_origin.empty()) m.origin = *ParseMachineOrigin(o.machine_origin);
  return m;
}

// A drawing kept at its own coordinates must lie inside the machine's
// travel, which starts at 0: say so with the extent, before the device's
// own check would name the first command that leaves it.
void RefuseOutsideTravel(const Toolpath& page, const MachineOptions& machine, PageOrigin origin) {
  if (origin != PageOrigin::kKeep) return;
  const double slack = machine.step.value() / 2;
  const std::array<double, 2> travel{machine.travel[0] > 0 ? machine.travel[0] : page.width,
                                     machine.travel[1] > 0 ? machine.travel[1] : page.height};
  bool inside = true;
  for (int c = 0; c < 2; ++c) {
    inside = inside && page.drawing_lo[c] >= -slack && page.drawing_hi[c] <= travel[c] + slack;
  }
  if (inside) return;
  throw InputError("--origin keep: the drawing runs over x " + FormatNumber(page.drawing_lo[0]) +
                   ".." + FormatNumber(page.drawing_hi[0]) + ", y " +
                   FormatNumber(page.drawing_lo[1]) + ".." + FormatNumber(page.drawing_hi[1]) +
                   " " + page.units + ", outside the machine's travel x 0.." +
                   FormatNumber(travel[0]) + ", y 0.." + FormatNumber(travel[1]) +
                   "; use --origin min or center to place it on the page");
}

enum class DeviceKind { kSim, kUsb, kSerial, kGpio, kUnknown };

DeviceKind DeviceKindOf(const std::string& device) {
  if (device == "sim") return DeviceKind::kSim;
  if (device == "usb" || device.rfind("usb:", 0) == 0) return DeviceKind::kUsb;
  if (device.rfind("serial:", 0) == 0) return DeviceKind::kSerial;
  if (device.rfind("gpio:", 0) == 0) return DeviceKind::kGpio;
  return DeviceKind::kUnknown;
}

// A real device's progress line shows machine time elapsed and left from
// the job's schedule: a quiet run on the simulated plotter first (the
// teapot's takes about a second, docs/protocol.md), only when the progress
// line shows. The device's own tick rate is known only after HELLO: the
// schedule assumes DryRunTickHz.
StreamOptions WithSchedule(const StreamOptions& o, const StreamJob& job) {
  StreamOptions real = o;
  const std::uint32_t tick_hz = DryRunTickHz(o);
  if (!ShowProgress(o.quiet) || 1'000'000 % tick_hz != 0) return real;
  MachineSchedule schedule = ScheduleJob(o, job, tick_hz);
  if (!schedule.executed_s.empty()) {
    real.schedule = std::make_shared<const MachineSchedule>(std::move(schedule));
  }
  return real;
}

// Builds the job of `set` and streams it to the device o.device names (or,
// with --dry-run, to the simulated plotter only).
int StreamJobTo(const StreamOptions& o, const PatchSet& set, const ToolpathOptions& drawing,
                const MachineOptions& machine) {
  StreamJob job = BuildStreamJob(set, drawing, machine, o.units, *ParseStreamPlan(o.plan));
  if (o.prepare_on_host) PrepareOnHost(&job);
  try {
    if (o.dry_run) return RunDryRun(o, job);
    const DeviceKind kind = DeviceKindOf(o.device);
    if (kind == DeviceKind::kSim) return RunSimulated(o, set, job, drawing, o.units);
    StreamOptions real = WithSchedule(o, job);
    if (!o.resume.empty()) {
      auto state = std::make_shared<JournalState>(ReadJournal(o.resume));
      CheckJournalMatches(o.resume, *state, job);
      real.resume_state = std::move(state);
    }
    switch (kind) {
      case DeviceKind::kUsb:
        return RunUsb(real, job);
      case DeviceKind::kSerial:
        return RunSerial(real, job);
      default:
        return RunGpio(real, job);
    }
  } catch (const DeviceError& e) {
    const std::string message = e.what();
    const bool not_homed = message.find("not homed") != std::string::npos;
    std::fprintf(stderr, "fdsurf: error: %s%s\n", message.c_str(),
                 not_homed ? " (the machine requires homing: run `fdsurf machine home` with the "
                             "same --machine/--device first)"
                           : "");
    return 3;
  }
}

// --step, --travel, --speed, --travel-speed and --accel: in --units, the defaults
// MachineOptions' mm values converted (Machine).
void AddMachineOptions(CLI::App* command, StreamOptions* o) {
  const MachineOptions mm;  // the defaults, in mm, mm/s and mm/s²
  command->add_option("--step", o->step,
                      "length of one motor step, in --units, S or one per axis SX,SY[,SZ] "
                      "(default " +
                          mm.step.Format(1) + " mm; for --units in " +
                          DefaultStepIn(mm.step, "in").Format(1) +
                          " in, the nearest with 9 decimals)");
  command->add_option("--travel", o->travel,
                      "machine travel WxH[xD] in --units (default: the page)");
  command->add_option("--speed", o->speed_limit,
                      "path speed limit, --units per second " + DefaultInMmHelp(mm.speed, "mm/s"));
  command->add_option("--travel-speed", o->travel_speed_limit,
                      "path speed limit with the pen up, --units per second (default: --speed)");
  command->add_option(
      "--accel", o->accel_limit,
      "path acceleration limit, --units per second² " + DefaultInMmHelp(mm.accel, "mm/s²"));
  command->add_option("--axis-accel", o->axis_accel_limit,
                      "each axis's acceleration limit, turning included, --units per second²; "
                      "above --accel (default: twice --accel)");
  for (std::size_t a = 0; a < 3; ++a) {
    command->add_option(kAxisAccelFlags[a], o->axis_accel_each[a],
                        std::string("the ") + "XYZ"[a] +
                            " axis's acceleration limit, --units per second² (default: "
                            "--axis-accel); the device keeps every axis within the smallest");
  }
  command
      ->add_option("--machine-origin", o->machine_origin,
                   "the page's corner at the machine's position 0: bottom-left (default; X right, "
                   "Y up), top-left (an AxiDraw: Y toward you), bottom-right, top-right")
      ->check(CLI::IsMember({"bottom-left", "top-left", "bottom-right", "top-right"}));
  command->add_flag("--require-homing", o->require_homing,
                    "the device refuses to move until homed: run `fdsurf machine home` first");
}

// --journal and --resume (runners/journal.h).
void AddJournalOptions(CLI::App* command, StreamOptions* o) {
  command->add_option("--journal", o->journal,
                      "usb, serial: record in this file which commands the device has executed, "
                      "for --resume (docs/protocol.md, job journal)");
  command->add_option("--resume", o->resume,
                      "usb, serial: continue the job this journal records, with the same "
                      "arguments, from the first command not executed (nothing drawn twice)");
}

}  // namespace

MachineOptions StreamMachine(const StreamOptions& o) { return Machine(o); }

// The options that only the simulated plotter (--device sim) uses: its link,
// its fault injection, its cost model and what it writes.
void AddSimulatorOptions(CLI::App* command, StreamOptions* o) {
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
  command
      ->add_option("--sim-cost", o->sim_cost,
                   "sim: charge the device's validation time as on this MCU (none, atmega2560)")
      ->check(CLI::IsMember({"none", "atmega2560"}))
      ->capture_default_str();
  command->add_flag("--sim-64bit-tables", o->sim_64bit_tables,
                    "sim: send the job as to a device of 64-bit tables only (the Arduino Uno): "
                    "in pieces, the prepared lines it could not hold (with --prepare-on-host)");
  command->add_option("--svg", o->svg, "sim: write what the plotter drew as SVG");
  command->add_option("--png", o->png, "sim: draw what the plotter drew as a PNG picture");
  command->add_option("--waveform", o->waveform,
                      "sim: write the plotter's step/dir/enable/pen pins (docs/boards.md)");
  command->add_option("--size", o->png_width, "PNG width in pixels")
      ->check(CLI::Range(16, 20000))
      ->capture_default_str();
}

void AddStreamOptions(CLI::App* command, StreamOptions* o) {
  AddInputOptions(command, &o->file, &o->input_format, &o->reader);
  command
      ->add_option("--device", o->device,
                   "sim (the simulated plotter), usb[:VID:PID|:BUS-PORT.PORT], "
                   "serial:PATH[:BAUD] (e.g. serial:/dev/ttyACM0:115200), serial:auto or "
                   "gpio:CHIP:STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN[:xmin=!N,ymin=!N,...]")
      ->capture_default_str();
  command
      ->add_option("--lines", o->lines, "isolines per patch: U (UxU) or UxV, 0 leaves a family out")
      ->capture_default_str();
  command->add_option("--view", o->view,
                      "top, front, side, iso or AZ,EL (degrees); default iso, top for a flat "
                      "drawing (SVG)");
  command->add_option("--layer", o->layer, "draw only this layer: its name or number (1, 2, ...)");
  command->add_option("--units", o->units, "units of the drawing and of these options")
      ->check(CLI::IsMember({"mm", "in"}))
      ->capture_default_str();
  AddPageOptions(command, &o->fit, &o->origin, &o->margin);
  command->add_option("--tolerance", o->tolerance,
                      "largest distance of the drawing from the exact curves, in --units " +
                          DefaultInMmHelp(ToolpathOptions{}.tolerance, "mm"));
  command->add_option("--dims", o->dims, "2 (pen plotter) or 3 (with Z, for CNC)")
      ->check(CLI::IsMember({2, 3}))
      ->capture_default_str();
  AddMachineOptions(command, o);
  command->add_option("--pen-delay", o->pen_delay_ms, "rest after each pen change, milliseconds")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  command
      ->add_option("--servo-pulse-up", o->servo_pulse_up_us,
                   "servo pen lift: pulse width with the pen up, µs (500..2500; both 0: the pen "
                   "is a switch)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  command
      ->add_option("--servo-pulse-down", o->servo_pulse_down_us,
                   "servo pen lift: pulse width with the pen down, µs (500..2500)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  command->add_option("--tick-hz", o->tick_hz,
                      "the device's step timer (sim: 40000 by default, must divide 1000000; "
                      "gpio: 10000)");
  command
      ->add_option("--connect-timeout", o->connect_timeout_s,
                   "usb, serial: seconds to retry HELLO before giving up (a board reset by "
                   "opening its port is silent 1-2 s)")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  command
      ->add_option("--reconnect-timeout", o->reconnect_timeout_s,
                   "usb, serial: seconds a device that hung up may take to come back")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  AddSimulatorOptions(command, o);
  command
      ->add_option("--hidden", o->hidden,
                   "show (every line) or remove (only the visible pieces, streamed as curves)")
      ->check(CLI::IsMember({"show", "remove"}));
  command
      ->add_option("--plan", o->plan,
                   "lines: every line a curve, planned across patches as plot plans its strokes "
                   "(fewest pen lifts and least pen-up travel); patches: one PATCH per patch, "
                   "its lines in the device's order (fewest bytes on the wire)")
      ->check(CLI::IsMember({"lines", "patches"}))
      ->capture_default_str();
  command->add_flag("-q,--quiet", o->quiet, "no summary or progress on stderr");
  command->add_flag("--dry-run", o->dry_run,
                    "run the job through the simulated plotter with these limits and report "
                    "machine time, pen-down and pen-up distance, pen lifts and the page extent; "
                    "nothing is sent to --device");
  command->add_flag("--prepare-on-host", o->prepare_on_host,
                    "plan every line on the host and send it as a PREPARED_CURVE (for a device "
                    "without a planner of its own); the drawing is the same");
  AddJournalOptions(command, o);
  command->add_flag("--no-pause", o->no_pause,
                    "between layers, say that the pen is to be changed but do not wait for Enter");
}

int RunStream(const StreamOptions& options) {
  // Messages name standard input "<stdin>", as the reader does.
  StreamOptions o = options;
  if (o.file == "-") o.file = "<stdin>";
  // A running `fdsurf serve` holding these lines: through it, as a board.
  if (!o.dry_run) o.device = DeviceThroughServer(o.device, o.quiet);
  const bool sim = DeviceKindOf(o.device) == DeviceKind::kSim;
  if (DeviceKindOf(o.device) == DeviceKind::kUnknown) {
    throw InputError("--device: '" + o.device +
                     "' is not sim, usb[:VID:PID|:BUS-PORT], serial:PATH[:BAUD], serial:auto or "
                     "gpio:CHIP:LINES");
  }
  const bool drawing_out = !o.svg.empty() || !o.png.empty() || !o.waveform.empty();
  const DeviceKind device_kind = DeviceKindOf(o.device);
  if ((!o.journal.empty() || !o.resume.empty()) &&
      (o.dry_run || (device_kind != DeviceKind::kUsb && device_kind != DeviceKind::kSerial))) {
    throw InputError(
        "--journal and --resume are for --device usb and serial, whose device keeps its state "
        "when the tool stops (not sim, nor --dry-run; gpio through `fdsurf serve`)");
  }
  if (!sim && ((drawing_out && !o.dry_run) || o.faults > 0 || o.sim_cost != "none")) {
    throw InputError(
        "--svg, --png, --waveform, --faults and --sim-cost are for --device sim (--svg, --png "
        "and --waveform also for --dry-run)");
  }
  if (o.sim_64bit_tables && (!sim || !o.prepare_on_host)) {
    throw InputError("--sim-64bit-tables is for --device sim with --prepare-on-host");
  }
  if ((sim || o.dry_run) && o.tick_hz != 0 && 1'000'000 % o.tick_hz != 0) {
    throw InputError("--tick-hz: " + std::to_string(o.tick_hz) + " does not divide 1000000" +
                     (sim ? "" : " (--dry-run runs the simulated plotter)"));
  }
  ToolpathOptions drawing = DrawingOptions(o);
  const MachineOptions machine = Machine(o);
  o.speed = machine.speed;  // for the runners' summaries
  o.travel_speed = machine.travel_speed;
  o.accel = machine.accel;
  o.axis_accel = machine.axis_accel;
  const PatchSet set = ReadDrawing(options.file, o.input_format, o.reader, o.layer, o.quiet);
  if (o.view.empty() && IsFlatDrawing(set)) drawing.view = ParseView("top");
  const std::string file_units = set.units.empty() ? "mm" : set.units;
  ToolpathOptions scaled = drawing;
  scaled.units_scale = file_units == o.units ? 1.0 : MmPerUnit(file_units) / MmPerUnit(o.units);
  PlacePage(o.fit, o.origin, o.units, 1.0, set, &scaled);
  RefuseOutsideTravel(PlanPage(set, scaled, o.units), machine, scaled.origin);
  if (o.hidden == "remove") {
    // The visible pieces, as plot draws them, streamed as the file's curves
    // are; the sim checks the plotter against them.
    const VisibleCurves visible = VisibleCurvesOf(set, scaled, machine, o.units);
    if (!o.quiet) {
      std::fprintf(stderr, "%s; %zu pieces drawn twice left out\n",
                   DescribeHiddenLines(visible.report, visible.hidden, o.units).c_str(),
                   visible.plan.duplicates_removed);
    }
    return StreamJobTo(o, visible.set, visible.options, visible.machine);
  }
  return StreamJobTo(o, set, scaled, machine);
}

}  // namespace fdsurf::host
