// SPDX-License-Identifier: MIT
// The plotter firmware: the protocol endpoint, a fixed-capacity command queue,
// the path generator and the motion loop, driven through the HAL interfaces
// only, so the same code runs in the simulator, on a Linux host (GPIO) and on
// an MCU. No heap: all storage is in the object, sized by the template.
//
// A main loop does three things, over and over:
//
//   device.Service(transport);   // bytes in, replies out
//   device.Fill();               // expand commands into the lookahead buffer
//
// and the step timer, kTickHz times a second:
//
//   device.Tick(steppers, pen);  // at most one unit move or pen change
//
// On a host both run in one thread. On an MCU Tick() runs in the step
// timer's interrupt: give the Device an `InterruptLock`, an RAII type that
// masks that interrupt while it exists (e.g. saves SREG and clears I on AVR,
// PRIMASK on Cortex-M). The main-loop calls take it only around the few
// instructions they share with Tick() (the lookahead buffer's counters, the
// executed count, the stop and fault state), never around the engine's
// work, so a long validation or set-up delays no tick. Tick() itself never
// touches what only the main loop owns (the queue, the path generator):
// the end of a stop and the queue drop after an output failure are finished
// by the next Fill().
//
// Commands are validated when they arrive (the engine's planner runs over
// every line a patch will draw, every line is checked against the machine's
// travel, and the travel is capped so that every move between two points in
// it is plannable), so execution never meets a refusal; a command that would
// fail is answered with an ERROR and never queued. The validation's cost per
// frame is bounded (motion::ValidateCommand, docs/motion.md).
//
// Homing (HOME, docs/protocol.md): a device given endstop inputs
// (set_endstops) reads them once per tick. A HOME waits until everything
// before it has executed and the pen is up, then Tick() itself steps each
// axis towards its switch at the command's constant rate (a phase
// accumulator: one addition and one comparison per tick, no division), backs
// off, and sets the axis's position; the path generator and its travel
// checks are not involved. MOTORS 0 disables the drivers and forgets homing.
// Outside HOME the switches are hard limits (as Grbl's): when a unit move
// would step an axis towards a switch that is triggered (its min switch
// moving negative, its max switch moving positive), Tick() makes no step,
// lifts the pen, forgets homing and faults (kEndstopHit); the next Fill()
// drops the queue and the buffer. No deceleration: the carriage is at its
// mechanical end. Motion away from a triggered switch is allowed (homing
// with no back-off leaves the carriage on it). The check is two ANDs of the
// masks the tick read anyway.
// A configuration with kConfigFlagHomingRequired makes Accept() refuse
// PATCH, CURVE and MOVE (kNotHomed) unless every axis will be homed by the
// time they run (a HOME accepted before them counts).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/inputs.h"
#include "fdsurf/hal/outputs.h"
#include "fdsurf/hal/transport.h"
#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/device_link.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf {
namespace device {

/// The InterruptLock of a Device whose Tick() runs in the same thread as its
/// main loop (the simulator, the GPIO runner): nothing to mask. (Its
/// constructor is user-provided so that `const InterruptLock lock;` is not
/// an unused variable to the compiler.)
struct SingleThreadLock {
  SingleThreadLock() {}  // NOLINT(modernize-use-equals-default)
};

/// A CONFIG's limits as the motion loop takes them at `tick_hz` and
/// `slice_ticks` ticks per slice (MotionLimits; the axis limits of the axes
/// it configures, the others 0). The host works out what a device will do
/// with its CONFIG by the same conversion.
inline motion::MotionLimits MotionLimitsOf(const protocol::MachineConfig& config, uint32_t tick_hz,
                                           uint8_t slice_ticks = 1) {
  motion::MotionLimits limits{
      tick_hz,   config.max_rate, config.accel, config.pen_delay_ms, config.travel_rate,
      {0, 0, 0}, slice_ticks};
  for (int a = 0; a < config.axes && a < protocol::kMaxAxes && a < 3; ++a) {
    limits.axis_accel[a] = config.axis_accel[a];
  }
  return limits;
}

/// kAxes: 2 (a pen plotter) or 3 (a CNC with Z). kQueueCapacity: commands
/// that can wait (the host's credit). kLookahead: unit moves and events
/// buffered ahead of the motion, a power of two; the loop reaches full speed
/// only if the buffer holds the braking distance (docs/motion.md).
/// InterruptLock: see the top of this file. kFrameBytes: the largest decoded
/// frame taken, protocol::kMaxFrameBytes, or protocol::kMaxPreparedFrameBytes
/// on a device built without the planner (FDSURF_DEVICE_PLANNER=0) that
/// must save RAM. kReplyBytes: encoded replies held until Service() hands
/// them to the transport, at least the largest (41 bytes); a reply that
/// finds no room is dropped and the host's retransmission brings it again,
/// so a small chip (the Uno: 96) trades only a rare resend for the RAM.
template <int kAxes, int kQueueCapacity = 8, int kLookahead = 1024,
          class InterruptLock = SingleThreadLock, size_t kFrameBytes = protocol::kMaxFrameBytes,
          size_t kReplyBytes = 256>
class Device {
 public:
  static_assert(kAxes == 2 || kAxes == 3, "2 or 3 axes");
  static_assert(kQueueCapacity >= 1 && kQueueCapacity <= 255, "1..255 queued commands");
  static_assert(kFrameBytes >= protocol::kMaxPreparedFrameBytes &&
                    kFrameBytes <= protocol::kMaxFrameBytes,
                "frames of kMaxPreparedFrameBytes (no planner) to kMaxFrameBytes");
  static_assert(kLookahead >= 2 && kLookahead <= 32768 && (kLookahead & (kLookahead - 1)) == 0,
                "the lookahead is a power of two");

