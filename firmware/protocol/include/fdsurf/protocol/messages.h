// SPDX-License-Identifier: MIT
// The device protocol's messages, decoded: what the host asks the device to
// do, and what the device answers. docs/protocol.md gives the wire format
// (COBS frames with a CRC-32, sequence numbers, acknowledgements, credits);
// this header is the contract between the protocol code and the device that
// executes the commands.
//
// All lengths, positions and rates are in motor steps: the host maps its
// drawing into steps before it sends anything, so the device never scales.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/adaptive.h"
#include "fdsurf/basis.h"
#include "fdsurf/forward_difference.h"

/// 1 (the default): the device sets PATCH and CURVE up itself, with the
/// planner (PrepareAdaptiveCurve, the isoline walker, CurvePowerCoefficients).
/// 0: a device without the planner, for small chips (the Arduino Uno, issue
/// 17). It takes PREPARED_CURVE, MOVE, PEN, HOME and MOTORS and refuses PATCH
/// and CURVE as unknown types (HELLO_REPLY's features say so), and it holds
/// none of their state, so its commands are smaller too. A firmware build
/// defines it for every file of the core and the firmware, as
/// targets/CMakeLists.txt builds fdsurf_core_prepared; the host always has
/// the planner.
#ifndef FDSURF_DEVICE_PLANNER
#define FDSURF_DEVICE_PLANNER 1
#endif

namespace fdsurf {
namespace protocol {

/// Protocol version spoken by this code; HELLO carries it. Version 2 adds
/// the session id (Hello::session), folded into the CRC of every other frame.
/// Version 3 adds PAUSE, RESUME and HALT, and the machine's pen hardware and
/// limits in CONFIG, and homing (HOME, MOTORS, MachineConfig::flags, the
/// status flags and HELLO_REPLY's features): issue 15, docs/protocol.md.
/// Version 4 adds PREPARED_CURVE (a curve the host has planned) and the
/// feature bit that says a device takes it: issue 17.
constexpr uint8_t kProtocolVersion = 4;
/// Largest decoded frame: type, sequence number, body and CRC together.
constexpr size_t kMaxFrameBytes = 512;
/// Largest decoded frame of the commands a device without the planner takes
/// (every type but PATCH and CURVE). The largest is a 3-D PREPARED_CURVE:
/// 7 bytes of frame, dims and level (2), the tolerance (4) and 12
/// coefficients below 2^47 (at most 7 zigzag varint bytes each), 97 bytes; a
/// CONFIG is at most 63 (codec_test's EveryCommandButPatchAndCurveFitsTheSmallFrame).
/// Such a device may size its frame buffer to this (device::Device's
/// kFrameBytes) and save 412 bytes of RAM; a PATCH sent to it is then
/// dropped as overlong instead of refused as an unknown type.
constexpr size_t kMaxPreparedFrameBytes = 100;
/// Largest number of axes a device drives (X, Y and optionally Z).
constexpr int kMaxAxes = 3;

/// Frame types. Host → device below 0x80, device → host from 0x80 on.
/// Sequenced commands (0x10..0x1F) are queued and executed exactly once in
/// sequence order; the others are answered at once.
enum class MessageType : uint8_t {
  kHello = 0x01,        ///< version and flags; answered by kHelloReply
  kStatusQuery = 0x02,  ///< answered by kStatusReport
  kStop = 0x03,         ///< stop motion, drop the queue; answered by kAck
  /// Decelerate to rest along the path, keep queue and buffer, lift the pen,
  /// hold (DeviceState::kPaused); answered by kAck.
  kPause = 0x04,
  /// Lower the pen again if the pause lifted it, go on; answered by kAck.
  kResume = 0x05,
  /// Emergency stop: at once (no deceleration), drop queue and buffer, lift
  /// the pen, disable the motors; answered by kAck.
  kHalt = 0x06,

  kConfig = 0x10,         ///< MachineConfig
  kPatch = 0x11,          ///< PatchCommand
  kCurve = 0x12,          ///< CurveCommand
  kMove = 0x13,           ///< MoveCommand
  kPen = 0x14,            ///< PenCommand
  kHome = 0x15,           ///< HomeCommand
  kMotors = 0x16,         ///< MotorsCommand
  kPreparedCurve = 0x17,  ///< PreparedCurveCommand

