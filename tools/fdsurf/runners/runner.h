// SPDX-License-Identifier: MIT
// The device runners of `fdsurf stream`: each takes a planned job
// (stream.h) to one kind of device through the host end of the link
// (HostLink) and reports what happened.
//
//   sim   the simulated plotter (sim/): the firmware in virtual time, with
//         the drawing and the motion checked afterwards (sim_runner.cc)
//   usb   a controller on a vendor-specific bulk interface, through libusb
//         (usb_runner.cc)
//   gpio  this host is the controller: the firmware's Device runs here in
//         real time on GPIO lines, through libgpiod (gpio_runner.cc)
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>

#include "../stream_command.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/link.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/toolpath.h"
#include "machine_schedule.h"

namespace fdsurf::host {

/// A device-side failure or a link that could not be recovered (exit 3).
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A device error from the link with its "(detail N)" numbers in words
/// ("out of travel (detail 1)" becomes "out of travel (on Y)").
std::string DecodeDeviceError(const std::string& message);

/// The link's settings for every runner.
HostLinkOptions LinkOptions();

/// Queues every command of the job on the link; EngineError for a command
/// the codec refuses (naming its label and field).
void Enqueue(const StreamJob& job, HostLink* link);
/// The same for commands [from, to) only.
void Enqueue(const StreamJob& job, HostLink* link, std::size_t from, std::size_t to);

/// The command index at which the next layer after `from` begins (a
/// LayerStart other than the first), or the job's size when none does.
std::size_t NextLayerBoundary(const StreamJob& job, std::size_t from);

/// "layer 2/3 'red'" for the layer that command index `command` belongs
/// to; empty when the job has fewer than two layers (nothing to tell apart).
std::string LayerLabel(const StreamJob& job, std::size_t command);

/// What the job draws, for the runners' summaries: "4 patches", "12 curves
/// in 3 layers", "4 patches and 12 curves" (DescribeDrawing; "N commands"
/// when neither).
std::string JobContents(const StreamJob& job);

/// SIGINT and SIGTERM counted while it lives: the first is the runner's to
/// act on (STOP), the second too (HALT, Again()); a third exits the process
/// at once with 130, the terminal restored (PauseKeys). The previous
/// handlers come back on destruction. Without one, Ctrl-C ends the process
/// as usual.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  /// A signal arrived since construction.
  static bool Interrupted();
  /// A second one arrived: the emergency stop (HALT) is wanted.
  static bool Again();
};

/// The pause key on a terminal: while it lives and stdin is a terminal (and
/// `enabled`), stdin is in non-canonical mode without echo (Ctrl-C still
/// signals), so that one key press is read without Enter; the terminal's
/// settings come back on destruction, and on a third Ctrl-C's exit.
class PauseKeys {
 public:
  explicit PauseKeys(bool enabled);
  ~PauseKeys();
  PauseKeys(const PauseKeys&) = delete;
  PauseKeys& operator=(const PauseKeys&) = delete;
  /// Keys are read (stdin is a terminal and the mode was set).
  FDSURF_NODISCARD bool active() const { return active_; }
  /// Reads what was typed without waiting: true if it held space or 'p'.
  bool Pressed();

 private:
  bool active_ = false;
};

class ProgressLine;

/// Pause and resume by key for a runner whose device is behind `link`: each
/// press of space or 'p' sends PAUSE, the next RESUME (HostLink retransmits
/// them until acknowledged); says so on stderr (unless quiet) and in the
/// progress line.
class PauseToggle {
 public:
  PauseToggle(bool enabled, bool quiet, ProgressLine* progress);
  /// Reads the keys; on a press asks `link` to pause or to resume.
  void Poll(HostLink* link);
  FDSURF_NODISCARD bool paused() const { return paused_; }

 private:
  PauseKeys keys_;
  bool quiet_;
  ProgressLine* progress_;
  bool paused_ = false;
};