  /// `tick_hz`: how often the caller will call Tick(). `slice_ticks`: how
  /// many ticks share one choice of speed (a power of two up to
  /// motion::kMaxSliceTicks; MotionLimits::slice_ticks): 1 chooses it on
  /// every tick; an MCU whose step interrupt must be short takes more.
  explicit Device(uint32_t tick_hz, uint8_t slice_ticks = 1)
      : tick_hz_(tick_hz), slice_ticks_(slice_ticks), link_(this), motion_(lookahead_, kLookahead) {
    ResetState();
  }
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  /// The endstop switches Tick() reads (not owned; nullptr: none, the
  /// default, and HOME is refused). Set before the first Service(): HELLO's
  /// features report it.
  void set_endstops(hal::EndstopInputs* endstops) { endstops_ = endstops; }

  // --- I/O --------------------------------------------------------------

  void OnByte(uint8_t byte) { link_.OnByte(byte); }
  size_t ReadOutput(uint8_t* data, size_t capacity) { return link_.ReadOutput(data, capacity); }

  /// Reads what the transport has (without waiting), handles it, and sends
  /// the replies. Returns the transport's error, if any.
  hal::IoStatus Service(hal::Transport& transport) {
    uint8_t buffer[64];
    size_t received = 0;
    const hal::IoStatus status = transport.Read(buffer, sizeof buffer, &received, 0);
    if (status != hal::IoStatus::kOk && status != hal::IoStatus::kTimeout) return status;
    for (size_t i = 0; i < received; ++i) link_.OnByte(buffer[i]);
    for (;;) {
      const size_t n = link_.ReadOutput(buffer, sizeof buffer);
      if (n == 0) break;
      const hal::IoStatus written = transport.Write(buffer, n, 100);
      if (written != hal::IoStatus::kOk) return written;
    }
    return hal::IoStatus::kOk;
  }

  // --- Work ---------------------------------------------------------------

  /// Starts queued commands and expands them into the lookahead buffer until
  /// it is full or there is nothing left to do. A configuration waits until
  /// everything before it has been executed, then takes effect.
  /// Also finishes what Tick() left to the main loop: a stop that has come
  /// to rest (the buffer dropped, the pen lifted) and the queue drop after a
  /// fault. `max_entries` bounds the entries pushed by this call, so that a
  /// device whose motion consumes entries faster than it expands them (an
  /// 8-bit MCU) still gets back to Service() and answers the host.
  void Fill(uint16_t max_entries = 0xFFFFu) {
    FinishEndstopHit();
    FinishStopAtRest();
    if (!FinishHomingAtRest()) return;
    for (uint16_t pushed = 0; pushed < max_entries;) {
      if (fault_) {
        DropQueue();
        return;
      }
      if (!RoomToFill()) return;
      if (generator_.Idle()) {
        // Nothing more to expand for now (or a command that waits for
        // rest): the buffered moves are all the loop will get, so their
        // turn caps become final (MotionLoop::Flush()).
        if (queued_ == 0) return FlushMotion();
        const protocol::Command& next = queue_[queue_head_];
        if (next.type == protocol::MessageType::kConfig) {
          if (!ApplyConfigAtRest(next.body.config)) return FlushMotion();
          PopCommand();
          continue;
        }
        if (next.type == protocol::MessageType::kHome) {
          // Tick() does the homing; nothing is expanded until it ends.
          if (StartHomingAtRest(next.body.home)) PopCommand();
          return FlushMotion();
        }
        if (next.type == protocol::MessageType::kMotors) {
          if (!RequestMotorsAtRest(next.body.motors.enabled)) return FlushMotion();
          PopCommand();
          continue;
        }
        generator_.Start(next);
        PopCommand();
      }
      uint8_t entry = 0;
      if (!generator_.Next(&entry)) {
        if (generator_.failed()) {
          Fault(protocol::ErrorCode::kPlannerRefused, static_cast<uint8_t>(generator_.failure()));
        }
        continue;
      }
      // RoomToFill() saw room, and Tick() only ever makes more. The turn
      // caps' measuring runs with the tick enabled; only the push is masked.
      const motion::MotionLoop::PreparedEntry prepared = motion_.Prepare(entry);
      const InterruptLock lock;
      (void)motion_.Push(prepared);
      ++pushed;
    }
  }

