// SPDX-License-Identifier: MIT
// The in-memory backend: a virtual clock, step/dir and pen outputs that record
// timestamped events, and a pair of connected transports with latency,
// bandwidth and unplugging. Nothing here blocks or reads the real time, so the
// simulator and the tests are deterministic.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include <deque>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/clock.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/outputs.h"
#include "fdsurf/hal/pwm.h"
#include "fdsurf/hal/transport.h"

namespace fdsurf {
namespace hal {

/// Virtual time in microseconds. SleepUntilMicros() jumps to the requested
/// time instead of waiting; time never goes backwards.
class SimClock final : public Clock {
 public:
  explicit SimClock(uint64_t start_us = 0) : now_us_(start_us) {}

  FDSURF_NODISCARD uint64_t now_us() const { return now_us_; }
  /// Moves time forward by `us`.
  void Advance(uint64_t us) { now_us_ += us; }
  /// Sets the time; a time earlier than now is ignored (time is monotonic).
  void Set(uint64_t t_us) {
    if (t_us > now_us_) now_us_ = t_us;
  }

 private:
  uint64_t DoNowMicros() override { return now_us_; }
  void DoSleepUntilMicros(uint64_t t_us) override { Set(t_us); }

  uint64_t now_us_;
};

/// One recorded change of the step/dir/enable lines. A Step() records an
/// event with the stepped axes in `axis_mask`; a SetDirections() or
/// SetEnabled() that changes something records one with `axis_mask` 0. Every
/// event carries the state in force at that moment.
struct StepDirEvent {
  uint64_t time_us;
  uint8_t axis_mask;      ///< axes pulsed (0: a direction or enable change)
  uint8_t negative_mask;  ///< directions in force (bit set: towards negative)
  bool enabled;           ///< motors energised
  bool operator==(const StepDirEvent&) const = default;
};

/// Step/dir/enable outputs that record events instead of driving pins.
/// Starts disabled with every direction positive.
class SimStepDir final : public StepDirOutputs {
 public:
  /// `axes` must be 2 or 3; with any other value every call fails with
  /// kInvalidArgument. The clock must outlive this object.
  SimStepDir(SimClock& clock, uint8_t axes);

  FDSURF_NODISCARD const std::vector<StepDirEvent>& events() const { return events_; }
  void ClearEvents() { events_.clear(); }
  /// Net steps of `axis` so far (+1 per positive step, -1 per negative),
  /// counting steps while disabled too (the events show those).
  FDSURF_NODISCARD int64_t position(int axis) const { return position_[axis]; }
  FDSURF_NODISCARD bool enabled() const { return enabled_; }
  FDSURF_NODISCARD uint8_t negative_mask() const { return negative_mask_; }

  /// Makes the next call fail with `status` (for testing callers' error
  /// paths); LastError() then reads "sim step/dir: injected <status name>".
  void InjectError(IoStatus status) { injected_ = status; }

 private:
  IoStatus DoSetEnabled(bool enabled) override;
  IoStatus DoSetDirections(uint8_t negative_mask) override;
  IoStatus DoStep(uint8_t axis_mask) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }
  IoStatus Check(uint8_t mask, const char* what);

  SimClock& clock_;
  std::vector<StepDirEvent> events_;
  int64_t position_[3] = {0, 0, 0};
  uint8_t negative_mask_ = 0;
  bool enabled_ = false;
  IoStatus injected_ = IoStatus::kOk;
  std::string last_error_;
};

/// One recorded pen change.
struct PenEvent {
  uint64_t time_us;
  bool down;
  bool operator==(const PenEvent&) const = default;
};

/// A pen output that records every change (a SetPen() to the current state
/// records nothing). Starts up.
class SimPen final : public PenOutput {
 public:
  explicit SimPen(SimClock& clock) : clock_(clock) {}

  FDSURF_NODISCARD const std::vector<PenEvent>& events() const { return events_; }
  void ClearEvents() { events_.clear(); }
  FDSURF_NODISCARD bool down() const { return down_; }
  /// Makes the next SetPen() fail with `status`.
  void InjectError(IoStatus status) { injected_ = status; }

 private:
  IoStatus DoSetPen(bool down) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }

  SimClock& clock_;
  std::vector<PenEvent> events_;
  bool down_ = false;
  IoStatus injected_ = IoStatus::kOk;
  std::string last_error_;
};

/// One recorded change of a PWM channel: the settings in force from
/// `time_us` on (a pulse of pulse_us at the start of every period_us while
/// enabled).
struct PwmEvent {
  uint64_t time_us;
  uint32_t period_us;
  uint32_t pulse_us;
  bool enabled;
  bool operator==(const PwmEvent&) const = default;
};

/// A PWM channel that records every change of its settings (a call that
/// changes nothing records nothing) with the virtual time. Starts disabled,
/// period and pulse 0. Refuses (kInvalidArgument) a period of 0 or above
/// `max_period_us`, or a pulse longer than the period, like a timer would.
class SimPwm final : public PwmOutput {
 public:
  /// The clock must outlive this object.
  explicit SimPwm(SimClock& clock, uint32_t max_period_us = 1000000)
      : clock_(clock), max_period_us_(max_period_us) {}

