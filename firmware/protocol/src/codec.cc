// SPDX-License-Identifier: MIT
#include "fdsurf/protocol/codec.h"

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/fixed.h"

namespace fdsurf {
namespace protocol {
namespace {

// ---------------------------------------------------------------- writing

// Writes plain (not COBS-encoded) body bytes, for EncodeCommandBody.
class BodyWriter {
 public:
  BodyWriter(uint8_t* out, size_t capacity) : out_(out), capacity_(capacity) {}
  void Put(uint8_t byte) {
    if (size_ < capacity_) {
      out_[size_] = byte;
    }
    ++size_;  // keeps counting so that Size() reports the overflow
  }
  void PutU16(uint16_t value) {
    Put(static_cast<uint8_t>(value & 0xFFu));
    Put(static_cast<uint8_t>(value >> 8));
  }
  void PutU32(uint32_t value) {
    for (int shift = 0; shift < 32; shift += 8) {
      Put(static_cast<uint8_t>((value >> shift) & 0xFFu));
    }
  }
  void PutVarint(uint64_t value) {
    while (value >= 0x80u) {
      Put(static_cast<uint8_t>((value & 0x7Fu) | 0x80u));
      value >>= 7;
    }
    Put(static_cast<uint8_t>(value));
  }
  void PutSignedVarint(int64_t value) {
    const uint64_t magnitude_twice = static_cast<uint64_t>(value) << 1;
    PutVarint(value < 0 ? ~magnitude_twice : magnitude_twice);
  }
  FDSURF_NODISCARD size_t Size() const { return size_ <= capacity_ ? size_ : 0; }

 private:
  uint8_t* out_;
  size_t capacity_;
  size_t size_ = 0;
};

// How many axes of geometry to write for `dims`: never more than the arrays hold.
int GeometryAxes(uint8_t dims) { return dims < kMaxAxes ? dims : kMaxAxes; }

uint8_t BoolByte(bool value) { return value ? 1 : 0; }

#if FDSURF_DEVICE_PLANNER
template <typename Writer>
void WritePatch(const PatchCommand& p, Writer* w) {
  w->Put(static_cast<uint8_t>(p.basis));
  w->Put(p.dims);
  w->PutU16(p.lines_s);
  w->PutU16(p.lines_t);
  w->PutU32(p.tolerance_q8);
  w->Put(p.skip_lines);
  for (int a = 0; a < GeometryAxes(p.dims); ++a) {
    for (const auto& row : p.geometry[a].g) {
      for (const GeometryFixed value : row) {
        w->PutSignedVarint(value.Raw());
      }
    }
  }
}

template <typename Writer>
void WriteCurve(const CurveCommand& c, Writer* w) {
  w->Put(static_cast<uint8_t>(c.basis));
  w->Put(c.dims);
  w->PutU32(c.tolerance_q8);
  for (int a = 0; a < GeometryAxes(c.dims); ++a) {
    for (const GeometryFixed value : c.geometry[a].g) {
      w->PutSignedVarint(value.Raw());
    }
  }
}
#endif  // FDSURF_DEVICE_PLANNER

template <typename Writer>
void WritePreparedCurve(const PreparedCurveCommand& c, Writer* w) {
  w->Put(c.dims);
  w->Put(c.level);
  w->PutU32(c.tolerance_q8);
  for (int a = 0; a < GeometryAxes(c.dims); ++a) {
    for (const int64_t coefficient : c.power[a].c) {
      w->PutSignedVarint(coefficient);
    }
  }
}

template <typename Writer>
void WriteCommandBody(const Command& command, Writer* w) {
  switch (command.type) {
    case MessageType::kConfig: {
      const MachineConfig& c = command.body.config;
      w->Put(c.axes);
      for (const uint32_t steps : c.steps_per_meter) {
        w->PutU32(steps);
      }
      for (const int32_t travel : c.travel_steps) {
        w->PutU32(static_cast<uint32_t>(travel));
      }
      w->PutU32(c.max_rate);
      w->PutU32(c.accel);
      w->PutU16(c.pen_delay_ms);
      w->PutU32(c.travel_rate);
      for (const uint32_t accel : c.axis_accel) {
        w->PutU32(accel);
      }
      w->PutU16(c.servo_up_us);
      w->PutU16(c.servo_down_us);
      w->Put(c.flags);
      break;
    }
#if FDSURF_DEVICE_PLANNER
    case MessageType::kPatch:
      WritePatch(command.body.patch, w);
      break;
    case MessageType::kCurve:
      WriteCurve(command.body.curve, w);
      break;
#endif
    case MessageType::kPreparedCurve:
      WritePreparedCurve(command.body.prepared_curve, w);
      break;
    case MessageType::kMove:
      for (const int32_t target : command.body.move.target) {
        // A negative target becomes a large varint the decoder refuses.
        w->PutVarint(static_cast<uint32_t>(target));
      }
      break;
    case MessageType::kPen:
      w->Put(BoolByte(command.body.pen.down));
      break;
    case MessageType::kHome: {
      const HomeCommand& h = command.body.home;
      w->Put(h.axes);
      w->Put(h.toward_max);
      w->PutU32(h.rate);
      w->PutU32(h.backoff);
      break;
    }
    case MessageType::kMotors:
      w->Put(BoolByte(command.body.motors.enabled));
      break;
    default:
      break;  // not a command: an empty body the decoder refuses
  }
}

// ---------------------------------------------------------------- reading

// Reads a body field by field; the first failure sticks and names the field.
class Reader {
 public:
  explicit Reader(const Frame& frame) : data_(frame.body), size_(frame.body_size) {}