  /// One tick of the step timer: at most one unit move (one step per axis)
  /// or one pen change, written to the outputs. An output error faults the
  /// device (it stops; STATUS reports it). Safe to call from an interrupt
  /// (see the top of this file).
  hal::IoStatus Tick(hal::StepDirOutputs& steppers, hal::PenOutput& pen) {
    // After a fault the motion still comes to rest along its path and the
    // pen is lifted, unless the outputs themselves failed.
    if (outputs_failed_ || endstop_hit_ || (fault_ && motion_.Idle())) {
      return hal::IoStatus::kOk;
    }
    if (pen_config_pending_) {
      // A CONFIG took effect (the motion at rest): the pen's servo widths.
      pen_config_pending_ = false;
      const hal::IoStatus configured = pen.ConfigureServo(pen_servo_up_us_, pen_servo_down_us_);
      if (configured != hal::IoStatus::kOk) return OutputFailed(configured);
    }
    hal::IoStatus status = ReadEndstops();
    if (status == hal::IoStatus::kOk && motors_request_ != kNoMotorsRequest) {
      status = ApplyMotorsRequest(steppers);
    }
    if (status == hal::IoStatus::kOk && homing_.active) status = HomingTick(steppers);
    if (status != hal::IoStatus::kOk) return OutputFailed(status);
    if (homing_.active) return hal::IoStatus::kOk;
    if (halt_outputs_ || pause_ != PausePhase::kNone) {
      bool consumed = false;
      const hal::IoStatus paused = TickPauseOrHalt(steppers, pen, &consumed);
      if (paused != hal::IoStatus::kOk) return OutputFailed(paused);
      if (consumed) return paused;
    }
    const motion::TickOutput out = motion_.Tick();
    executed_ += out.commands_done;
    if (out.pen != 0) status = pen.SetPen(out.pen > 0);
    // Towards a triggered switch: min while negative, max while positive.
    const uint8_t hit = static_cast<uint8_t>(
        out.step_mask & ((out.negative_mask & endstops_now_.min_mask) |
                         (static_cast<uint8_t>(~out.negative_mask) & endstops_now_.max_mask)));
    if (hit != 0) return EndstopHit(out, hit, pen);
    if (status == hal::IoStatus::kOk && out.step_mask != 0) {
      if (!enabled_) {
        status = steppers.SetEnabled(true);
        enabled_ = status == hal::IoStatus::kOk;
      }
      const uint8_t directions = static_cast<uint8_t>((directions_ & ~out.step_mask) |
                                                      (out.negative_mask & out.step_mask));
      if (status == hal::IoStatus::kOk && directions != directions_) {
        status = steppers.SetDirections(directions);
        directions_ = directions;
      }
      if (status == hal::IoStatus::kOk) status = steppers.Step(out.step_mask);
    }
    if (status != hal::IoStatus::kOk) return OutputFailed(status);
    return hal::IoStatus::kOk;
  }

  // --- State --------------------------------------------------------------

  FDSURF_NODISCARD const motion::MotionLoop& motion() const { return motion_; }
  FDSURF_NODISCARD const protocol::DeviceLinkStats& link_stats() const { return link_.stats(); }
  FDSURF_NODISCARD const protocol::FrameDecoderStats& frame_stats() const {
    return link_.frame_stats();
  }
  FDSURF_NODISCARD uint32_t executed() const { return executed_; }
  /// The validation work done since construction (lines planned, hull
  /// tests), for a simulator to charge as compute time.
  FDSURF_NODISCARD const motion::ValidationWork& validation_work() const {
    return validation_work_;
  }
  FDSURF_NODISCARD bool Idle() const {
    return queued_ == 0 && generator_.Idle() && motion_.Idle() && !homing_.active &&
           motors_request_ == kNoMotorsRequest;
  }
  /// Axes homed (bit a: axis a) since the motors were last disabled.
  FDSURF_NODISCARD uint8_t homed() const { return homed_; }

  // --- The protocol sink (fdsurf/protocol/device_link.h) ------------------

  protocol::ErrorCode Accept(const protocol::Command& command, uint8_t* detail) {
    *detail = 0;
    if (motion_.Stopping()) return protocol::ErrorCode::kStopped;
    if (command.type == protocol::MessageType::kConfig) {
      const protocol::MachineConfig& config = command.body.config;
      if (config.axes != kAxes) {
        *detail = protocol::kConfigFieldAxes;
        return protocol::ErrorCode::kDimsMismatch;
      }
      motion::TickLimits limits;
      motion::MotionLimits path_limits = LimitsOf(config);
      for (uint32_t& axis_accel : path_limits.axis_accel) axis_accel = 0;
      if (!motion::ToTickLimits(path_limits, &limits)) {
        *detail = config.max_rate > tick_hz_      ? protocol::kConfigFieldMaxRate
                  : config.travel_rate > tick_hz_ ? protocol::kConfigFieldTravelRate
                                                  : protocol::kConfigFieldAccel;
        return protocol::ErrorCode::kBadField;
      }
      if (!AxisAccelServable(config, detail)) return protocol::ErrorCode::kBadField;
      // A travel over kMaxPlannableTravelSteps would allow moves the engine
      // cannot plan: refused here, so that no accepted move can fault.
      uint8_t axis = 0;
      if (!motion::TravelPlannable<kAxes>(config, &axis)) {
        *detail = static_cast<uint8_t>(protocol::kConfigFieldTravel + axis);
        return protocol::ErrorCode::kBadField;
      }
      accepted_config_ = config;
      configured_ = true;
    } else {
      if (!configured_) return protocol::ErrorCode::kNotConfigured;
      const protocol::ErrorCode error = ValidateQueued(command, detail);
      if (error != protocol::ErrorCode::kNone) return error;
    }
    queue_[(queue_head_ + queued_) % kQueueCapacity] = command;
    ++queued_;
    return protocol::ErrorCode::kNone;
  }
  FDSURF_NODISCARD uint8_t Credits() const {
    return static_cast<uint8_t>(kQueueCapacity - queued_);
  }
  FDSURF_NODISCARD uint8_t QueueCapacity() const { return static_cast<uint8_t>(kQueueCapacity); }
  FDSURF_NODISCARD uint32_t TickHz() const { return tick_hz_; }
  FDSURF_NODISCARD uint8_t MaxAxes() const { return static_cast<uint8_t>(kAxes); }
  FDSURF_NODISCARD uint8_t Features() const {
    const uint8_t endstops = endstops_ != nullptr ? protocol::kFeatureEndstops : 0;
    const uint8_t planner = FDSURF_DEVICE_PLANNER ? protocol::kFeaturePlanner : 0;
    const uint8_t narrow = FDSURF_DEVICE_WIDE_TABLES ? 0 : protocol::kFeature64BitTables;
    const uint8_t uncapped = FDSURF_DEVICE_TURN_CAPS ? 0 : protocol::kFeatureNoTurnCaps;
    return static_cast<uint8_t>(endstops | planner | narrow | uncapped |
                                protocol::kFeaturePreparedCurves);
  }

