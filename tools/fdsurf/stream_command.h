// SPDX-License-Identifier: MIT
// `fdsurf stream`: plans a drawing, streams it as patches to a device (the
// simulated plotter, a USB controller, or GPIO lines driven from this host)
// and reports what happened.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "cli_options.h"
#include "fdsurf/host/stream.h"

namespace CLI {
class App;
}

namespace fdsurf::host {

struct MachineSchedule;  // runners/machine_schedule.h
struct JournalState;     // runners/journal.h

struct StreamOptions {
  std::string file;
  std::string input_format;
  ReaderFlags reader;
  std::string device = "sim";
  // The drawing, as for `fdsurf plot`.
  std::string lines = "8";
  std::string view;   // empty: iso, or top for a flat drawing (IsFlatDrawing)
  std::string layer;  // --layer NAME|N, empty: all
  std::string units = "mm";
  /// --fit and --origin as typed, "" when left out (PlacePage's defaults).
  std::string fit;
  std::string origin;
  std::string margin;
  std::string tolerance;
  int dims = 2;
  // The machine.
  std::string step;
  std::string travel;
  /// Path speed (--units per second) and acceleration (per second²) limits
  /// as typed; nullopt when left out: MachineOptions' defaults, which are
  /// mm/s and mm/s², converted to --units.
  std::optional<double> speed_limit;
  /// --travel-speed, --units per second; unset: --speed.
  std::optional<double> travel_speed_limit;
  std::optional<double> accel_limit;
  /// --axis-accel, --units per second²; unset: twice the path's.
  std::optional<double> axis_accel_limit;
  /// --accel-x, --accel-y, --accel-z: one axis's limit, over --axis-accel.
  std::array<std::optional<double>, 3> axis_accel_each;
  /// The limits in effect, in --units: set by RunStream for the runners.
  double speed = 0;
  double travel_speed = 0;  ///< pen up; the runners' summaries name it when ≠ speed
  double accel = 0;
  std::array<double, 3> axis_accel{};  ///< each axis's limit (MachineOptions::axis_accel)
  int pen_delay_ms = 100;
  /// The servo pen lift's pulse widths, µs; both 0: a switch pen.
  int servo_pulse_up_us = 0;
  int servo_pulse_down_us = 0;
  /// --require-homing: CONFIG's homing-required flag (MachineOptions).
  bool require_homing = false;
  /// --machine-origin: the page corner at the machine's position 0
  /// (MachineOrigin, stream.h); "" for bottom-left.
  std::string machine_origin;
  std::uint32_t tick_hz = 0;
  // The link and the simulator.
  std::uint64_t link_bytes_per_second = 1'000'000;
  double faults = 0;
  /// usb, serial: how long HELLO is retried, and how long a device that
  /// hung up may take to come back, seconds.
  double connect_timeout_s = 10;
  double reconnect_timeout_s = 30;
  /// sim: what the device's validation costs in virtual time: "none" or
  /// "atmega2560" (16 MHz, the cycles measured under simavr).
  std::string sim_cost = "none";
  /// sim: the simulated device takes the job as a device that steps 64-bit
  /// tables only (HELLO's protocol::kFeature64BitTables, the Arduino Uno)
  /// is sent it: every prepared line it could not hold, in pieces
  /// (SplitForSixtyFourBitTables). The reference of such a board's
  /// end-to-end test (tests/boards/run_e2e.py).
  bool sim_64bit_tables = false;
  std::uint64_t seed = 1;
  std::string svg;
  std::string png;
  /// sim: the plotter's step/dir/enable/pen pins in the waveform format.
  std::string waveform;
  int png_width = 1600;
  bool quiet = false;
  /// --hidden: "show", or "remove": only the visible pieces of the lines,
  /// streamed as Bézier curves (VisibleCurvesOf, stream.h).
  std::string hidden = "show";
  /// --plan: "lines" (each line a curve, planned as plot plans strokes) or
  /// "patches" (one PATCH per patch); StreamPlan, fdsurf/host/stream.h.
  std::string plan = "lines";
  /// Do not wait for Enter between layers (the pen change); the runners
  /// also go on without waiting when stdin is not a terminal.
  bool no_pause = false;
  /// --dry-run: run the job through the simulated plotter with these limits
  /// and report machine time, distances, pen lifts and extent; whatever
  /// --device says, nothing is opened (RunDryRun, runners/runner.h).
  bool dry_run = false;
  /// --prepare-on-host: plan every line here and send PREPARED_CURVEs
  /// (PrepareOnHost, fdsurf/host/stream.h), for a device without a planner
  /// of its own; the drawing is the same.
  bool prepare_on_host = false;
  /// A real device's schedule in machine time for its progress line (set by
  /// RunStream when the progress line shows; nullptr otherwise).
  std::shared_ptr<const MachineSchedule> schedule;
  /// --journal FILE: record which commands the device executed (usb,
  /// serial). --resume FILE: continue the job that FILE journals; its state,
  /// read and checked against the job by RunStream.
  std::string journal;
  std::string resume;
  std::shared_ptr<const JournalState> resume_state;
};

/// Adds the options of `stream` to `command`.
void AddStreamOptions(CLI::App* command, StreamOptions* options);

/// Runs the command: 0 when the job finished within the bound and the
/// limits, 1 when the simulated plotter saw the bound or a limit broken,
/// 2 for bad input, 3 when the device refused the job or the link failed.
/// Throws InputError / OutputError / EngineError as the other commands do.
int RunStream(const StreamOptions& options);

/// The machine stream drives for `o` (--step, --travel, --speed, --accel,
/// --pen-delay in o.units); InputError for a bad value. `fdsurf machine`
/// uses it too.
MachineOptions StreamMachine(const StreamOptions& o);

}  // namespace fdsurf::host