  FDSURF_NODISCARD bool ok() const { return result_.ok(); }
  DecodeResult result() const { return result_; }

  uint8_t U8(uint8_t field) {
    if (!Need(1, field)) {
      return 0;
    }
    return data_[pos_++];
  }
  uint16_t U16(uint8_t field) {
    if (!Need(2, field)) {
      return 0;
    }
    const uint16_t value =
        static_cast<uint16_t>(static_cast<uint16_t>(data_[pos_ + 1]) << 8 | data_[pos_]);
    pos_ += 2;
    return value;
  }
  uint32_t U32(uint8_t field) {
    if (!Need(4, field)) {
      return 0;
    }
    uint32_t value = 0;
    for (int k = 3; k >= 0; --k) {
      value = value << 8 | data_[pos_ + static_cast<size_t>(k)];
    }
    pos_ += 4;
    return value;
  }
  // LEB128: at most kMaxVarintBytes bytes, no bits beyond 64, and minimal
  // (no trailing 0x00 group), so every value has exactly one encoding.
  uint64_t Varint(uint8_t field) {
    uint64_t value = 0;
    for (int k = 0; k < kMaxVarintBytes; ++k) {
      if (!Need(1, field)) {
        return 0;
      }
      const uint8_t byte = data_[pos_++];
      const uint64_t group = byte & 0x7Fu;
      if (k == kMaxVarintBytes - 1 && group > 1) {
        Fail(ErrorCode::kBadField, field);  // more than 64 bits
        return 0;
      }
      value |= group << (7 * k);
      if ((byte & 0x80u) == 0) {
        if (k > 0 && byte == 0) {
          Fail(ErrorCode::kBadField, field);  // not minimal
          return 0;
        }
        return value;
      }
    }
    Fail(ErrorCode::kBadField, field);  // an 11th byte would follow
    return 0;
  }
  int64_t SignedVarint(uint8_t field) {
    const uint64_t zigzag = Varint(field);
    const int64_t half = static_cast<int64_t>(zigzag >> 1);  // < 2^63
    return (zigzag & 1u) != 0 ? -half - 1 : half;
  }
  // Every byte consumed: else kBadLength naming one past the last field.
  void End(uint8_t field_count) {
    if (ok() && pos_ != size_) {
      Fail(ErrorCode::kBadLength, field_count);
    }
  }
  void Check(bool valid, uint8_t field) {
    if (ok() && !valid) {
      Fail(ErrorCode::kBadField, field);
    }
  }
  void Fail(ErrorCode code, uint8_t field) {
    if (ok()) {
      result_ = DecodeResult{code, field};
    }
  }