  void FillStatus(protocol::StatusReport* report) const {
    const InterruptLock lock;
    if (fault_) {
      report->state = protocol::DeviceState::kFault;
    } else if (pause_ != PausePhase::kNone) {
      report->state = protocol::DeviceState::kPaused;
    } else if (motion_.Stopping()) {
      report->state = protocol::DeviceState::kStopping;
    } else if (homing_.active) {
      report->state = protocol::DeviceState::kHoming;
    } else {
      report->state = Idle() ? protocol::DeviceState::kIdle : protocol::DeviceState::kRunning;
    }
    report->error = error_;
    report->error_detail = error_detail_;
    // The pen as it is: a pause lifts it behind the motion loop's back.
    report->pen_down = motion_.pen_down() && !pen_lifted_by_pause_;
    for (int a = 0; a < protocol::kMaxAxes; ++a) report->position[a] = motion_.position()[a];
    report->queued = static_cast<uint8_t>(queued_);
    report->credits = Credits();
    report->next_seq = link_.next_seq();
    report->executed = executed_;
    report->moves = motion_.moves();
    const uint8_t endstops = static_cast<uint8_t>(endstops_now_.min_mask | endstops_now_.max_mask);
    report->flags = static_cast<uint8_t>((enabled_ ? protocol::kStatusFlagMotorsEnabled : 0) |
                                         homed_ * protocol::kStatusFlagHomedX |
                                         endstops * protocol::kStatusFlagEndstopX);
  }

  /// STOP: the queue is dropped now; the motion decelerates to rest along
  /// its path, then the rest of the buffer is dropped and the pen lifted.
  /// A homing in progress ends at once (its axis is not homed).
  void Stop() {
    DropQueue();
    const InterruptLock lock;
    EndPause();
    EndHoming();
    if (motion_.Idle()) {
      FinishStop();
    } else {
      motion_.Stop();
    }
  }

  /// PAUSE: the motion decelerates to rest along its path (as for STOP) but
  /// the queue and the buffer are kept; at rest the pen, if down, is lifted
  /// and the pen delay waited; then it holds (STATUS: kPaused). Commands are
  /// still accepted and expanded meanwhile. Ignored during a stop or a fault
  /// and when already paused.
  void Pause() {
    const InterruptLock lock;
    if (fault_ || motion_.Stopping() || pause_ != PausePhase::kNone) return;
    motion_.Pause();
    pause_ = PausePhase::kBraking;
  }

  /// RESUME: the pen is lowered again if the pause lifted it (with the pen
  /// delay), then the motion goes on from where it rests. A resume while
  /// still decelerating just goes on. Ignored when not paused.
  void Resume() {
    const InterruptLock lock;
    if (pause_ == PausePhase::kNone) return;
    if (pen_lifted_by_pause_) {
      pause_ = PausePhase::kLowering;
      pause_wait_ = 0;
      lower_pending_ = true;
    } else {
      EndPause();
    }
  }

  /// HALT, the emergency stop: the queue and the buffer are dropped at once
  /// with no deceleration (steps may be lost on a real machine: the position
  /// is then only what was commanded), and on the next tick the pen is
  /// lifted and the drivers disabled (they are enabled again by the next
  /// step). Configuration and counters are kept.
  void Halt() {
    DropQueue();
    const InterruptLock lock;
    EndPause();
    // The drivers go off: a homing ends and what was homed is forgotten.
    EndHoming();
    homed_ = 0;
    accepted_homed_ = 0;
    motors_request_ = kNoMotorsRequest;
    // The buffer goes at once; the motion loop's own pen state follows
    // through a pen-up entry, while the outputs are written directly by the
    // next Tick().
    FinishStop();
    halt_outputs_ = true;
  }