  FDSURF_NODISCARD const std::vector<PwmEvent>& events() const { return events_; }
  void ClearEvents() { events_.clear(); }
  FDSURF_NODISCARD uint32_t period_us() const { return period_us_; }
  FDSURF_NODISCARD uint32_t pulse_us() const { return pulse_us_; }
  FDSURF_NODISCARD bool enabled() const { return enabled_; }
  /// Makes the next call fail with `status`; LastError() then reads
  /// "sim pwm: injected <status name>".
  void InjectError(IoStatus status) { injected_ = status; }

 private:
  IoStatus DoSetPeriodMicros(uint32_t period_us) override;
  IoStatus DoSetPulseMicros(uint32_t pulse_us) override;
  IoStatus DoSetEnabled(bool enabled) override;
  FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }
  IoStatus Injected();
  void Record(uint32_t period_us, uint32_t pulse_us, bool enabled);

  SimClock& clock_;
  uint32_t max_period_us_;
  std::vector<PwmEvent> events_;
  uint32_t period_us_ = 0;
  uint32_t pulse_us_ = 0;
  bool enabled_ = false;
  IoStatus injected_ = IoStatus::kOk;
  std::string last_error_;
};

/// The link between the two ends of a SimTransportPair.
struct SimLinkOptions {
  /// Added to every write's delivery time.
  uint64_t latency_us = 0;
  /// Bytes per second in each direction; 0 is unlimited. Writes in one
  /// direction are serialised: a write starts when the previous one has been
  /// sent, and takes ceil(size · 10^6 / bytes_per_second) µs.
  uint64_t bytes_per_second = 0;
  /// Most bytes in flight per direction (written, not yet read); a write that
  /// would exceed it fails with kTimeout and sends nothing. 0 is unlimited.
  size_t max_in_flight = 0;
};

/// Two connected Transport endpoints, "host" and "device", over in-memory
/// queues in virtual time. A write of n bytes at time t, on an idle link,
/// becomes readable on the other end at t + latency + ceil(n·10^6/bandwidth).
/// Read() never waits: it returns kTimeout at once if nothing is readable yet.
///
/// Disconnect() unplugs the link: queued bytes are dropped and both ends
/// return kDisconnected until the link is plugged back (PlugIn() or the time
/// given to PlugInAt() passes) *and* that end has called Reconnect(), as a
/// real host must reopen a replugged device.
class SimTransportPair {
 public:
  /// The clock must outlive this object.
  explicit SimTransportPair(SimClock& clock, const SimLinkOptions& options = SimLinkOptions());
  SimTransportPair(const SimTransportPair&) = delete;
  SimTransportPair& operator=(const SimTransportPair&) = delete;

  Transport& host() { return host_; }
  Transport& device() { return device_; }

  /// Unplugs the link now.
  void Disconnect();
  /// Plugs the link back in now.
  void PlugIn();
  /// Plugs the link back in when the virtual time reaches `t_us`; a
  /// Reconnect() waiting for it advances the clock to `t_us`.
  void PlugInAt(uint64_t t_us);
  bool connected();

  /// Bytes written towards the device (or host) and not read yet, including
  /// those not yet deliverable.
  FDSURF_NODISCARD size_t in_flight_to_device() const { return to_device_.in_flight; }
  FDSURF_NODISCARD size_t in_flight_to_host() const { return to_host_.in_flight; }

 private:
  struct Chunk {
    uint64_t ready_us;
    std::vector<uint8_t> bytes;
    size_t offset;
  };
  struct Direction {
    std::deque<Chunk> chunks;
    uint64_t busy_until_us = 0;
    size_t in_flight = 0;
  };
  class Endpoint final : public Transport {
   public:
    Endpoint(SimTransportPair& pair, const char* name, Direction& out, Direction& in)
        : pair_(pair), name_(name), out_(out), in_(in) {}
    ~Endpoint() = default;

   private:
    IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) override;
    IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received, uint32_t timeout_ms) override;
    IoStatus DoReconnect(uint32_t timeout_ms) override;
    FDSURF_NODISCARD const char* DoLastError() const override { return last_error_.c_str(); }
    IoStatus Fail(IoStatus status, const std::string& detail);
    bool Usable();

    SimTransportPair& pair_;
    const char* name_;
    Direction& out_;
    Direction& in_;
    uint32_t generation_ = 0;
    std::string last_error_;
  };

  void UpdatePlug();

  SimClock& clock_;
  SimLinkOptions options_;
  Direction to_device_;
  Direction to_host_;
  Endpoint host_;
  Endpoint device_;
  bool connected_ = true;
  bool replug_scheduled_ = false;
  uint64_t replug_at_us_ = 0;
  uint32_t generation_ = 0;
};

}  // namespace hal
}  // namespace fdsurf