 private:
  bool Need(size_t bytes, uint8_t field) {
    if (!ok()) {
      return false;
    }
    if (size_ - pos_ < bytes) {
      Fail(ErrorCode::kBadLength, field);
      return false;
    }
    return true;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  DecodeResult result_ = {ErrorCode::kNone, 0};
};

constexpr DecodeResult kOk{ErrorCode::kNone, 0};

#if FDSURF_DEVICE_PLANNER
bool BasisValid(uint8_t basis) { return basis < kBasisCount; }
#endif
bool DimsValid(uint8_t dims) { return dims >= 2 && dims <= kMaxAxes; }
#if FDSURF_DEVICE_PLANNER
bool LinesValid(uint16_t lines) { return lines == 0 || (lines >= 2 && lines <= kMaxLines); }
#endif

// Both 0 (a plain switch pen) or each a servo pulse width: one encoding of
// "no servo", and no width a servo could be driven to the end stop by.
bool ServoPulseValid(uint16_t us) { return us >= 500 && us <= 2500; }

void ReadServo(Reader* r, MachineConfig* c) {
  c->servo_up_us = r->U16(kConfigFieldServoUp);
  c->servo_down_us = r->U16(kConfigFieldServoDown);
  const bool switch_pen = c->servo_up_us == 0 && c->servo_down_us == 0;
  r->Check(switch_pen || ServoPulseValid(c->servo_up_us), kConfigFieldServoUp);
  r->Check(switch_pen || ServoPulseValid(c->servo_down_us), kConfigFieldServoDown);
}

void ReadConfig(Reader* r, MachineConfig* c) {
  c->axes = r->U8(kConfigFieldAxes);
  r->Check(c->axes >= 2 && c->axes <= kMaxAxes, kConfigFieldAxes);
  for (int a = 0; a < kMaxAxes; ++a) {
    const uint8_t field = static_cast<uint8_t>(kConfigFieldStepsPerMeter + a);
    c->steps_per_meter[a] = r->U32(field);
    // Used axes need a scale; unused ones must be 0 (one encoding per config).
    r->Check(a < c->axes ? c->steps_per_meter[a] > 0 : c->steps_per_meter[a] == 0, field);
  }
  for (int a = 0; a < kMaxAxes; ++a) {
    const uint8_t field = static_cast<uint8_t>(kConfigFieldTravel + a);
    const uint32_t travel = r->U32(field);
    c->travel_steps[a] = static_cast<int32_t>(travel & 0x7FFFFFFFu);
    r->Check(
        a < c->axes ? travel >= 1 && travel <= static_cast<uint32_t>(kMaxTravelSteps) : travel == 0,
        field);
  }
  c->max_rate = r->U32(kConfigFieldMaxRate);
  r->Check(c->max_rate >= 1, kConfigFieldMaxRate);
  c->accel = r->U32(kConfigFieldAccel);
  r->Check(c->accel >= 1, kConfigFieldAccel);
  c->pen_delay_ms = r->U16(kConfigFieldPenDelay);
  c->travel_rate = r->U32(kConfigFieldTravelRate);
  r->Check(c->travel_rate >= 1, kConfigFieldTravelRate);
  for (int a = 0; a < kMaxAxes; ++a) {
    const uint8_t field = static_cast<uint8_t>(kConfigFieldAxisAccel + a);
    c->axis_accel[a] = r->U32(field);
    // Used axes need a limit; unused ones must be 0.
    r->Check(a < c->axes ? c->axis_accel[a] >= 1 : c->axis_accel[a] == 0, field);
  }
  ReadServo(r, c);
  c->flags = r->U8(kConfigFieldFlags);
  r->Check((c->flags & ~kConfigKnownFlags) == 0, kConfigFieldFlags);
  r->End(kConfigFieldCount);
}

// One geometry value of a used axis (zigzag varint, |raw| < the limit), or
// zero for an unused axis (not on the wire).
GeometryFixed ReadGeometry(Reader* r, bool used, uint8_t field) {
  if (!used) {
    return GeometryFixed::FromRaw(0);
  }
  const int64_t raw = r->SignedVarint(field);
  r->Check(GeometryInRange(raw), field);
  return GeometryFixed::FromRaw(raw);
}

#if FDSURF_DEVICE_PLANNER
void ReadPatch(Reader* r, PatchCommand* p) {
  const uint8_t basis = r->U8(kPatchFieldBasis);
  r->Check(BasisValid(basis), kPatchFieldBasis);
  p->basis = static_cast<Basis>(basis);
  p->dims = r->U8(kPatchFieldDims);
  r->Check(DimsValid(p->dims), kPatchFieldDims);
  p->lines_s = r->U16(kPatchFieldLinesS);
  r->Check(LinesValid(p->lines_s), kPatchFieldLinesS);
  p->lines_t = r->U16(kPatchFieldLinesT);
  r->Check(LinesValid(p->lines_t), kPatchFieldLinesT);
  r->Check(p->lines_s != 0 || p->lines_t != 0, kPatchFieldLinesS);
  p->tolerance_q8 = r->U32(kPatchFieldTolerance);
  r->Check(p->tolerance_q8 > 0, kPatchFieldTolerance);
  p->skip_lines = r->U8(kPatchFieldSkipLines);
  r->Check((p->skip_lines & ~kSkipLinesMask) == 0, kPatchFieldSkipLines);
  const int axes = r->ok() ? p->dims : 0;
  uint8_t field = kPatchFieldGeometry;
  for (int a = 0; a < kMaxAxes; ++a) {
    for (auto& row : p->geometry[a].g) {
      for (GeometryFixed& value : row) {
        value = ReadGeometry(r, a < axes, field++);
      }
    }
  }
  r->End(static_cast<uint8_t>(kPatchFieldGeometry + 16 * axes));
}

void ReadCurve(Reader* r, CurveCommand* c) {
  const uint8_t basis = r->U8(kCurveFieldBasis);
  r->Check(BasisValid(basis), kCurveFieldBasis);
  c->basis = static_cast<Basis>(basis);
  c->dims = r->U8(kCurveFieldDims);
  r->Check(DimsValid(c->dims), kCurveFieldDims);
  c->tolerance_q8 = r->U32(kCurveFieldTolerance);
  r->Check(c->tolerance_q8 > 0, kCurveFieldTolerance);
  const int axes = r->ok() ? c->dims : 0;
  uint8_t field = kCurveFieldGeometry;
  for (int a = 0; a < kMaxAxes; ++a) {
    for (GeometryFixed& value : c->geometry[a].g) {
      value = ReadGeometry(r, a < axes, field++);
    }
  }
  r->End(static_cast<uint8_t>(kCurveFieldGeometry + 4 * axes));
}

#endif  // FDSURF_DEVICE_PLANNER

// The power coefficients are in the geometry's range (|raw| < 2^47), as
// CurvePowerCoefficients and the isoline walker produce them; the level is
// one the planner can choose. Whether the level meets the tolerance is the
// device's check (PrepareAdaptiveCurveAtLevel), not the codec's.
void ReadPreparedCurve(Reader* r, PreparedCurveCommand* c) {
  c->dims = r->U8(kPreparedCurveFieldDims);
  r->Check(DimsValid(c->dims), kPreparedCurveFieldDims);
  c->level = r->U8(kPreparedCurveFieldLevel);
  r->Check(c->level <= kMaxAdaptiveLevel, kPreparedCurveFieldLevel);
  c->tolerance_q8 = r->U32(kPreparedCurveFieldTolerance);
  r->Check(c->tolerance_q8 > 0, kPreparedCurveFieldTolerance);
  const int axes = r->ok() ? c->dims : 0;
  uint8_t field = kPreparedCurveFieldPower;
  for (int a = 0; a < kMaxAxes; ++a) {
    for (int64_t& coefficient : c->power[a].c) {
      coefficient = a < axes ? ReadGeometry(r, true, field).Raw() : 0;
      ++field;
    }
  }
  r->End(static_cast<uint8_t>(kPreparedCurveFieldPower + 4 * axes));
}

void ReadMove(Reader* r, MoveCommand* m) {
  for (int a = 0; a < kMaxAxes; ++a) {
    const uint8_t field = static_cast<uint8_t>(kMoveFieldTarget + a);
    const uint64_t target = r->Varint(field);
    r->Check(target <= static_cast<uint64_t>(kMaxTravelSteps), field);
    m->target[a] = static_cast<int32_t>(target & static_cast<uint64_t>(kMaxTravelSteps));
  }
  r->End(kMoveFieldCount);
}

void ReadPen(Reader* r, PenCommand* p) {
  const uint8_t down = r->U8(kPenFieldDown);
  r->Check(down <= 1, kPenFieldDown);
  p->down = down == 1;
  r->End(kPenFieldCount);
}

// The axis mask must name at least one axis and none beyond kMaxAxes; the
// device checks it against its configuration.
void ReadHome(Reader* r, HomeCommand* h) {
  constexpr uint8_t kAxisBits = (1u << kMaxAxes) - 1u;
  h->axes = r->U8(kHomeFieldAxes);
  r->Check(h->axes != 0 && (h->axes & ~kAxisBits) == 0, kHomeFieldAxes);
  h->toward_max = r->U8(kHomeFieldTowardMax);
  r->Check((h->toward_max & ~h->axes) == 0, kHomeFieldTowardMax);
  h->rate = r->U32(kHomeFieldRate);
  r->Check(h->rate >= 1, kHomeFieldRate);
  h->backoff = r->U32(kHomeFieldBackoff);
  r->Check(h->backoff <= static_cast<uint32_t>(kMaxTravelSteps), kHomeFieldBackoff);
  r->End(kHomeFieldCount);
}

void ReadMotors(Reader* r, MotorsCommand* m) {
  const uint8_t enabled = r->U8(kMotorsFieldEnabled);
  r->Check(enabled <= 1, kMotorsFieldEnabled);
  m->enabled = enabled == 1;
  r->End(kMotorsFieldCount);
}

bool ErrorCodeValid(uint8_t code) { return code <= kLastErrorCode; }

bool DeviceStateValid(uint8_t state) { return state <= static_cast<uint8_t>(DeviceState::kHoming); }

}  // namespace

// ---------------------------------------------------------------- encoding

size_t EncodeCommandBody(const Command& command, uint8_t* body, size_t capacity) {
  BodyWriter writer(body, capacity);
  WriteCommandBody(command, &writer);
  return writer.Size();
}

size_t EncodeCommand(const Command& command, uint8_t* out, size_t capacity, uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(command.type), command.seq, session);
  WriteCommandBody(command, &encoder);
  return encoder.Finish();
}

size_t EncodeFrame(MessageType type, uint16_t seq, const uint8_t* body, size_t body_size,
                   uint8_t* out, size_t capacity, uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(type), seq, session);
  for (size_t i = 0; i < body_size; ++i) {
    encoder.Put(body[i]);
  }
  return encoder.Finish();
}

size_t EncodeHello(uint16_t token, const Hello& hello, uint8_t* out, size_t capacity) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(MessageType::kHello), token);
  encoder.Put(hello.version);
  encoder.Put(hello.flags);
  encoder.PutU32(hello.session);
  return encoder.Finish();
}

