// SPDX-License-Identifier: MIT
// The simulated plotter: the firmware's Device, unchanged, over the in-memory
// HAL (virtual clock, recorded step/dir and pen events, a transport pair with
// latency and bandwidth), co-simulated with the host's HostLink in virtual
// time. What it drew is read back from the recorded pin events alone.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/hal/sim_endstops.h"
#include "fdsurf/host/link.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/protocol/device_link.h"
#include "fdsurf/sim/fault_link.h"

namespace fdsurf::sim {

namespace internal {
class DeviceRunner;  // the firmware Device for 2 or 3 axes
}  // namespace internal

/// The device's compute time, charged in virtual time: while the device
/// validates the frames it has just read, its main loop is busy (its replies
/// wait, nothing is read or expanded) and only the step timer, an
/// interrupt, goes on. The time comes from the validation's counted work
/// (motion::ValidationWork), so it is deterministic. cpu_hz = 0 (the
/// default): computing is free, as on a fast host.
struct DeviceCost {
  std::uint32_t cpu_hz = 0;
  std::uint32_t cycles_per_line = 0;           // the planner on one line
  std::uint32_t cycles_per_hull_test = 0;      // each halving's hull test
  std::uint32_t cycles_per_prepared_line = 0;  // a PREPARED_CURVE's check at its level
  /// An ATmega2560 at 16 MHz, as measured under simavr (docs/motion.md).
  static DeviceCost Atmega2560();
  FDSURF_NODISCARD std::uint64_t Microseconds(const motion::ValidationWork& work) const;
};

struct PlotterOptions {
  /// 2 (pen plotter) or 3 (CNC with Z).
  int axes = 2;
  /// The device's step timer. Must divide 10^6 (whole microseconds per tick).
  std::uint32_t tick_hz = 40000;
  /// The link: one-way latency and bytes per second each way (USB full
  /// speed bulk transfers carry about 1 MB/s; a 115200-baud UART 11.5 kB/s).
  std::uint64_t latency_us = 500;
  std::uint64_t bytes_per_second = 1'000'000;
  /// Faults on each direction of the link, and their seed.
  FaultRates to_device;
  FaultRates to_host;
  std::uint64_t fault_seed = 1;
  /// What the device's validation costs in time (free by default).
  DeviceCost device_cost;
  /// Endstop switches for HOME (hal/sim_endstops.h): none unless `endstops`.
  bool endstops = false;
  hal::SimEndstopOptions endstop_options;
};

/// Progress of a run: virtual time, commands acknowledged and executed.
struct RunProgress {
  std::uint64_t time_us = 0;
  std::uint64_t acknowledged = 0;
  std::uint64_t executed = 0;
  std::uint64_t total = 0;
  std::uint64_t frames_sent = 0;
};

struct RunResult {
  bool finished = false;
  /// Why not, when !finished: the link's error, or a time-out.
  std::string error;
  std::uint64_t time_us = 0;
  /// When the device had acknowledged every command (virtual time).
  std::uint64_t acknowledged_us = 0;
  std::uint64_t executed = 0;
  /// How long the device's main loop spent validating, by the device cost
  /// model (0 when it is free).
  std::uint64_t validation_us = 0;
  host::HostLinkStats host;
  protocol::DeviceLinkStats device;
  protocol::FrameDecoderStats device_frames;
  FaultStats faults_to_device;
  FaultStats faults_to_host;
};

/// One pen-down stroke as the machine drew it: positions in steps.
struct DrawnPath {
  std::vector<std::array<std::int64_t, 3>> points;
};

class SimulatedPlotter {
 public:
  explicit SimulatedPlotter(const PlotterOptions& options);
  ~SimulatedPlotter();
  SimulatedPlotter(const SimulatedPlotter&) = delete;
  SimulatedPlotter& operator=(const SimulatedPlotter&) = delete;

  /// Runs the host link against the device until the link is Finished() or
  /// Failed(), or `time_limit_us` of virtual time passes. `progress` is
  /// called about every `progress_interval_us` of virtual time.
  RunResult Run(host::HostLink& link, std::uint64_t time_limit_us,
                const std::function<void(const RunProgress&)>& progress = {},
                std::uint64_t progress_interval_us = 1'000'000);

  /// Unplugs the link at `at_us` and plugs it back at `back_us` (virtual
  /// time); the host calls Resume() when it reconnects.
  void ScheduleUnplug(std::uint64_t at_us, std::uint64_t back_us);

  FDSURF_NODISCARD const PlotterOptions& options() const { return options_; }
  FDSURF_NODISCARD const std::vector<hal::StepDirEvent>& step_events() const {
    return steps_.events();
  }
  FDSURF_NODISCARD const std::vector<hal::PenEvent>& pen_events() const { return pen_.events(); }
  /// The machine's position now (steps), from the recorded pulses.
  FDSURF_NODISCARD std::array<std::int64_t, 3> position() const;
  /// The endstop switches, or nullptr without options().endstops.
  FDSURF_NODISCARD const hal::SimEndstops* endstops() const { return endstops_.get(); }

  /// The pen-down strokes, rebuilt from the recorded step and pen events.
  FDSURF_NODISCARD std::vector<DrawnPath> DrawnPaths() const;

 private:
  class FaultyTransport;

  PlotterOptions options_;
  hal::SimClock clock_;
  hal::SimStepDir steps_;
  hal::SimPen pen_;
  hal::SimTransportPair link_;
  std::unique_ptr<hal::SimEndstops> endstops_;
  std::unique_ptr<FaultyTransport> device_end_;
  std::unique_ptr<internal::DeviceRunner> runner_;
  std::uint64_t unplug_at_us_ = 0;
  std::uint64_t replug_at_us_ = 0;
  bool unplug_scheduled_ = false;
};

/// Rebuilds pen-down strokes from step and pen events (exposed for tests).
std::vector<DrawnPath> ReplayEvents(const std::vector<hal::StepDirEvent>& steps,
                                    const std::vector<hal::PenEvent>& pens);

}  // namespace fdsurf::sim
