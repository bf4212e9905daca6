// SPDX-License-Identifier: MIT
#include "fdsurf/sim/plotter.h"

#include <algorithm>
#include <stdexcept>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/device/device.h"

namespace fdsurf::sim {

namespace internal {

// The firmware's Device for 2 or 3 axes behind one interface.
class DeviceRunner {
 public:
  virtual ~DeviceRunner() = default;
  virtual hal::IoStatus Service(hal::Transport& transport) = 0;
  virtual void Fill() = 0;
  virtual hal::IoStatus Tick(hal::StepDirOutputs& steppers, hal::PenOutput& pen) = 0;
  FDSURF_NODISCARD virtual const protocol::DeviceLinkStats& link_stats() const = 0;
  FDSURF_NODISCARD virtual const protocol::FrameDecoderStats& frame_stats() const = 0;
  FDSURF_NODISCARD virtual std::uint32_t executed() const = 0;
  FDSURF_NODISCARD virtual motion::ValidationWork validation_work() const = 0;
  virtual void set_endstops(hal::EndstopInputs* endstops) = 0;
};

}  // namespace internal

namespace {

// The same queue and lookahead a Raspberry Pi or a Cortex-M4 build would use.
template <int kAxes>
class AxesRunner final : public internal::DeviceRunner {
 public:
  explicit AxesRunner(std::uint32_t tick_hz) : device_(tick_hz) {}
  hal::IoStatus Service(hal::Transport& transport) override { return device_.Service(transport); }
  void Fill() override { device_.Fill(); }
  hal::IoStatus Tick(hal::StepDirOutputs& steppers, hal::PenOutput& pen) override {
    return device_.Tick(steppers, pen);
  }
  FDSURF_NODISCARD const protocol::DeviceLinkStats& link_stats() const override {
    return device_.link_stats();
  }
  FDSURF_NODISCARD const protocol::FrameDecoderStats& frame_stats() const override {
    return device_.frame_stats();
  }
  FDSURF_NODISCARD std::uint32_t executed() const override { return device_.executed(); }
  FDSURF_NODISCARD motion::ValidationWork validation_work() const override {
    return device_.validation_work();
  }
  void set_endstops(hal::EndstopInputs* endstops) override { device_.set_endstops(endstops); }

 private:
  device::Device<kAxes, 8, 1024> device_;
};

}  // namespace

// The device's end of the link, with faults injected into what it sends.
class SimulatedPlotter::FaultyTransport final : public hal::Transport {
 public:
  FaultyTransport(hal::Transport& inner, FaultRates rates, std::uint64_t seed)
      : inner_(inner), faults_(rates, seed) {}
  ~FaultyTransport() = default;
  FaultyTransport(const FaultyTransport&) = delete;
  FaultyTransport& operator=(const FaultyTransport&) = delete;
  FDSURF_NODISCARD const FaultStats& stats() const { return faults_.stats(); }

  /// While held, what the device writes waits (it is still computing);
  /// Release() sends it.
  void Hold() { holding_ = true; }
  hal::IoStatus Release() {
    holding_ = false;
    if (held_.empty()) return hal::IoStatus::kOk;
    const std::vector<std::uint8_t> out = std::move(held_);
    held_.clear();
    return Write(out.data(), out.size(), 100);
  }

 private:
  hal::IoStatus DoWrite(const std::uint8_t* data, std::size_t size,
                        std::uint32_t timeout_ms) override {
    if (holding_) {
      held_.insert(held_.end(), data, data + size);
      return hal::IoStatus::kOk;
    }
    faulted_.clear();
    faults_.Process(data, size, &faulted_);
    if (faulted_.empty()) return hal::IoStatus::kOk;
    return inner_.Write(faulted_.data(), faulted_.size(), timeout_ms);
  }
  hal::IoStatus DoRead(std::uint8_t* data, std::size_t capacity, std::size_t* received,
                       std::uint32_t timeout_ms) override {
    return inner_.Read(data, capacity, received, timeout_ms);
  }
  hal::IoStatus DoReconnect(std::uint32_t timeout_ms) override {
    return inner_.Reconnect(timeout_ms);
  }
  FDSURF_NODISCARD const char* DoLastError() const override { return inner_.LastError(); }