size_t EncodeStatusQuery(uint16_t token, uint8_t* out, size_t capacity, uint32_t session) {
  return EncodeFrame(MessageType::kStatusQuery, token, nullptr, 0, out, capacity, session);
}

size_t EncodeStop(uint16_t token, uint8_t* out, size_t capacity, uint32_t session) {
  return EncodeFrame(MessageType::kStop, token, nullptr, 0, out, capacity, session);
}

size_t EncodePause(uint16_t token, uint8_t* out, size_t capacity, uint32_t session) {
  return EncodeFrame(MessageType::kPause, token, nullptr, 0, out, capacity, session);
}

size_t EncodeResume(uint16_t token, uint8_t* out, size_t capacity, uint32_t session) {
  return EncodeFrame(MessageType::kResume, token, nullptr, 0, out, capacity, session);
}

size_t EncodeHalt(uint16_t token, uint8_t* out, size_t capacity, uint32_t session) {
  return EncodeFrame(MessageType::kHalt, token, nullptr, 0, out, capacity, session);
}

size_t EncodeHelloReply(uint16_t token, const HelloReply& reply, uint8_t* out, size_t capacity,
                        uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(MessageType::kHelloReply), token, session);
  encoder.Put(reply.version);
  encoder.PutU16(reply.next_seq);
  encoder.Put(reply.credits);
  encoder.Put(reply.queue_capacity);
  encoder.PutU32(reply.tick_hz);
  encoder.Put(reply.max_axes);
  encoder.PutU16(reply.max_lines);
  encoder.Put(reply.features);
  return encoder.Finish();
}

