// SPDX-License-Identifier: MIT
// Encoding and validating decoding of every message in messages.h.
//
// Bodies are little-endian. Geometry values (Q47.16 raw) are zigzag LEB128
// varints, move targets unsigned LEB128 varints; docs/protocol.md has the
// body of every message, field by field, with the index each field has in
// DecodeResult::field.
//
// Decoding validates every field and the exact body length; on failure it
// returns the ErrorCode and the field's index and leaves no partial state
// the caller could act on (the output is unspecified; check the result).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/protocol/frame.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf {
namespace protocol {

/// Largest number of bytes of one varint: ceil(64 / 7).
constexpr int kMaxVarintBytes = 10;
/// Largest travel (and move target) in steps: 2^30 - 1.
constexpr int32_t kMaxTravelSteps = (int32_t{1} << 30) - 1;
/// Largest isoline count of a patch: a grid of kMaxPatchSteps steps has
/// kMaxPatchSteps + 1 lines.
constexpr uint16_t kMaxLines = kMaxPatchSteps + 1;
/// The largest ErrorCode value this version defines.
constexpr uint8_t kLastErrorCode = static_cast<uint8_t>(ErrorCode::kEndstopHit);

/// Field indices (DecodeResult::field and ErrorReply::detail for kBadField).
/// For kBadLength the index is that of the field cut short, or the number of
/// fields of the body when bytes are left over after the last one.
// kHello
constexpr uint8_t kHelloFieldVersion = 0;
constexpr uint8_t kHelloFieldFlags = 1;
constexpr uint8_t kHelloFieldSession = 2;
constexpr uint8_t kHelloFieldCount = 3;
// kConfig: per-axis fields take 3 consecutive indices (X, Y, Z).
constexpr uint8_t kConfigFieldAxes = 0;
constexpr uint8_t kConfigFieldStepsPerMeter = 1;  // 1..3
constexpr uint8_t kConfigFieldTravel = 4;         // 4..6
constexpr uint8_t kConfigFieldMaxRate = 7;
constexpr uint8_t kConfigFieldAccel = 8;
constexpr uint8_t kConfigFieldPenDelay = 9;
constexpr uint8_t kConfigFieldTravelRate = 10;
constexpr uint8_t kConfigFieldAxisAccel = 11;  // 11..13
constexpr uint8_t kConfigFieldServoUp = 14;
constexpr uint8_t kConfigFieldServoDown = 15;
constexpr uint8_t kConfigFieldFlags = 16;
constexpr uint8_t kConfigFieldCount = 17;
// kPatch: geometry[axis].g[i][j] is field kPatchFieldGeometry + 16·axis + 4·i + j.
constexpr uint8_t kPatchFieldBasis = 0;
constexpr uint8_t kPatchFieldDims = 1;
constexpr uint8_t kPatchFieldLinesS = 2;
constexpr uint8_t kPatchFieldLinesT = 3;
constexpr uint8_t kPatchFieldTolerance = 4;
constexpr uint8_t kPatchFieldSkipLines = 5;
constexpr uint8_t kPatchFieldGeometry = 6;
// kCurve: geometry[axis].g[i] is field kCurveFieldGeometry + 4·axis + i.
constexpr uint8_t kCurveFieldBasis = 0;
constexpr uint8_t kCurveFieldDims = 1;
constexpr uint8_t kCurveFieldTolerance = 2;
constexpr uint8_t kCurveFieldGeometry = 3;
// kPreparedCurve: power[axis].c[k] is field kPreparedCurveFieldPower + 4·axis + k.
constexpr uint8_t kPreparedCurveFieldDims = 0;
constexpr uint8_t kPreparedCurveFieldLevel = 1;
constexpr uint8_t kPreparedCurveFieldTolerance = 2;
constexpr uint8_t kPreparedCurveFieldPower = 3;
// kMove: target[axis] is field axis.
constexpr uint8_t kMoveFieldTarget = 0;
constexpr uint8_t kMoveFieldCount = 3;
// kPen
constexpr uint8_t kPenFieldDown = 0;
constexpr uint8_t kPenFieldCount = 1;
// kHome
constexpr uint8_t kHomeFieldAxes = 0;
constexpr uint8_t kHomeFieldTowardMax = 1;
constexpr uint8_t kHomeFieldRate = 2;
constexpr uint8_t kHomeFieldBackoff = 3;
constexpr uint8_t kHomeFieldCount = 4;
// kMotors
constexpr uint8_t kMotorsFieldEnabled = 0;
constexpr uint8_t kMotorsFieldCount = 1;
// kHelloReply
constexpr uint8_t kHelloReplyFieldVersion = 0;
constexpr uint8_t kHelloReplyFieldNextSeq = 1;
constexpr uint8_t kHelloReplyFieldCredits = 2;
constexpr uint8_t kHelloReplyFieldQueueCapacity = 3;
constexpr uint8_t kHelloReplyFieldTickHz = 4;
constexpr uint8_t kHelloReplyFieldMaxAxes = 5;
constexpr uint8_t kHelloReplyFieldMaxLines = 6;
constexpr uint8_t kHelloReplyFieldFeatures = 7;
constexpr uint8_t kHelloReplyFieldCount = 8;
// kStatusReport: position[axis] is field kStatusFieldPosition + axis.
constexpr uint8_t kStatusFieldState = 0;
constexpr uint8_t kStatusFieldError = 1;
constexpr uint8_t kStatusFieldErrorDetail = 2;
constexpr uint8_t kStatusFieldPenDown = 3;
constexpr uint8_t kStatusFieldPosition = 4;  // 4..6
constexpr uint8_t kStatusFieldQueued = 7;
constexpr uint8_t kStatusFieldCredits = 8;
constexpr uint8_t kStatusFieldNextSeq = 9;
constexpr uint8_t kStatusFieldExecuted = 10;
constexpr uint8_t kStatusFieldMoves = 11;
constexpr uint8_t kStatusFieldFlags = 12;
constexpr uint8_t kStatusFieldCount = 13;
// kAck
constexpr uint8_t kAckFieldNextSeq = 0;
constexpr uint8_t kAckFieldCredits = 1;
constexpr uint8_t kAckFieldCount = 2;
// kNak
constexpr uint8_t kNakFieldNextSeq = 0;
constexpr uint8_t kNakFieldCredits = 1;
constexpr uint8_t kNakFieldReason = 2;
constexpr uint8_t kNakFieldCount = 3;
// kError
constexpr uint8_t kErrorFieldCode = 0;
constexpr uint8_t kErrorFieldDetail = 1;
constexpr uint8_t kErrorFieldCount = 2;

/// The outcome of decoding: kNone, or why and where the body was refused.
/// [[nodiscard]] (FDSURF_NODISCARD): a dropped result lets a refused body through.
struct FDSURF_NODISCARD DecodeResult {
  ErrorCode code;
  uint8_t field;
  FDSURF_NODISCARD constexpr bool ok() const { return code == ErrorCode::kNone; }
};

/// A decoded device → host message. `seq` is the frame's seq field: the
/// seq or token of the frame it answers.
struct Reply {
  MessageType type;
  uint16_t seq;
  union Body {
    Body() : ack{0, 0} {}
    HelloReply hello;
    StatusReport status;
    Ack ack;
    Nak nak;
    ErrorReply error;
  } body;
};

// ---- Encoding. Each writes one complete wire frame (COBS and delimiter
// included) into `out` and returns its size, or 0 if it does not fit in
// `capacity` (kMaxEncodedFrameBytes always fits). Encoding does not validate:
// `session`: the session whose tag the CRC carries (frame.h); 0, the plain
// CRC, is for HELLO only (EncodeHello always uses it).
// the encoders write whatever the struct holds (dims beyond kMaxAxes are
// clamped when choosing how much geometry to write, so they never read
// outside the arrays), and the decoder refuses what is out of range.

size_t EncodeCommand(const Command& command, uint8_t* out, size_t capacity, uint32_t session = 0);
/// Only the body of a command (no type, seq, CRC or COBS) into `body`.
/// Returns the body size, or 0 if it does not fit (no body is empty).
size_t EncodeCommandBody(const Command& command, uint8_t* body, size_t capacity);
/// A frame of `type` and `seq` around an already encoded body.
size_t EncodeFrame(MessageType type, uint16_t seq, const uint8_t* body, size_t body_size,
                   uint8_t* out, size_t capacity, uint32_t session = 0);
size_t EncodeHello(uint16_t token, const Hello& hello, uint8_t* out, size_t capacity);
size_t EncodeStatusQuery(uint16_t token, uint8_t* out, size_t capacity, uint32_t session = 0);
size_t EncodeStop(uint16_t token, uint8_t* out, size_t capacity, uint32_t session = 0);
/// kPause, kResume, kHalt (empty bodies, like kStop).
size_t EncodePause(uint16_t token, uint8_t* out, size_t capacity, uint32_t session = 0);
size_t EncodeResume(uint16_t token, uint8_t* out, size_t capacity, uint32_t session = 0);
size_t EncodeHalt(uint16_t token, uint8_t* out, size_t capacity, uint32_t session = 0);
size_t EncodeHelloReply(uint16_t token, const HelloReply& reply, uint8_t* out, size_t capacity,
                        uint32_t session = 0);
size_t EncodeStatusReport(uint16_t token, const StatusReport& report, uint8_t* out, size_t capacity,
                          uint32_t session = 0);
/// `seq`: the seq or token of the frame acknowledged.
size_t EncodeAck(uint16_t seq, const Ack& ack, uint8_t* out, size_t capacity, uint32_t session = 0);
size_t EncodeNak(uint16_t seq, const Nak& nak, uint8_t* out, size_t capacity, uint32_t session = 0);
/// The frame's seq field is `error.seq`.
size_t EncodeError(const ErrorReply& error, uint8_t* out, size_t capacity, uint32_t session = 0);

// ---- Decoding. All take a CRC-checked frame from FrameDecoder.

/// A sequenced command (kConfig..kMotors). Errors: kUnknownType (not a known
/// sequenced type), kBadLength, kBadField. out->type and out->seq are the
/// frame's. Geometry of unused axes is zeroed.
DecodeResult DecodeCommand(const Frame& frame, Command* out);
/// Validates the fields of a command struct exactly as DecodeCommand would after a round
/// trip (the host checks what it sends before it sends it). Uses about 1 KB
/// of stack (a body buffer and a Command): meant for the host, not a device.
DecodeResult ValidateFields(const Command& command);
/// kHello. A first byte other than kProtocolVersion gives
/// kUnsupportedVersion (field 0) whatever follows, so later versions may
/// change the rest of the body; else kBadLength, kBadField (unknown flags,
/// session 0).
DecodeResult DecodeHello(const Frame& frame, Hello* out);
/// kStatusQuery, kStop, kPause, kResume and kHalt: the body must be empty (kBadLength, field 0).
DecodeResult DecodeEmpty(const Frame& frame);
/// Any device → host message. Errors: kUnknownType, kBadLength, kBadField.
DecodeResult DecodeReply(const Frame& frame, Reply* out);

}  // namespace protocol
}  // namespace fdsurf