  kHelloReply = 0x81,
  kStatusReport = 0x82,
  kAck = 0x83,
  kNak = 0x84,
  kError = 0x85,
};

/// Whether a message type is a sequenced (queued, exactly-once) command.
inline bool IsSequenced(MessageType type) {
  return static_cast<uint8_t>(type) >= 0x10 && static_cast<uint8_t>(type) <= 0x1F;
}

/// Flags of kHello.
constexpr uint8_t kHelloFlagNewSession = 0x01;  ///< forget sequence state and queue, start at seq 0
/// Every flag this version knows; a HELLO with another bit set is refused.
constexpr uint8_t kHelloKnownFlags = kHelloFlagNewSession;

/// kHello's body. The frame's seq field carries a token the reply echoes.
/// HELLO is the one host frame with the plain CRC; every other frame of both
/// directions carries SessionTag(session) in its CRC (frame.h), the HELLO's
/// replies included.
struct Hello {
  uint8_t version;
  uint8_t flags;
  /// Chosen by the host, != 0. With kHelloFlagNewSession the device starts
  /// this session (a repeat of the current one's HELLO is answered without
  /// a reset); without it the device resumes it, or refuses with
  /// kUnknownSession if it is not the session it has.
  uint32_t session;
};

/// The machine the host drives, in steps. Sent once per job (sequenced, so
/// it takes effect in order with the motion commands).
struct MachineConfig {
  /// 2 (X, Y) or 3 (X, Y, Z).
  uint8_t axes;
  /// Informational scale, steps per metre, > 0 per used axis.
  uint32_t steps_per_meter[kMaxAxes];
  /// Each axis moves within [0, travel_steps], 1 ≤ travel_steps < 2^30.
  int32_t travel_steps[kMaxAxes];
  /// Path speed limit with the pen down, steps per second,
  /// 1 ≤ max_rate ≤ the device's tick rate.
  uint32_t max_rate;
  /// Path acceleration limit in steps per second², ≥ 1.
  uint32_t accel;
  /// Rest after every pen change before motion resumes, milliseconds.
  uint16_t pen_delay_ms;
  /// Path speed limit with the pen up (travel), steps per second,
  /// 1 ≤ travel_rate ≤ the device's tick rate.
  uint32_t travel_rate;
  /// Each axis's acceleration limit, steps per second²: ≥ 1 for used axes,
  /// 0 for unused ones. `accel` stays the limit along the path; the device
  /// also keeps every axis's share, the centripetal part included, within
  /// this (docs/motion.md, "Acceleration on curves").
  uint32_t axis_accel[kMaxAxes];
  /// A hobby-servo pen lift's pulse widths, µs, every 20 ms: with the pen up
  /// and with it down. Both 0: the pen output is a plain switch; else each
  /// in 500..2500 (hal/pwm.h ServoPen).
  uint16_t servo_up_us;
  uint16_t servo_down_us;
  /// kConfigFlag... bits; the others must be 0.
  uint8_t flags;
};

/// MachineConfig::flags: PATCH, CURVE and MOVE are refused with kNotHomed
/// until every configured axis has been homed (HOME) since the motors were
/// last disabled.
constexpr uint8_t kConfigFlagHomingRequired = 0x01;
constexpr uint8_t kConfigKnownFlags = kConfigFlagHomingRequired;

/// Draw a patch as isolines: lines_s s-lines then lines_t t-lines, each a
/// step-exact adaptive forward-difference path within tolerance, with
/// pen-up travel between lines (serpentine order).
struct PatchCommand {
  Basis basis;
  /// Equal to the configured axes.
  uint8_t dims;
  /// 0 (family left out) or 2..kMaxPatchSteps + 1; not both 0.
  uint16_t lines_s;
  uint16_t lines_t;
  /// Euclidean tolerance in 2^-8 steps (as AdaptiveSettings::tolerance_q8).
  uint32_t tolerance_q8;
  /// Edge lines not to draw, because another patch draws the same curve:
  /// kSkipFirstSLine | kSkipLastSLine | kSkipFirstTLine | kSkipLastTLine.
  uint8_t skip_lines;
  /// Geometry in steps, Q47.16; only [0, dims) used.
  PatchGeometry1 geometry[kMaxAxes];
};

/// PatchCommand::skip_lines: the s-line at s = 0, at s = 1, the t-line at
/// t = 0, at t = 1. The other bits must be 0.
constexpr uint8_t kSkipFirstSLine = 0x01;
constexpr uint8_t kSkipLastSLine = 0x02;
constexpr uint8_t kSkipFirstTLine = 0x04;
constexpr uint8_t kSkipLastTLine = 0x08;
constexpr uint8_t kSkipLinesMask = 0x0F;

/// Draw one cubic curve with the current pen state, starting with a straight
/// move from the current position to the curve's start if they differ.
struct CurveCommand {
  Basis basis;
  uint8_t dims;
  uint32_t tolerance_q8;
  CurveGeometry1 geometry[kMaxAxes];
};

/// CURVE as the host has planned it ("the host computes, the device adds"):
/// the curve's power coefficients, already rounded once to 2^-16 steps, and
/// the finest level the host's planner chose. The device checks that level
/// with shifts and additions only (PrepareAdaptiveCurveAtLevel: the same
/// tests as the planner, no search, no wide integers, no divide) and steps
/// the exact table it forms; everything else is as for CURVE (a straight
/// move to the start first if the machine is elsewhere, the current pen
/// state, a step-exact path within the tolerance). A patch is sent as its
/// drawn isolines, each a PREPARED_CURVE (docs/protocol.md, "Prepared
/// curves").
struct PreparedCurveCommand {
  /// Equal to the configured axes.
  uint8_t dims;
  /// The finest step is 2^-level, 0..kMaxAdaptiveLevel.
  uint8_t level;
  /// Euclidean tolerance in 2^-8 steps (as AdaptiveSettings::tolerance_q8).
  uint32_t tolerance_q8;
  /// a·u³ + b·u² + c·u + d per axis, u from 0 to 1, in 2^-16 steps
  /// (|each| < 2^47); only [0, dims) used.
  PowerCurve1 power[kMaxAxes];
};

/// A straight move to `target` (steps) with the current pen state.
struct MoveCommand {
  int32_t target[kMaxAxes];
};

struct PenCommand {
  bool down;
};

/// Homes the axes in `axes` (bit a: axis a), one after the other in axis
/// order, once everything before it has been executed: each moves towards
/// its endstop (the max end for the axes in `toward_max`, else the min end)
/// at `rate` steps/s until the switch triggers, backs off `backoff` steps,
/// and takes that point as its position 0 (min) or travel_steps (max).
/// The device refuses it with kBadField unless axes ≠ 0 and ⊆ the
/// configured axes, toward_max ⊆ axes, 1 ≤ rate ≤ tick_hz and backoff ≤ the
/// travel of every homed axis; it fails with kHomingFailed (detail = axis)
/// when a switch does not trigger within the axis's travel plus a margin or
/// is still triggered after a back-off other than 0.
struct HomeCommand {
  uint8_t axes;
  uint8_t toward_max;
  uint32_t rate;
  uint32_t backoff;
};

/// Enables (true) or disables the stepper drivers once everything before it
/// has been executed. Disabling forgets homing: the carriage may be moved by
/// hand.
struct MotorsCommand {
  bool enabled;
};

/// A decoded sequenced command.
struct Command {
  MessageType type;
  uint16_t seq;
  union Body {
    Body() : pen{false} {}
    MachineConfig config;
#if FDSURF_DEVICE_PLANNER
    PatchCommand patch;
    CurveCommand curve;
#endif
    PreparedCurveCommand prepared_curve;
    MoveCommand move;
    PenCommand pen;
    HomeCommand home;
    MotorsCommand motors;
  } body;
};

/// Why a frame was refused (kError body), or why a kNak was sent.
enum class ErrorCode : uint8_t {
  kNone = 0,
  kBadLength = 1,           ///< body shorter or longer than its type requires
  kUnknownType = 2,         ///< no such message type
  kBadField = 3,            ///< a field is out of range; `field` says which
  kUnsupportedVersion = 4,  ///< HELLO with another protocol version
  kNotConfigured = 5,       ///< motion command before any kConfig
  kDimsMismatch = 6,        ///< dims differ from the configured axes
  kOutOfTravel = 7,         ///< the path could leave [0, travel_steps]
  kPlannerRefused = 8,      ///< the engine refused it; `detail` is the fdsurf::Status
  kQueueFull = 9,           ///< no credit left (the host overran its window)
  kOutOfOrder = 10,         ///< kNak: a sequence number ahead of the expected one
  kStopped = 11,            ///< a command arrived while a stop was in progress
  kOutputFailed = 12,       ///< a step or pen output failed (status: detail = hal::IoStatus)
  kUnknownSession = 13,     ///< a resume HELLO for a session the device does not have
  kNotHomed = 14,           ///< motion refused: the configuration requires homing first
  kHomingFailed = 15,       ///< an endstop did not trigger (or release); detail = axis
  /// A switch triggered while its axis stepped towards it outside HOME (a
  /// hard limit): the device stopped at once, lifted the pen and forgot
  /// homing. detail = axis, plus kEndstopHitMax for a max switch; STATUS's
  /// position is where the axis stopped (its last step made).
  kEndstopHit = 16,
};

/// kEndstopHit's detail: this bit set for a max switch, clear for a min one.
constexpr uint8_t kEndstopHitMax = 4;

/// A short, stable name ("bad length", ...).
const char* ErrorName(ErrorCode code);

/// Device state in kStatusReport.
enum class DeviceState : uint8_t {
  kIdle = 0,      ///< queue empty, at rest
  kRunning = 1,   ///< executing or about to
  kStopping = 2,  ///< decelerating after kStop
  kFault = 3,     ///< an execution error; `error` says which
  kPaused = 4,    ///< decelerating to, or holding at, a pause (kPause)
  kHoming = 5,    ///< executing a HOME command
};

struct HelloReply {
  uint8_t version;
  /// The sequence number the device expects next (resume point).
  uint16_t next_seq;
  /// Free command slots now, and the queue's capacity.
  uint8_t credits;
  uint8_t queue_capacity;
  /// Motion ticks per second (the step clock); the largest max_rate.
  uint32_t tick_hz;
  /// Axes the device drives; largest grid it evaluates.
  uint8_t max_axes;
  uint16_t max_lines;
  /// kFeature... bits: what the device was built with.
  uint8_t features;
};

/// HelloReply::features: the device reads endstop inputs (HOME can work).
constexpr uint8_t kFeatureEndstops = 0x01;
/// HelloReply::features: the device takes PREPARED_CURVE.
constexpr uint8_t kFeaturePreparedCurves = 0x02;
/// HelloReply::features: the device has the planner (FDSURF_DEVICE_PLANNER)
/// and takes PATCH and CURVE; without it, the host sends PREPARED_CURVEs.
constexpr uint8_t kFeaturePlanner = 0x04;
/// HelloReply::features: the device steps 64-bit tables only
/// (FDSURF_DEVICE_WIDE_TABLES=0, motion/path_generator.h): it refuses a
/// PREPARED_CURVE whose table, relative to its first point, needs the
/// 128-bit accumulator, so the host sends such a line in pieces
/// (host::SplitForSixtyFourBitTables).
constexpr uint8_t kFeature64BitTables = 0x08;
/// HelloReply::features: the device has no turn caps
/// (FDSURF_DEVICE_TURN_CAPS=0, motion/turn_caps.h): with axis limits in its
/// CONFIG it keeps each axis within them by a lower top speed, where no
/// turn could need a cap, instead of slowing on the turns alone (the host
/// says so).
constexpr uint8_t kFeatureNoTurnCaps = 0x10;
/// Every feature bit this version knows; a HELLO_REPLY with another is refused.
constexpr uint8_t kKnownFeatures = kFeatureEndstops | kFeaturePreparedCurves | kFeaturePlanner |
                                   kFeature64BitTables | kFeatureNoTurnCaps;

struct StatusReport {
  DeviceState state;
  ErrorCode error;
  uint8_t error_detail;
  bool pen_down;
  int32_t position[kMaxAxes];
  /// Commands waiting (not yet started) and free slots.
  uint8_t queued;
  uint8_t credits;
  /// The next expected sequence number, and how many sequenced commands have
  /// finished executing since the session began (wraps at 2^32).
  uint16_t next_seq;
  uint32_t executed;
  /// Unit moves (ticks that stepped) since the session began.
  uint32_t moves;
  /// kStatusFlag... bits: motors enabled, axes homed, endstops triggered.
  uint8_t flags;
};

/// StatusReport::flags. Axis a's homed bit is kStatusFlagHomedX << a, its
/// endstop bit (either of its switches triggered now) kStatusFlagEndstopX << a.
constexpr uint8_t kStatusFlagMotorsEnabled = 0x01;
constexpr uint8_t kStatusFlagHomedX = 0x02;
constexpr uint8_t kStatusFlagEndstopX = 0x10;
constexpr uint8_t kStatusKnownFlags = 0x7F;

struct Ack {
  /// Cumulative: every seq before this one is accepted.
  uint16_t next_seq;
  uint8_t credits;
};

struct Nak {
  uint16_t next_seq;
  uint8_t credits;
  ErrorCode reason;
};

/// Every reply's frame seq field echoes the seq (or, for HELLO, STATUS_QUERY
/// STOP, PAUSE, RESUME and HALT, the token) of the frame it answers; ACK, NAK and ERROR bodies
/// carry the fields below.
struct ErrorReply {
  /// The refused frame's sequence number (its token for unsequenced frames);
  /// on the wire this is the frame's seq field, not part of the body.
  uint16_t seq;
  ErrorCode code;
  /// For kBadField the field's index in the body (docs/protocol.md numbers
  /// them); for kPlannerRefused the fdsurf::Status.
  uint8_t detail;
};

}  // namespace protocol
}  // namespace fdsurf