size_t EncodeStatusReport(uint16_t token, const StatusReport& report, uint8_t* out, size_t capacity,
                          uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(MessageType::kStatusReport), token, session);
  encoder.Put(static_cast<uint8_t>(report.state));
  encoder.Put(static_cast<uint8_t>(report.error));
  encoder.Put(report.error_detail);
  encoder.Put(BoolByte(report.pen_down));
  for (const int32_t position : report.position) {
    encoder.PutU32(static_cast<uint32_t>(position));
  }
  encoder.Put(report.queued);
  encoder.Put(report.credits);
  encoder.PutU16(report.next_seq);
  encoder.PutU32(report.executed);
  encoder.PutU32(report.moves);
  encoder.Put(report.flags);
  return encoder.Finish();
}

size_t EncodeAck(uint16_t seq, const Ack& ack, uint8_t* out, size_t capacity, uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(MessageType::kAck), seq, session);
  encoder.PutU16(ack.next_seq);
  encoder.Put(ack.credits);
  return encoder.Finish();
}

size_t EncodeNak(uint16_t seq, const Nak& nak, uint8_t* out, size_t capacity, uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(MessageType::kNak), seq, session);
  encoder.PutU16(nak.next_seq);
  encoder.Put(nak.credits);
  encoder.Put(static_cast<uint8_t>(nak.reason));
  return encoder.Finish();
}