  hal::Transport& inner_;
  FaultLink faults_;
  std::vector<std::uint8_t> faulted_;
  std::vector<std::uint8_t> held_;
  bool holding_ = false;
};

// Measured under simavr (docs/motion.md): a hull test is validate-graze
// less validate-inside over its 19 tests; a line is validate-frame per line
// less its 3 hull tests.
constexpr std::uint32_t kAvrCyclesPerLine = 425039;
constexpr std::uint32_t kAvrCyclesPerHullTest = 5062;
// validate-prepared: the same line as a PREPARED_CURVE, no hull test.
constexpr std::uint32_t kAvrCyclesPerPreparedLine = 43014;

DeviceCost DeviceCost::Atmega2560() {
  return DeviceCost{16'000'000, kAvrCyclesPerLine, kAvrCyclesPerHullTest,
                    kAvrCyclesPerPreparedLine};
}

std::uint64_t DeviceCost::Microseconds(const motion::ValidationWork& work) const {
  if (cpu_hz == 0) return 0;
  const std::uint64_t cycles = std::uint64_t{work.lines} * cycles_per_line +
                               std::uint64_t{work.hull_tests} * cycles_per_hull_test +
                               std::uint64_t{work.prepared_lines} * cycles_per_prepared_line;
  return (cycles * 1'000'000 + cpu_hz - 1) / cpu_hz;
}

SimulatedPlotter::SimulatedPlotter(const PlotterOptions& options)
    : options_(options),
      steps_(clock_, static_cast<std::uint8_t>(options.axes)),
      pen_(clock_),
      link_(clock_, hal::SimLinkOptions{options.latency_us, options.bytes_per_second, 0}) {
  if (options.axes != 2 && options.axes != 3) {
    throw std::invalid_argument("the simulated plotter has 2 or 3 axes");
  }
  if (options.tick_hz == 0 || 1'000'000 % options.tick_hz != 0) {
    throw std::invalid_argument("the simulated tick rate must divide 1 MHz");
  }
  device_end_ =
      std::make_unique<FaultyTransport>(link_.device(), options.to_host, options.fault_seed + 1);
  if (options.axes == 2) {
    runner_ = std::make_unique<AxesRunner<2>>(options.tick_hz);
  } else {
    runner_ = std::make_unique<AxesRunner<3>>(options.tick_hz);
  }
  if (options.endstops) {
    endstops_ = std::make_unique<hal::SimEndstops>(steps_, options.endstop_options);
    runner_->set_endstops(endstops_.get());
  }
}

SimulatedPlotter::~SimulatedPlotter() = default;

void SimulatedPlotter::ScheduleUnplug(std::uint64_t at_us, std::uint64_t back_us) {
  unplug_scheduled_ = true;
  unplug_at_us_ = at_us;
  replug_at_us_ = back_us;
}

namespace {

// The host's PC end of the link during Run: it takes replies, then sends
// what the HostLink wants sent, through the faults injected towards the
// device; a lost port is reconnected and the link resumed.
class HostSide {
 public:
  HostSide(hal::Transport& port, FaultRates to_device, std::uint64_t seed, std::uint64_t tick_us)
      : port_(port), to_device_(to_device, seed), tick_us_(tick_us) {}

  void Service(host::HostLink& link, std::uint64_t now) {
    if (down_) {
      if (port_.Reconnect(0) == hal::IoStatus::kOk) {
        down_ = false;
        link.Resume();
        next_poll_ = now;
      }
      return;
    }
    for (;;) {
      std::size_t got = 0;
      const hal::IoStatus read = port_.Read(in_, sizeof in_, &got, 0);
      if (read == hal::IoStatus::kDisconnected) down_ = true;
      if (read != hal::IoStatus::kOk) break;
      link.OnBytes(in_, got, now);
      next_poll_ = now;  // an acknowledgement may open the window
    }
    if (!down_ && now >= next_poll_) Send(link, now);
  }

  FDSURF_NODISCARD const FaultStats& fault_stats() const { return to_device_.stats(); }

 private:
  // The host's PC polls its port about every millisecond.
  static constexpr std::uint64_t kHostPollUs = 1000;

  void Send(host::HostLink& link, std::uint64_t now) {
    out_.clear();
    link.Poll(now, &out_);
    if (!out_.empty()) {
      faulted_.clear();
      to_device_.Process(out_.data(), out_.size(), &faulted_);
      if (!faulted_.empty() &&
          port_.Write(faulted_.data(), faulted_.size(), 0) == hal::IoStatus::kDisconnected) {
        down_ = true;
      }
    }
    next_poll_ = std::max(now + tick_us_, std::min(link.NextPollUs(now), now + kHostPollUs));
  }