  /// A new session: as STOP, and the configuration and counters are
  /// forgotten too. Homing is kept: the motors stayed where they were.
  void Reset() {
    Stop();
    const InterruptLock lock;
    configured_ = false;
    executed_ = 0;
    fault_ = false;
    outputs_failed_ = false;
    error_ = protocol::ErrorCode::kNone;
    error_detail_ = 0;
  }

 private:
  FDSURF_NODISCARD motion::MotionLimits LimitsOf(const protocol::MachineConfig& config) const {
    return MotionLimitsOf(config, tick_hz_, slice_ticks_);
  }

  // Each used axis's acceleration limit must exceed the path's at this tick
  // rate, per tick and rounded down as the loop uses them: the difference is
  // what the turn caps leave for the centripetal part (docs/motion.md, "Each
  // axis on curves"). false: *detail names the field (11..13).
  bool AxisAccelServable(const protocol::MachineConfig& config, uint8_t* detail) const {
    for (int a = 0; a < config.axes && a < protocol::kMaxAxes; ++a) {
      if (!motion::AxisLimitServable(config.axis_accel[a], config.accel, tick_hz_)) {
        *detail = static_cast<uint8_t>(protocol::kConfigFieldAxisAccel + a);
        return false;
      }
    }
    return true;
  }

  void ResetState() {
    queued_ = 0;
    queue_head_ = 0;
    executed_ = 0;
    configured_ = false;
    fault_ = false;
    outputs_failed_ = false;
    enabled_ = false;
    directions_ = 0;
    pen_config_pending_ = false;
    pen_servo_up_us_ = 0;
    pen_servo_down_us_ = 0;
    error_ = protocol::ErrorCode::kNone;
    error_detail_ = 0;
    homed_ = 0;
    accepted_homed_ = 0;
    motors_request_ = kNoMotorsRequest;
    homing_ = Homing{};
    endstop_hit_ = false;
    endstops_now_ = hal::EndstopState{0, 0};
    for (int32_t& travel : applied_travel_) travel = 0;
    generator_.Reset(motion_.position(), false);
    pause_ = PausePhase::kNone;
  }

  // A configuration takes effect once everything before it has been
  // executed; false while the motion is not at rest yet.
  bool ApplyConfigAtRest(const protocol::MachineConfig& config) {
    // The conversion divides 64-bit numbers (a thousand cycles on a
    // Cortex-M0, more on an AVR): done before the tick is masked. Accept()
    // checked that it succeeds.
    motion::TickLimits tick;
    const bool converted = motion::ToTickLimits(LimitsOf(config), &tick);
    const InterruptLock lock;
    if (!motion_.Idle() || motors_request_ != kNoMotorsRequest) return false;
    if (converted) motion_.Configure(tick);
    // Handed to the pen output by the next Tick(), before any pen change.
    pen_servo_up_us_ = config.servo_up_us;
    pen_servo_down_us_ = config.servo_down_us;
    pen_config_pending_ = true;
    for (int a = 0; a < protocol::kMaxAxes; ++a) applied_travel_[a] = config.travel_steps[a];
    ++executed_;
    return true;
  }

  // MotionLoop::Flush() in its halves, the measuring with the tick enabled.
  // Only Fill() changes what is pending, and Tick() only ever makes room;
  // when Full(), the next Fill() tries again.
  void FlushMotion() {
    if (!motion_.FlushPending()) return;
    {
      const InterruptLock lock;
      if (motion_.Full()) return;
    }
    const motion::TurnCaps::Final final = motion_.PrepareFlush();
    const InterruptLock lock;
    motion_.CommitFlush(final);
  }

  FDSURF_NODISCARD bool RoomToFill() const {
    const InterruptLock lock;
    return !motion_.Stopping() && !motion_.Full();
  }

  void FinishStopAtRest() {
    const InterruptLock lock;
    if (motion_.Stopping() && motion_.speed() == 0) FinishStop();
  }

  void DropQueue() {
    queued_ = 0;
    queue_head_ = 0;
    const InterruptLock lock;
    // What is homed now is what the next accepted command will find.
    accepted_homed_ = homed_;
  }

  void PopCommand() {
    queue_head_ = static_cast<uint8_t>((queue_head_ + 1) % kQueueCapacity);
    --queued_;
  }

  // The pause or the halt's share of a tick; *consumed when the tick is
  // spent (the motion loop is not run).
  hal::IoStatus TickPauseOrHalt(hal::StepDirOutputs& steppers, hal::PenOutput& pen,
                                bool* consumed) {
    if (halt_outputs_) {
      halt_outputs_ = false;
      hal::IoStatus status = pen.SetPen(false);
      if (status == hal::IoStatus::kOk) status = steppers.SetEnabled(false);
      enabled_ = false;
      *consumed = true;
      return status;
    }
    *consumed = pause_ != PausePhase::kBraking;
    switch (pause_) {
      case PausePhase::kBraking:
        if (!motion_.HeldAtPause()) return hal::IoStatus::kOk;  // still decelerating
        *consumed = true;
        if (!motion_.pen_down()) {
          pause_ = PausePhase::kHeld;
          return hal::IoStatus::kOk;
        }
        pen_lifted_by_pause_ = true;
        pause_ = PausePhase::kLifting;
        pause_wait_ = motion_.limits().pen_delay_ticks;
        return pen.SetPen(false);
      case PausePhase::kLifting:
        if (pause_wait_ > 0) {
          --pause_wait_;
        } else {
          pause_ = PausePhase::kHeld;
        }
        return hal::IoStatus::kOk;
      case PausePhase::kLowering:
        if (lower_pending_) {
          lower_pending_ = false;
          pen_lifted_by_pause_ = false;
          pause_wait_ = motion_.limits().pen_delay_ticks;
          return pen.SetPen(true);
        }
        if (pause_wait_ > 0) {
          --pause_wait_;
        } else {
          EndPause();
        }
        return hal::IoStatus::kOk;
      case PausePhase::kHeld:
      case PausePhase::kNone:
        return hal::IoStatus::kOk;
    }
    return hal::IoStatus::kOk;
  }