size_t EncodeError(const ErrorReply& error, uint8_t* out, size_t capacity, uint32_t session) {
  FrameEncoder encoder(out, capacity);
  encoder.Begin(static_cast<uint8_t>(MessageType::kError), error.seq, session);
  encoder.Put(static_cast<uint8_t>(error.code));
  encoder.Put(error.detail);
  return encoder.Finish();
}

// ---------------------------------------------------------------- decoding

DecodeResult DecodeCommand(const Frame& frame, Command* out) {
  const MessageType type = static_cast<MessageType>(frame.type);
  out->type = type;
  out->seq = frame.seq;
  Reader reader(frame);
  switch (type) {
    case MessageType::kConfig:
      ReadConfig(&reader, &out->body.config);
      break;
#if FDSURF_DEVICE_PLANNER
    case MessageType::kPatch:
      ReadPatch(&reader, &out->body.patch);
      break;
    case MessageType::kCurve:
      ReadCurve(&reader, &out->body.curve);
      break;
#endif
    case MessageType::kPreparedCurve:
      ReadPreparedCurve(&reader, &out->body.prepared_curve);
      break;
    case MessageType::kMove:
      ReadMove(&reader, &out->body.move);
      break;
    case MessageType::kPen:
      ReadPen(&reader, &out->body.pen);
      break;
    case MessageType::kHome:
      ReadHome(&reader, &out->body.home);
      break;
    case MessageType::kMotors:
      ReadMotors(&reader, &out->body.motors);
      break;
    default:
      return DecodeResult{ErrorCode::kUnknownType, 0};
  }
  return reader.result();
}