/// At a layer boundary (`command` = a LayerStart's command), once the device
/// has executed everything before it and rests with the pen up: prints
/// "fdsurf: layer 2/3 'NAME': change the pen, then press Enter" on stderr and
/// waits for a line on stdin when stdin is a terminal and !no_pause;
/// otherwise says that it goes on without waiting (`executed` commands so
/// far, for the message). Never blocks when stdin is not a terminal.
///
/// While it waits, `service` is called over and over: it keeps the device
/// going (the link read and polled, the outputs ticked) for a few
/// milliseconds and returns; stdin is checked between calls without
/// blocking (without a `service`, stdin is polled every 20 ms). Returns
/// false when Ctrl-C (an InterruptGuard) ended the wait: the caller stops
/// the job as after Ctrl-C elsewhere; true to go on with the next layer.
bool PauseForLayer(bool no_pause, const StreamJob& job, std::size_t command, std::uint64_t executed,
                   const std::function<void()>& service = {});

/// A device moves at most one step per axis per tick: InputError naming
/// --speed and --tick-hz when the job's speed needs more.
void CheckSpeedAgainstTicks(const StreamJob& job, std::uint32_t tick_hz, const StreamOptions& o);

/// The progress line on stderr: the layer running (LayerLabel), a bar,
/// commands executed, frames sent, and the rate (machine time over wall
/// time for the simulator); for a real device with a schedule (SetSchedule),
/// the machine time elapsed and left instead of the rate.
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled) : enabled_(enabled), start_(Clock::now()) {}
  ~ProgressLine() { Finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// The layer that the next lines show ("" for none).
  void SetLayer(std::string label) { layer_ = std::move(label); }
  /// The job's schedule (ScheduleJob), or nullptr for none; not owned.
  void SetSchedule(const MachineSchedule* schedule) { schedule_ = schedule; }
  /// The pause key's hint at the end of the line: "[space: pause]", or
  /// "paused — space to resume" while `paused`; nothing unless `keys`.
  void SetPauseState(bool keys, bool paused) {
    pause_keys_ = keys;
    paused_ = paused;
  }

  /// Redraws at most 10 times a second (and always when `force`).
  /// `machine_seconds` > 0 for a simulated device.
  void Show(std::uint64_t executed, std::uint64_t total, std::uint64_t frames,
            double machine_seconds, bool force = false);
  /// Ends the line, if one was drawn.
  void Finish();

 private:
  using Clock = std::chrono::steady_clock;
  bool enabled_;
  bool shown_ = false;
  std::string layer_;
  const MachineSchedule* schedule_ = nullptr;
  bool pause_keys_ = false;
  bool paused_ = false;
  std::uint64_t last_executed_ = 0;
  Clock::time_point executed_changed_;
  Clock::time_point start_;
  Clock::time_point last_;
};

/// Each runner returns the command's exit code (stream_command.h) and
/// throws DeviceError when the device fails or the link is lost, InputError
/// for a bad --device.
int RunSimulated(const StreamOptions& o, const PatchSet& set, const StreamJob& job,
                 const ToolpathOptions& drawing, const std::string& units);
int RunUsb(const StreamOptions& o, const StreamJob& job);
int RunGpio(const StreamOptions& o, const StreamJob& job);

/// The tick rate a dry run assumes for o.device: --tick-hz when given, else
/// the simulator's default (40000 Hz) or, for gpio, the GPIO runner's (10000).
std::uint32_t DryRunTickHz(const StreamOptions& o);

/// `stream --dry-run`: the job through the simulated plotter at
/// DryRunTickHz with o's limits, no pause between layers, nothing opened;
/// prints on stdout the machine time, the pen-down and pen-up distances, the
/// pen lifts, the page extent drawn and the command count, and writes
/// --svg/--png/--waveform when given (no comparison with the exact curves).
/// 0; DeviceError when the simulated device refused the job.
int RunDryRun(const StreamOptions& o, const StreamJob& job);

/// The job's schedule in machine time (machine_schedule.h), from a quiet
/// run on the simulated plotter at `tick_hz`; empty when that run did not
/// finish (the real run will say why).
MachineSchedule ScheduleJob(const StreamOptions& o, const StreamJob& job, std::uint32_t tick_hz);

}  // namespace fdsurf::host