  // Also on STOP, HALT and faults: a pen the pause lifted stays up (they
  // lift it anyway, through the buffer).
  void EndPause() {
    pause_ = PausePhase::kNone;
    pen_lifted_by_pause_ = false;
    pause_wait_ = 0;
    lower_pending_ = false;
    motion_.Resume();
  }

  hal::IoStatus OutputFailed(hal::IoStatus status) {
    // The queue is the main loop's: Fill() drops it on seeing fault_.
    outputs_failed_ = true;
    error_ = protocol::ErrorCode::kOutputFailed;
    error_detail_ = static_cast<uint8_t>(status);
    fault_ = true;
    EndPause();
    EndHoming();
    motion_.Stop();
    return status;
  }

  void FinishStop() {
    motion_.Clear();
    generator_.Reset(motion_.position(), motion_.pen_down());
    if (motion_.pen_down()) {
      // Lifted through the buffer, so the pen delay is kept.
      motion_.Push(motion::MakeEntry(motion::EntryKind::kPenUp));
    }
  }

  // ---- Homing and motors (the HOME and MOTORS commands) ----------------

  struct Homing {
    bool active = false;
    bool ended = false;    // the main loop has to resynchronise the generator
    bool backing = false;  // backing off (else searching for the switch)
    uint8_t axis = 0;
    uint8_t remaining = 0;  // axes still to home, the current one included
    uint8_t toward_max = 0;
    uint32_t rate = 0;
    uint32_t backoff = 0;
    uint32_t accumulator = 0;  // += rate per tick; a step each time it reaches tick_hz
    uint32_t steps_left = 0;   // of the search budget, or of the back-off
  };
  static constexpr uint8_t kNoMotorsRequest = 0;
  static constexpr uint8_t kMotorsOffRequest = 1;
  static constexpr uint8_t kMotorsOnRequest = 2;
  static constexpr uint8_t kAxisBits = static_cast<uint8_t>((1u << kAxes) - 1u);

  // Everything but CONFIG: HOME and MOTORS here, motion through
  // motion::ValidateCommand (and refused while homing is required and the
  // axes will not all be homed by the time it runs).
  protocol::ErrorCode ValidateQueued(const protocol::Command& command, uint8_t* detail) {
    switch (command.type) {
      case protocol::MessageType::kHome:
        return ValidateHome(command.body.home, detail);
      case protocol::MessageType::kMotors:
        if (!command.body.motors.enabled) accepted_homed_ = 0;
        return protocol::ErrorCode::kNone;
      case protocol::MessageType::kPen:
        break;
      default:
        if ((accepted_config_.flags & protocol::kConfigFlagHomingRequired) != 0 &&
            accepted_homed_ != kAxisBits) {
          return protocol::ErrorCode::kNotHomed;
        }
        break;
    }
    return motion::ValidateCommand<kAxes>(command, accepted_config_, detail, &validation_work_);
  }

  protocol::ErrorCode ValidateHome(const protocol::HomeCommand& home, uint8_t* detail) {
    const hal::EndstopState fitted =
        endstops_ != nullptr ? endstops_->fitted() : hal::EndstopState{0, 0};
    const uint8_t toward_min = static_cast<uint8_t>(home.axes & ~home.toward_max);
    if ((home.axes & ~kAxisBits) != 0 || (toward_min & ~fitted.min_mask) != 0 ||
        (home.toward_max & ~fitted.max_mask) != 0) {
      *detail = protocol::kHomeFieldAxes;
      return protocol::ErrorCode::kBadField;
    }
    if (home.rate > tick_hz_) {
      *detail = protocol::kHomeFieldRate;
      return protocol::ErrorCode::kBadField;
    }
    for (int a = 0; a < kAxes; ++a) {
      if ((home.axes >> a & 1u) != 0 &&
          home.backoff > static_cast<uint32_t>(accepted_config_.travel_steps[a])) {
        *detail = protocol::kHomeFieldBackoff;
        return protocol::ErrorCode::kBadField;
      }
    }
    accepted_homed_ = static_cast<uint8_t>(accepted_homed_ | home.axes);
    return protocol::ErrorCode::kNone;
  }