DecodeResult ValidateFields(const Command& command) {
  if (!IsSequenced(command.type)) {
    return DecodeResult{ErrorCode::kUnknownType, 0};
  }
  uint8_t body[kMaxBodyBytes];
  const size_t size = EncodeCommandBody(command, body, sizeof body);
  if (size == 0) {
    return DecodeResult{ErrorCode::kBadLength, 0};
  }
  const Frame frame{static_cast<uint8_t>(command.type), command.seq, body, size, true};
  Command decoded;
  return DecodeCommand(frame, &decoded);
}

DecodeResult DecodeHello(const Frame& frame, Hello* out) {
  if (frame.body_size >= 1 && frame.body[0] != kProtocolVersion) {
    out->version = frame.body[0];
    out->flags = 0;
    out->session = 0;
    return DecodeResult{ErrorCode::kUnsupportedVersion, kHelloFieldVersion};
  }
  Reader reader(frame);
  out->version = reader.U8(kHelloFieldVersion);
  out->flags = reader.U8(kHelloFieldFlags);
  reader.Check((out->flags & ~kHelloKnownFlags) == 0, kHelloFieldFlags);
  out->session = reader.U32(kHelloFieldSession);
  reader.Check(out->session != 0, kHelloFieldSession);
  reader.End(kHelloFieldCount);
  return reader.result();
}

DecodeResult DecodeEmpty(const Frame& frame) {
  return frame.body_size == 0 ? kOk : DecodeResult{ErrorCode::kBadLength, 0};
}