  hal::Transport& port_;
  FaultLink to_device_;
  std::uint64_t tick_us_;
  std::vector<std::uint8_t> out_;
  std::vector<std::uint8_t> faulted_;
  std::uint8_t in_[512] = {};
  bool down_ = false;
  std::uint64_t next_poll_ = 0;
};

}  // namespace

RunResult SimulatedPlotter::Run(host::HostLink& link, std::uint64_t time_limit_us,
                                const std::function<void(const RunProgress&)>& progress,
                                std::uint64_t progress_interval_us) {
  const std::uint64_t tick_us = 1'000'000 / options_.tick_hz;
  HostSide host(link_.host(), options_.to_device, options_.fault_seed, tick_us);
  bool device_down = false;
  std::uint64_t next_progress = progress_interval_us;
  std::uint64_t busy_until = 0;  // the device's main loop computes until then
  motion::ValidationWork charged = runner_->validation_work();

  RunResult result;
  for (;;) {
    const std::uint64_t now = clock_.now_us();
    if (link.Finished() || link.Failed() || now >= time_limit_us) break;
    if (result.acknowledged_us == 0 && link.AllAcknowledged()) result.acknowledged_us = now;
    if (unplug_scheduled_ && now >= unplug_at_us_) {
      unplug_scheduled_ = false;
      link_.Disconnect();
      link_.PlugInAt(replug_at_us_);
    }

    host.Service(link, now);

    // The device: its main loop (unless still busy validating), then one
    // tick of its step timer, an interrupt that a busy main loop does not stop.
    if (now >= busy_until) {
      if (device_end_->Release() == hal::IoStatus::kDisconnected) device_down = true;
      if (device_down) {
        device_down = device_end_->Reconnect(0) != hal::IoStatus::kOk;
      } else {
        device_end_->Hold();
        device_down = runner_->Service(*device_end_) == hal::IoStatus::kDisconnected;
        const motion::ValidationWork work = runner_->validation_work();
        const motion::ValidationWork spent{work.lines - charged.lines,
                                           work.hull_tests - charged.hull_tests,
                                           work.prepared_lines - charged.prepared_lines};
        charged = work;
        const std::uint64_t busy_us = options_.device_cost.Microseconds(spent);
        result.validation_us += busy_us;
        busy_until = now + busy_us;
        if (busy_until == now && device_end_->Release() == hal::IoStatus::kDisconnected) {
          device_down = true;
        }
      }
      if (now >= busy_until) runner_->Fill();
    }
    (void)runner_->Tick(steps_, pen_);  // a failed output faults the device: the host sees kFault
    clock_.Advance(tick_us);

    if (progress && now >= next_progress) {
      next_progress = now + progress_interval_us;
      progress(RunProgress{now, link.acknowledged(), runner_->executed(), link.enqueued(),
                           link.stats().frames_sent});
    }
  }
  result.time_us = clock_.now_us();
  result.finished = link.Finished();
  if (link.Failed()) {
    result.error = link.error();
  } else if (!result.finished) {
    result.error = "the job did not finish within " + std::to_string(time_limit_us / 1'000'000) +
                   " s of machine time";
  }
  result.executed = runner_->executed();
  result.host = link.stats();
  result.device = runner_->link_stats();
  result.device_frames = runner_->frame_stats();
  result.faults_to_device = host.fault_stats();
  result.faults_to_host = device_end_->stats();
  return result;
}

std::array<std::int64_t, 3> SimulatedPlotter::position() const {
  return {steps_.position(0), steps_.position(1), options_.axes == 3 ? steps_.position(2) : 0};
}

std::vector<DrawnPath> SimulatedPlotter::DrawnPaths() const {
  return ReplayEvents(steps_.events(), pen_.events());
}

std::vector<DrawnPath> ReplayEvents(const std::vector<hal::StepDirEvent>& steps,
                                    const std::vector<hal::PenEvent>& pens) {
  std::vector<DrawnPath> paths;
  std::array<std::int64_t, 3> position{0, 0, 0};
  bool down = false;
  DrawnPath current;
  const auto finish = [&] {
    if (current.points.size() >= 2) paths.push_back(std::move(current));
    current = DrawnPath{};
  };
  std::size_t p = 0;
  for (const hal::StepDirEvent& event : steps) {
    // Pen changes and steps never share a tick; a pen event at or before
    // this step's time happened first.
    while (p < pens.size() && pens[p].time_us <= event.time_us) {
      if (pens[p].down && !down) current.points.push_back(position);
      if (!pens[p].down && down) finish();
      down = pens[p].down;
      ++p;
    }
    if (event.axis_mask == 0) continue;
    for (int axis = 0; axis < 3; ++axis) {
      if ((event.axis_mask >> axis & 1) == 0) continue;
      position[axis] += (event.negative_mask >> axis & 1) != 0 ? -1 : 1;
    }
    if (down) current.points.push_back(position);
  }
  for (; p < pens.size(); ++p) {
    if (pens[p].down && !down) current.points.push_back(position);
    if (!pens[p].down && down) finish();
    down = pens[p].down;
  }
  finish();
  return paths;
}

}  // namespace fdsurf::sim