  // A HOME at the head of the queue: once the motion is at rest, lifts the
  // pen if it is down (and waits for that), then hands the homing to
  // Tick(). True when the homing has started.
  bool StartHomingAtRest(const protocol::HomeCommand& home) {
    const InterruptLock lock;
    if (!motion_.Idle() || motors_request_ != kNoMotorsRequest) return false;
    if (motion_.pen_down()) {
      (void)motion_.Push(motion::MakeEntry(motion::EntryKind::kPenUp));
      return false;
    }
    homing_ = Homing{};
    homing_.active = true;
    homing_.remaining = home.axes;
    homing_.toward_max = home.toward_max;
    homing_.rate = home.rate;
    homing_.backoff = home.backoff;
    StartHomingAxis();
    return true;
  }

  // The lowest axis left: its search budget is its travel and an eighth.
  void StartHomingAxis() {
    uint8_t axis = 0;
    while ((homing_.remaining >> axis & 1u) == 0) ++axis;
    const uint32_t travel = static_cast<uint32_t>(applied_travel_[axis]);
    homing_.axis = axis;
    homing_.backing = false;
    homing_.accumulator = 0;
    homing_.steps_left = travel + (travel >> 3) + 1;
  }

  // False while Tick() is homing; once it has ended, the path generator
  // continues from where the homing left the machine.
  bool FinishHomingAtRest() {
    const InterruptLock lock;
    if (homing_.active) return false;
    if (homing_.ended) {
      homing_.ended = false;
      generator_.Reset(motion_.position(), motion_.pen_down());
    }
    return true;
  }

  bool RequestMotorsAtRest(bool enabled) {
    const InterruptLock lock;
    if (!motion_.Idle() || motors_request_ != kNoMotorsRequest) return false;
    motors_request_ = enabled ? kMotorsOnRequest : kMotorsOffRequest;
    return true;
  }

  // In Tick(): a MOTORS command's effect, counted as executed.
  // A homing in progress ends at once (its axis is not homed).
  void EndHoming() {
    if (homing_.active) {
      homing_.active = false;
      homing_.ended = true;
    }
  }

  hal::IoStatus ApplyMotorsRequest(hal::StepDirOutputs& steppers) {
    const bool enable = motors_request_ == kMotorsOnRequest;
    motors_request_ = kNoMotorsRequest;
    ++executed_;
    if (!enable) homed_ = 0;
    const hal::IoStatus status = steppers.SetEnabled(enable);
    enabled_ = enable && status == hal::IoStatus::kOk;
    return status;
  }

  hal::IoStatus ReadEndstops() {
    if (endstops_ == nullptr) return hal::IoStatus::kOk;
    const hal::IoStatus status = endstops_->Read(&endstops_now_);
    if (status != hal::IoStatus::kOk) endstops_now_ = hal::EndstopState{0, 0};
    return status;
  }

  // One tick of homing: O(1), additions and comparisons only. The axis steps
  // when the accumulator reaches tick_hz (rate steps per second on average,
  // no ramp: the rate must be one the motors start at).
  hal::IoStatus HomingTick(hal::StepDirOutputs& steppers) {
    homing_.accumulator += homing_.rate;
    if (homing_.accumulator < tick_hz_) return hal::IoStatus::kOk;
    homing_.accumulator -= tick_hz_;
    const uint8_t bit = static_cast<uint8_t>(1u << homing_.axis);
    const bool toward_max = (homing_.toward_max & bit) != 0;
    const uint8_t switches = toward_max ? endstops_now_.max_mask : endstops_now_.min_mask;
    const bool triggered = (switches & bit) != 0;
    if (!homing_.backing) {
      if (triggered) {
        homing_.backing = true;
        homing_.steps_left = homing_.backoff;
        return hal::IoStatus::kOk;
      }
      if (homing_.steps_left == 0) return HomingFailed();
      --homing_.steps_left;
      return HomingStep(steppers, toward_max);
    }
    if (homing_.steps_left > 0) {
      --homing_.steps_left;
      return HomingStep(steppers, !toward_max);
    }
    // A back-off of 0 rests on the switch on purpose; any other must release it.
    if (triggered && homing_.backoff > 0) return HomingFailed();
    FinishHomingAxis(toward_max);
    return hal::IoStatus::kOk;
  }

  hal::IoStatus HomingStep(hal::StepDirOutputs& steppers, bool positive) {
    const uint8_t bit = static_cast<uint8_t>(1u << homing_.axis);
    hal::IoStatus status = hal::IoStatus::kOk;
    if (!enabled_) {
      status = steppers.SetEnabled(true);
      enabled_ = status == hal::IoStatus::kOk;
    }
    const uint8_t directions =
        static_cast<uint8_t>(positive ? (directions_ & ~bit) : (directions_ | bit));
    if (status == hal::IoStatus::kOk && directions != directions_) {
      status = steppers.SetDirections(directions);
      directions_ = directions;
    }
    if (status == hal::IoStatus::kOk) status = steppers.Step(bit);
    if (status != hal::IoStatus::kOk) return status;
    int32_t position[protocol::kMaxAxes];
    for (int a = 0; a < protocol::kMaxAxes; ++a) position[a] = motion_.position()[a];
    position[homing_.axis] += positive ? 1 : -1;
    motion_.set_position(position);
    return hal::IoStatus::kOk;
  }