DecodeResult DecodeReply(const Frame& frame, Reply* out) {
  const MessageType type = static_cast<MessageType>(frame.type);
  out->type = type;
  out->seq = frame.seq;
  Reader r(frame);
  switch (type) {
    case MessageType::kHelloReply: {
      HelloReply& h = out->body.hello;
      h.version = r.U8(kHelloReplyFieldVersion);
      h.next_seq = r.U16(kHelloReplyFieldNextSeq);
      h.credits = r.U8(kHelloReplyFieldCredits);
      h.queue_capacity = r.U8(kHelloReplyFieldQueueCapacity);
      r.Check(h.queue_capacity >= 1, kHelloReplyFieldQueueCapacity);
      r.Check(h.credits <= h.queue_capacity, kHelloReplyFieldCredits);
      h.tick_hz = r.U32(kHelloReplyFieldTickHz);
      r.Check(h.tick_hz >= 1, kHelloReplyFieldTickHz);
      h.max_axes = r.U8(kHelloReplyFieldMaxAxes);
      r.Check(DimsValid(h.max_axes), kHelloReplyFieldMaxAxes);
      h.max_lines = r.U16(kHelloReplyFieldMaxLines);
      r.Check(h.max_lines >= 2, kHelloReplyFieldMaxLines);
      h.features = r.U8(kHelloReplyFieldFeatures);
      r.Check((h.features & ~kKnownFeatures) == 0, kHelloReplyFieldFeatures);
      r.End(kHelloReplyFieldCount);
      break;
    }
    case MessageType::kStatusReport: {
      StatusReport& s = out->body.status;
      const uint8_t state = r.U8(kStatusFieldState);
      r.Check(DeviceStateValid(state), kStatusFieldState);
      s.state = static_cast<DeviceState>(state);
      const uint8_t error = r.U8(kStatusFieldError);
      r.Check(ErrorCodeValid(error), kStatusFieldError);
      s.error = static_cast<ErrorCode>(error);
      s.error_detail = r.U8(kStatusFieldErrorDetail);
      const uint8_t pen = r.U8(kStatusFieldPenDown);
      r.Check(pen <= 1, kStatusFieldPenDown);
      s.pen_down = pen == 1;
      for (int a = 0; a < kMaxAxes; ++a) {
        s.position[a] = static_cast<int32_t>(r.U32(static_cast<uint8_t>(kStatusFieldPosition + a)));
      }
      s.queued = r.U8(kStatusFieldQueued);
      s.credits = r.U8(kStatusFieldCredits);
      s.next_seq = r.U16(kStatusFieldNextSeq);
      s.executed = r.U32(kStatusFieldExecuted);
      s.moves = r.U32(kStatusFieldMoves);
      s.flags = r.U8(kStatusFieldFlags);
      r.Check((s.flags & ~kStatusKnownFlags) == 0, kStatusFieldFlags);
      r.End(kStatusFieldCount);
      break;
    }
    case MessageType::kAck:
      out->body.ack.next_seq = r.U16(kAckFieldNextSeq);
      out->body.ack.credits = r.U8(kAckFieldCredits);
      r.End(kAckFieldCount);
      break;
    case MessageType::kNak: {
      Nak& n = out->body.nak;
      n.next_seq = r.U16(kNakFieldNextSeq);
      n.credits = r.U8(kNakFieldCredits);
      const uint8_t reason = r.U8(kNakFieldReason);
      r.Check(reason != 0 && ErrorCodeValid(reason), kNakFieldReason);
      n.reason = static_cast<ErrorCode>(reason);
      r.End(kNakFieldCount);
      break;
    }
    case MessageType::kError: {
      ErrorReply& e = out->body.error;
      e.seq = frame.seq;
      const uint8_t code = r.U8(kErrorFieldCode);
      r.Check(code != 0 && ErrorCodeValid(code), kErrorFieldCode);
      e.code = static_cast<ErrorCode>(code);
      e.detail = r.U8(kErrorFieldDetail);
      r.End(kErrorFieldCount);
      break;
    }
    default:
      return DecodeResult{ErrorCode::kUnknownType, 0};
  }
  return r.result();
}

const char* ErrorName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kNone:
      return "none";
    case ErrorCode::kBadLength:
      return "bad length";
    case ErrorCode::kUnknownType:
      return "unknown type";
    case ErrorCode::kBadField:
      return "bad field";
    case ErrorCode::kUnsupportedVersion:
      return "unsupported version";
    case ErrorCode::kNotConfigured:
      return "not configured";
    case ErrorCode::kDimsMismatch:
      return "dims mismatch";
    case ErrorCode::kOutOfTravel:
      return "out of travel";
    case ErrorCode::kPlannerRefused:
      return "planner refused";
    case ErrorCode::kQueueFull:
      return "queue full";
    case ErrorCode::kOutOfOrder:
      return "out of order";
    case ErrorCode::kStopped:
      return "stopped";
    case ErrorCode::kOutputFailed:
      return "output failed";
    case ErrorCode::kUnknownSession:
      return "unknown session";
    case ErrorCode::kNotHomed:
      return "not homed";
    case ErrorCode::kHomingFailed:
      return "homing failed";
    case ErrorCode::kEndstopHit:
      return "endstop hit";
  }
  return "unknown error";
}

}  // namespace protocol
}  // namespace fdsurf