  void FinishHomingAxis(bool toward_max) {
    int32_t position[protocol::kMaxAxes];
    for (int a = 0; a < protocol::kMaxAxes; ++a) position[a] = motion_.position()[a];
    position[homing_.axis] = toward_max ? applied_travel_[homing_.axis] : 0;
    motion_.set_position(position);
    const uint8_t bit = static_cast<uint8_t>(1u << homing_.axis);
    homed_ = static_cast<uint8_t>(homed_ | bit);
    homing_.remaining = static_cast<uint8_t>(homing_.remaining & ~bit);
    if (homing_.remaining != 0) {
      StartHomingAxis();
      return;
    }
    homing_.active = false;
    homing_.ended = true;
    ++executed_;
  }

  // In Tick(): the switch never triggered (or never released). The queue
  // is dropped by the next Fill(), as after any fault.
  hal::IoStatus HomingFailed() {
    error_ = protocol::ErrorCode::kHomingFailed;
    error_detail_ = homing_.axis;
    fault_ = true;
    homing_.active = false;
    homing_.ended = true;
    return hal::IoStatus::kOk;
  }

  // In Tick(): the unit move `out` would step the axes in `hit` towards
  // their triggered switches. None of its steps is made (the loop's
  // position is put back), the pen goes up at once, homing is forgotten;
  // Tick() then does nothing until Fill() has dropped the motion
  // (FinishEndstopHit). The lowest axis hit is reported.
  hal::IoStatus EndstopHit(const motion::TickOutput& out, uint8_t hit, hal::PenOutput& pen) {
    int32_t position[protocol::kMaxAxes];
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      position[a] = motion_.position()[a];
      if ((out.step_mask >> a & 1u) != 0)
        position[a] += (out.negative_mask >> a & 1u) != 0 ? 1 : -1;
    }
    motion_.set_position(position);
    uint8_t axis = 0;
    while ((hit >> axis & 1u) == 0) ++axis;
    const bool max = (out.negative_mask >> axis & 1u) == 0;
    endstop_hit_ = true;
    fault_ = true;
    error_ = protocol::ErrorCode::kEndstopHit;
    error_detail_ = static_cast<uint8_t>(axis | (max ? protocol::kEndstopHitMax : 0));
    homed_ = 0;
    EndPause();
    const hal::IoStatus lifted = pen.SetPen(false);
    return lifted == hal::IoStatus::kOk ? lifted : OutputFailed(lifted);
  }

  // In the main loop after an endstop hit: as HALT, the queue and the buffer
  // go at once and the loop's pen state follows through a pen-up entry
  // (the pen itself is up already); a homing accepted but not run is void.
  void FinishEndstopHit() {
    {
      const InterruptLock lock;
      if (!endstop_hit_) return;
    }
    DropQueue();
    const InterruptLock lock;
    FinishStop();
    accepted_homed_ = 0;
    endstop_hit_ = false;
  }

  // In Tick(): an output (or input) failed; Fill() drops the queue.
  // A fault found by the main loop (Tick() records its own).
  void Fault(protocol::ErrorCode error, uint8_t detail) {
    DropQueue();
    const InterruptLock lock;
    EndPause();
    fault_ = true;
    error_ = error;
    error_detail_ = detail;
    motion_.Stop();
  }

  // A pause's course: decelerating, lifting the pen (pen delay), holding,
  // lowering it again at RESUME (pen delay), then kNone.
  enum class PausePhase : uint8_t { kNone, kBraking, kLifting, kHeld, kLowering };

  uint32_t tick_hz_;
  uint8_t slice_ticks_;
  protocol::DeviceLink<Device, kReplyBytes, kFrameBytes> link_;
  uint8_t lookahead_[kLookahead];
  motion::MotionLoop motion_;
  motion::PathGenerator<kAxes> generator_;
  protocol::Command queue_[kQueueCapacity];
  uint8_t queue_head_;
  uint8_t queued_;
  protocol::MachineConfig accepted_config_;
  bool configured_;
  bool fault_;
  bool outputs_failed_;
  bool enabled_;
  uint8_t directions_;
  // The pen's CONFIG (servo widths, µs) waiting for Tick() to hand it over.
  bool pen_config_pending_;
  uint16_t pen_servo_up_us_;
  uint16_t pen_servo_down_us_;
  protocol::ErrorCode error_;
  uint8_t error_detail_;
  uint32_t executed_;
  motion::ValidationWork validation_work_ = {0, 0, 0};
  PausePhase pause_ = PausePhase::kNone;
  uint32_t pause_wait_ = 0;           // pen delay ticks left in kLifting/kLowering
  bool pen_lifted_by_pause_ = false;  // the pen is up only because of the pause
  bool lower_pending_ = false;        // kLowering: the pen is yet to be lowered
  bool halt_outputs_ = false;         // HALT: pen up and drivers off on the next tick
  bool endstop_hit_ = false;          // a hard limit stopped Tick(); Fill() drops the motion
  hal::EndstopInputs* endstops_ = nullptr;
  hal::EndstopState endstops_now_ = {0, 0};
  Homing homing_;
  int32_t applied_travel_[protocol::kMaxAxes] = {0, 0, 0};
  uint8_t homed_ = 0;
  uint8_t accepted_homed_ = 0;
  uint8_t motors_request_ = kNoMotorsRequest;
};

}  // namespace device
}  // namespace fdsurf
