// SPDX-License-Identifier: MIT
// Message codec of the device protocol: round trips, every validation
// refusal with its documented field index, the worked example of
// docs/protocol.md, and a fuzz of the decoders with CRC-valid random bodies.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/frame.h"

namespace fdsurf::protocol {
namespace {

using Bytes = std::vector<uint8_t>;

// Decodes one wire frame (delimiter included) into a Frame whose body lives
// in `storage`.
Frame Unwire(const Bytes& wire, Bytes* storage) {
  storage->assign(kMaxFrameBytes, 0);
  FrameDecoder decoder(storage->data(), storage->size());
  Frame frame{};
  int frames = 0;
  for (uint8_t b : wire) {
    if (decoder.OnByte(b)) {
      frame = decoder.frame();
      ++frames;
    }
  }
  EXPECT_EQ(frames, 1);
  return frame;
}

Bytes Wire(const Command& command) {
  Bytes out(kMaxEncodedFrameBytes);
  out.resize(EncodeCommand(command, out.data(), out.size()));
  return out;
}

// A frame with the command's type and seq around an arbitrary body.
Frame BodyFrame(MessageType type, const Bytes& body) {
  return Frame{static_cast<uint8_t>(type), 0, body.data(), body.size(), true};
}

Bytes CommandBody(const Command& command) {
  Bytes body(kMaxBodyBytes);
  body.resize(EncodeCommandBody(command, body.data(), body.size()));
  return body;
}

Command Config() {
  Command c;
  c.type = MessageType::kConfig;
  c.seq = 0;
  c.body.config = MachineConfig{
      2, {80000, 80000, 0}, {16000, 12000, 0}, 4000, 20000, 150, 6000, {30000, 25000, 0}, 0, 0, 0};
  return c;
}

Command Patch(uint8_t dims, uint64_t salt) {
  Command c;
  c.type = MessageType::kPatch;
  c.seq = 7;
  PatchCommand& p = c.body.patch;
  p = PatchCommand{};
  p.basis = Basis::kBezier;
  p.dims = dims;
  p.lines_s = 9;
  p.lines_t = 0;
  p.tolerance_q8 = 13;
  p.skip_lines = static_cast<uint8_t>(salt & kSkipLinesMask);
  std::mt19937_64 rng(salt);
  for (int a = 0; a < dims; ++a) {
    for (auto& row : p.geometry[a].g) {
      for (GeometryFixed& value : row) {
        const int64_t raw =
            static_cast<int64_t>(rng() % (2 * static_cast<uint64_t>(kGeometryLimitRaw) - 1)) -
            (kGeometryLimitRaw - 1);
        value = GeometryFixed::FromRaw(raw);
      }
    }
  }
  return c;
}

Command Curve(uint8_t dims) {
  Command c;
  c.type = MessageType::kCurve;
  c.seq = 0xFFFF;
  CurveCommand& k = c.body.curve;
  k = CurveCommand{};
  k.basis = Basis::kCatmullRom;
  k.dims = dims;
  k.tolerance_q8 = 1000;
  for (int a = 0; a < dims; ++a) {
    for (int i = 0; i < 4; ++i) {
      k.geometry[a].g[i] = GeometryFixed::FromRaw((a * 4 + i - 5) * 123456789LL);
    }
  }
  return c;
}

Command Prepared(uint8_t dims) {
  Command c;
  c.type = MessageType::kPreparedCurve;
  c.seq = 0x1234;
  PreparedCurveCommand& k = c.body.prepared_curve;
  k = PreparedCurveCommand{};
  k.dims = dims;
  k.level = 12;
  k.tolerance_q8 = 300;
  for (int a = 0; a < dims; ++a) {
    for (int i = 0; i < 4; ++i) k.power[a].c[i] = (a * 4 + i - 5) * 987654321LL;
  }
  return c;
}

Command Move(int32_t x, int32_t y, int32_t z) {
  Command c;
  c.type = MessageType::kMove;
  c.seq = 3;
  c.body.move = MoveCommand{{x, y, z}};
  return c;
}

Command Pen(bool down) {
  Command c;
  c.type = MessageType::kPen;
  c.seq = 4;
  c.body.pen.down = down;
  return c;
}

Command Home(uint8_t axes, uint8_t toward_max, uint32_t rate, uint32_t backoff) {
  Command c;
  c.type = MessageType::kHome;
  c.seq = 5;
  c.body.home = HomeCommand{axes, toward_max, rate, backoff};
  return c;
}

Command Motors(bool enabled) {
  Command c;
  c.type = MessageType::kMotors;
  c.seq = 6;
  c.body.motors.enabled = enabled;
  return c;
}

// Round trip through the wire; the decoded command re-encodes to the same
// body (a byte-exact comparison of every field that is sent).
void ExpectRoundTrip(const Command& command) {
  Bytes storage;
  const Bytes wire = Wire(command);
  ASSERT_FALSE(wire.empty());
  const Frame frame = Unwire(wire, &storage);
  Command decoded;
  const DecodeResult result = DecodeCommand(frame, &decoded);
  ASSERT_TRUE(result.ok()) << ErrorName(result.code) << " field " << int{result.field};
  EXPECT_EQ(decoded.type, command.type);
  EXPECT_EQ(decoded.seq, command.seq);
  EXPECT_EQ(CommandBody(decoded), CommandBody(command));
  EXPECT_TRUE(ValidateFields(command).ok());
}

TEST(Codec, CommandRoundTrips) {
  ExpectRoundTrip(Config());
  Command config3 = Config();
  config3.body.config.axes = 3;
  config3.body.config.steps_per_meter[2] = 400000;
  config3.body.config.travel_steps[2] = kMaxTravelSteps;
  config3.body.config.axis_accel[2] = 0xFFFFFFFFu;
  ExpectRoundTrip(config3);
  Command servo = Config();
  servo.body.config.servo_up_us = 1200;
  servo.body.config.servo_down_us = 1850;
  ExpectRoundTrip(servo);
  // The widths on the wire, after axis_accel: u16 little-endian each, then flags.
  const Bytes servo_body = CommandBody(servo);
  ASSERT_EQ(servo_body.size(), 56u);
  EXPECT_EQ(Bytes(servo_body.end() - 5, servo_body.end() - 1), (Bytes{0xB0, 0x04, 0x3A, 0x07}));
  for (uint64_t salt = 0; salt < 50; ++salt) {
    ExpectRoundTrip(Patch(2, salt));
    ExpectRoundTrip(Patch(3, salt));
  }
  ExpectRoundTrip(Curve(2));
  ExpectRoundTrip(Curve(3));
  ExpectRoundTrip(Prepared(2));
  ExpectRoundTrip(Prepared(3));
  Command extremes = Prepared(3);
  extremes.body.prepared_curve.level = kMaxAdaptiveLevel;
  extremes.body.prepared_curve.power[2].c[0] = kGeometryLimitRaw - 1;
  extremes.body.prepared_curve.power[2].c[1] = -(kGeometryLimitRaw - 1);
  ExpectRoundTrip(extremes);
  // dims, level, tolerance (u32), then 4 zigzag varints per axis.
  const Bytes prepared_body = CommandBody(Prepared(2));
  EXPECT_EQ(Bytes(prepared_body.begin(), prepared_body.begin() + 6),
            (Bytes{2, 12, 0x2C, 0x01, 0, 0}));
  ExpectRoundTrip(Move(0, 0, 0));
  ExpectRoundTrip(Move(kMaxTravelSteps, 1, 127));
  ExpectRoundTrip(Pen(true));
  ExpectRoundTrip(Pen(false));
  Command homing_required = Config();
  homing_required.body.config.flags = kConfigFlagHomingRequired;
  ExpectRoundTrip(homing_required);
  ExpectRoundTrip(Home(0x01, 0, 1, 0));
  ExpectRoundTrip(Home(0x07, 0x05, 0xFFFFFFFFu, static_cast<uint32_t>(kMaxTravelSteps)));
  ExpectRoundTrip(Motors(true));
  ExpectRoundTrip(Motors(false));
}

// HOME is axes u8, toward_max u8, rate u32, backoff u32 (10 bytes); MOTORS
// one byte; CONFIG's flags byte is its last (after the servo widths).
// The largest frame of each command a device without the planner takes,
// every field at its widest: all fit kMaxPreparedFrameBytes, the size such a
// device may give its frame buffer, and the largest is a 3-D PREPARED_CURVE.
TEST(Codec, EveryCommandButPatchAndCurveFitsTheSmallFrame) {
  constexpr int64_t kWidest = -((int64_t{1} << 47) - 1);  // zigzag 2^48 - 3: 7 bytes
  Command prepared = Prepared(3);
  prepared.body.prepared_curve.level = 30;
  prepared.body.prepared_curve.tolerance_q8 = UINT32_MAX;
  for (PowerCurve1& axis : prepared.body.prepared_curve.power) {
    for (int64_t& value : axis.c) value = kWidest;
  }
  Command config = Config();
  MachineConfig& machine = config.body.config;
  machine.axes = 3;
  for (int a = 0; a < kMaxAxes; ++a) {
    machine.steps_per_meter[a] = UINT32_MAX;
    machine.travel_steps[a] = INT32_MIN;
    machine.axis_accel[a] = UINT32_MAX;
  }
  machine.max_rate = machine.accel = machine.travel_rate = UINT32_MAX;
  machine.pen_delay_ms = machine.servo_up_us = machine.servo_down_us = UINT16_MAX;
  machine.flags = 0xff;
  const Command widest[] = {prepared,
                            config,
                            Move(INT32_MIN, INT32_MIN, INT32_MIN),
                            Pen(true),
                            Home(0xff, 0xff, UINT32_MAX, UINT32_MAX),
                            Motors(true)};
  size_t largest = 0;
  for (const Command& command : widest) {
    const size_t frame = CommandBody(command).size() + kFrameOverheadBytes;
    EXPECT_LE(frame, kMaxPreparedFrameBytes) << static_cast<int>(command.type);
    largest = std::max(largest, frame);
  }
  EXPECT_EQ(CommandBody(prepared).size() + kFrameOverheadBytes, largest);
  EXPECT_EQ(largest, 97u);  // messages.h derives it
  std::printf("largest frames: PREPARED_CURVE %zu, CONFIG %zu bytes\n", largest,
              CommandBody(config).size() + kFrameOverheadBytes);
}

TEST(Codec, HomeMotorsAndFlagsBodies) {
  EXPECT_EQ(CommandBody(Home(0x03, 0x02, 0x01020304u, 0x0A0B0C0Du)),
            (Bytes{0x03, 0x02, 0x04, 0x03, 0x02, 0x01, 0x0D, 0x0C, 0x0B, 0x0A}));
  EXPECT_EQ(CommandBody(Motors(true)), Bytes{1});
  EXPECT_EQ(CommandBody(Motors(false)), Bytes{0});
  Command config = Config();
  config.body.config.flags = kConfigFlagHomingRequired;
  const Bytes body = CommandBody(config);
  ASSERT_EQ(body.size(), 56u);
  EXPECT_EQ(body.back(), kConfigFlagHomingRequired);
}

TEST(Codec, GeometryValuesExactAtTheLimits) {
  Command c = Curve(3);
  const int64_t values[] = {0, 1, -1, 63, -64, 64, kGeometryLimitRaw - 1, -(kGeometryLimitRaw - 1)};
  for (int64_t v : values) {
    c.body.curve.geometry[2].g[3] = GeometryFixed::FromRaw(v);
    Bytes storage;
    Command d;
    ASSERT_TRUE(DecodeCommand(Unwire(Wire(c), &storage), &d).ok());
    EXPECT_EQ(d.body.curve.geometry[2].g[3].Raw(), v);
  }
}

TEST(Codec, TeapotSizedPatchIsCompact) {
  // Values of about 30 bits (geometry in steps, Q47.16) take 5 bytes each.
  Command c = Patch(2, 0);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      c.body.patch.geometry[0].g[i][j] = GeometryFixed::FromRaw((int64_t{1} << 29) + i * 1000 + j);
      c.body.patch.geometry[1].g[i][j] = GeometryFixed::FromRaw(-(int64_t{1} << 29) + i);
    }
  }
  EXPECT_EQ(CommandBody(c).size(), 11u + 32u * 5u);
  EXPECT_EQ(Wire(c).size(), 11u + 32u * 5u + kFrameOverheadBytes + 2u);  // docs/protocol.md: 180
}

TEST(Codec, UnusedGeometryIsZeroedAndNotSent) {
  Command c = Patch(2, 1);
  c.body.patch.geometry[2].g[1][1] = GeometryFixed::FromRaw(99);  // not sent for dims 2
  Bytes storage;
  Command d;
  std::memset(static_cast<void*>(&d), 0xAB, sizeof d);
  ASSERT_TRUE(DecodeCommand(Unwire(Wire(c), &storage), &d).ok());
  for (const auto& row : d.body.patch.geometry[2].g) {
    for (const GeometryFixed value : row) {
      EXPECT_EQ(value.Raw(), 0);
    }
  }
}

DecodeResult DecodeOf(const Command& command) {
  Bytes storage;
  Command decoded;
  return DecodeCommand(Unwire(Wire(command), &storage), &decoded);
}

void ExpectRefused(const Command& command, ErrorCode code, uint8_t field) {
  const DecodeResult result = DecodeOf(command);
  EXPECT_EQ(result.code, code) << ErrorName(result.code);
  EXPECT_EQ(result.field, field);
  const DecodeResult validated = ValidateFields(command);
  EXPECT_EQ(validated.code, code);
  EXPECT_EQ(validated.field, field);
}

TEST(CodecValidation, Config) {
  auto with = [](auto change) {
    Command c = Config();
    change(&c.body.config);
    return c;
  };
  const ErrorCode bad = ErrorCode::kBadField;
  ExpectRefused(with([](MachineConfig* m) { m->axes = 1; }), bad, kConfigFieldAxes);
  ExpectRefused(with([](MachineConfig* m) { m->axes = 4; }), bad, kConfigFieldAxes);
  ExpectRefused(with([](MachineConfig* m) { m->steps_per_meter[0] = 0; }), bad, 1);
  ExpectRefused(with([](MachineConfig* m) { m->steps_per_meter[1] = 0; }), bad, 2);
  ExpectRefused(with([](MachineConfig* m) { m->steps_per_meter[2] = 5; }), bad, 3);  // unused
  ExpectRefused(with([](MachineConfig* m) { m->travel_steps[0] = 0; }), bad, 4);
  ExpectRefused(with([](MachineConfig* m) { m->travel_steps[1] = -5; }), bad, 5);
  ExpectRefused(with([](MachineConfig* m) { m->travel_steps[1] = kMaxTravelSteps + 1; }), bad, 5);
  ExpectRefused(with([](MachineConfig* m) { m->travel_steps[2] = 1; }), bad, 6);  // unused
  ExpectRefused(with([](MachineConfig* m) {
                  m->axes = 3;
                  m->steps_per_meter[2] = 1;
                }),
                bad, 6);  // Z used, travel 0
  ExpectRefused(with([](MachineConfig* m) { m->max_rate = 0; }), bad, kConfigFieldMaxRate);
  ExpectRefused(with([](MachineConfig* m) { m->accel = 0; }), bad, kConfigFieldAccel);
  ExpectRefused(with([](MachineConfig* m) { m->travel_rate = 0; }), bad, kConfigFieldTravelRate);
  ExpectRefused(with([](MachineConfig* m) { m->axis_accel[0] = 0; }), bad, kConfigFieldAxisAccel);
  ExpectRefused(with([](MachineConfig* m) { m->axis_accel[1] = 0; }), bad,
                kConfigFieldAxisAccel + 1);
  ExpectRefused(with([](MachineConfig* m) { m->axis_accel[2] = 7; }), bad,
                kConfigFieldAxisAccel + 2);  // unused
  ExpectRefused(with([](MachineConfig* m) {
                  m->axes = 3;
                  m->steps_per_meter[2] = 1;
                  m->travel_steps[2] = 10;
                }),
                bad, kConfigFieldAxisAccel + 2);  // Z used, no limit
  // The servo pen: both 0 (a switch) or each in 500..2500.
  const auto servo = [&](uint16_t up, uint16_t down) {
    return with([=](MachineConfig* m) {
      m->servo_up_us = up;
      m->servo_down_us = down;
    });
  };
  EXPECT_TRUE(ValidateFields(servo(500, 2500)).ok());
  EXPECT_TRUE(ValidateFields(servo(2500, 500)).ok());
  ExpectRefused(servo(499, 2000), bad, kConfigFieldServoUp);
  ExpectRefused(servo(1000, 2501), bad, kConfigFieldServoDown);
  ExpectRefused(servo(0, 2000), bad, kConfigFieldServoUp);    // one 0 is not a switch
  ExpectRefused(servo(1000, 0), bad, kConfigFieldServoDown);  // nor the other
  ExpectRefused(with([](MachineConfig* m) { m->flags = 0x02; }), bad, kConfigFieldFlags);
  ExpectRefused(with([](MachineConfig* m) { m->flags = 0x80; }), bad, kConfigFieldFlags);
}

TEST(CodecValidation, HomeAndMotors) {
  const ErrorCode bad = ErrorCode::kBadField;
  ExpectRefused(Home(0, 0, 100, 0), bad, kHomeFieldAxes);             // no axis
  ExpectRefused(Home(0x08, 0, 100, 0), bad, kHomeFieldAxes);          // beyond Z
  ExpectRefused(Home(0x01, 0x02, 100, 0), bad, kHomeFieldTowardMax);  // not homed
  ExpectRefused(Home(0x03, 0, 0, 0), bad, kHomeFieldRate);
  ExpectRefused(Home(0x03, 0, 1, static_cast<uint32_t>(kMaxTravelSteps) + 1), bad,
                kHomeFieldBackoff);
  Command out;
  EXPECT_EQ(DecodeCommand(BodyFrame(MessageType::kMotors, Bytes{2}), &out).field,
            kMotorsFieldEnabled);
  const DecodeResult longer = DecodeCommand(BodyFrame(MessageType::kMotors, Bytes{1, 0}), &out);
  EXPECT_EQ(longer.code, ErrorCode::kBadLength);
  EXPECT_EQ(longer.field, kMotorsFieldCount);
  const Bytes home_short = {0x01, 0x00, 0x10, 0x00, 0x00, 0x00, 0x05, 0x00, 0x00};
  const DecodeResult cut = DecodeCommand(BodyFrame(MessageType::kHome, home_short), &out);
  EXPECT_EQ(cut.code, ErrorCode::kBadLength);
  EXPECT_EQ(cut.field, kHomeFieldBackoff);
}

TEST(CodecValidation, Patch) {
  auto with = [](auto change) {
    Command c = Patch(3, 5);
    change(&c.body.patch);
    return c;
  };
  const ErrorCode bad = ErrorCode::kBadField;
  ExpectRefused(with([](PatchCommand* p) { p->basis = static_cast<Basis>(kBasisCount); }), bad,
                kPatchFieldBasis);
  ExpectRefused(with([](PatchCommand* p) { p->dims = 1; }), bad, kPatchFieldDims);
  ExpectRefused(with([](PatchCommand* p) { p->dims = 4; }), bad, kPatchFieldDims);
  ExpectRefused(with([](PatchCommand* p) { p->dims = 200; }), bad, kPatchFieldDims);
  ExpectRefused(with([](PatchCommand* p) { p->lines_s = 1; }), bad, kPatchFieldLinesS);
  ExpectRefused(with([](PatchCommand* p) { p->lines_s = kMaxLines + 1; }), bad, kPatchFieldLinesS);
  ExpectRefused(with([](PatchCommand* p) { p->lines_t = 1; }), bad, kPatchFieldLinesT);
  ExpectRefused(with([](PatchCommand* p) { p->lines_t = 0xFFFF; }), bad, kPatchFieldLinesT);
  ExpectRefused(with([](PatchCommand* p) { p->lines_s = p->lines_t = 0; }), bad, kPatchFieldLinesS);
  ExpectRefused(with([](PatchCommand* p) { p->tolerance_q8 = 0; }), bad, kPatchFieldTolerance);
  ExpectRefused(with([](PatchCommand* p) { p->skip_lines = 0x10; }), bad, kPatchFieldSkipLines);
  for (int a = 0; a < 3; ++a) {
    for (int k = 0; k < 16; ++k) {
      for (int64_t v : {kGeometryLimitRaw, -kGeometryLimitRaw, INT64_MAX, INT64_MIN}) {
        ExpectRefused(with([&](PatchCommand* p) {
                        p->geometry[a].g[k / 4][k % 4] = GeometryFixed::FromRaw(v);
                      }),
                      bad, static_cast<uint8_t>(kPatchFieldGeometry + 16 * a + k));
      }
    }
  }
  // Boundary values are accepted.
  EXPECT_TRUE(DecodeOf(with([](PatchCommand* p) {
                p->lines_s = 2;
                p->lines_t = kMaxLines;
              })).ok());
}

TEST(CodecValidation, CurveMovePen) {
  const ErrorCode bad = ErrorCode::kBadField;
  Command c = Curve(3);
  c.body.curve.basis = static_cast<Basis>(9);
  ExpectRefused(c, bad, kCurveFieldBasis);
  c = Curve(3);
  c.body.curve.dims = 0;
  ExpectRefused(c, bad, kCurveFieldDims);
  c = Curve(2);
  c.body.curve.tolerance_q8 = 0;
  ExpectRefused(c, bad, kCurveFieldTolerance);
  for (int a = 0; a < 3; ++a) {
    for (int i = 0; i < 4; ++i) {
      c = Curve(3);
      c.body.curve.geometry[a].g[i] = GeometryFixed::FromRaw(-kGeometryLimitRaw);
      ExpectRefused(c, bad, static_cast<uint8_t>(kCurveFieldGeometry + 4 * a + i));
    }
  }
  for (int a = 0; a < 3; ++a) {
    Command m = Move(1, 2, 3);
    m.body.move.target[a] = -1;
    ExpectRefused(m, bad, static_cast<uint8_t>(kMoveFieldTarget + a));
    m.body.move.target[a] = kMaxTravelSteps + 1;
    ExpectRefused(m, bad, static_cast<uint8_t>(kMoveFieldTarget + a));
  }
  c = Prepared(3);
  c.body.prepared_curve.dims = 1;
  ExpectRefused(c, bad, kPreparedCurveFieldDims);
  c = Prepared(2);
  c.body.prepared_curve.level = kMaxAdaptiveLevel + 1;
  ExpectRefused(c, bad, kPreparedCurveFieldLevel);
  c = Prepared(2);
  c.body.prepared_curve.tolerance_q8 = 0;
  ExpectRefused(c, bad, kPreparedCurveFieldTolerance);
  for (int a = 0; a < 3; ++a) {
    for (int i = 0; i < 4; ++i) {
      c = Prepared(3);
      c.body.prepared_curve.power[a].c[i] = kGeometryLimitRaw;
      ExpectRefused(c, bad, static_cast<uint8_t>(kPreparedCurveFieldPower + 4 * a + i));
    }
  }
  const Bytes pen2 = {2};
  Command out;
  const DecodeResult r = DecodeCommand(BodyFrame(MessageType::kPen, pen2), &out);
  EXPECT_EQ(r.code, bad);
  EXPECT_EQ(r.field, kPenFieldDown);
}

TEST(CodecValidation, ExactLength) {
  const Command commands[] = {
      Config(),    Patch(2, 3),         Patch(3, 4),  Curve(2),
      Curve(3),    Move(5, 300, 70000), Pen(true),    Home(0x03, 0x01, 800, 40),
      Prepared(2), Prepared(3),         Motors(false)};
  for (const Command& c : commands) {
    const Bytes body = CommandBody(c);
    Command out;
    // Every proper prefix is too short; the error names a field, never UB.
    for (size_t n = 0; n < body.size(); ++n) {
      const Bytes prefix(body.begin(), body.begin() + static_cast<std::ptrdiff_t>(n));
      const DecodeResult r = DecodeCommand(BodyFrame(c.type, prefix), &out);
      EXPECT_EQ(r.code, ErrorCode::kBadLength) << "type " << int(c.type) << " prefix " << n;
    }
    // One byte more: kBadLength naming one past the last field.
    Bytes longer = body;
    longer.push_back(0);
    const DecodeResult r = DecodeCommand(BodyFrame(c.type, longer), &out);
    EXPECT_EQ(r.code, ErrorCode::kBadLength);
  }
  Command out;
  const Bytes pen = {1, 0};
  EXPECT_EQ(DecodeCommand(BodyFrame(MessageType::kPen, pen), &out).field, kPenFieldCount);
  Bytes config_short = CommandBody(Config());
  ASSERT_EQ(config_short.size(), 56u);
  config_short.pop_back();  // flags missing
  DecodeResult r = DecodeCommand(BodyFrame(MessageType::kConfig, config_short), &out);
  EXPECT_EQ(r.code, ErrorCode::kBadLength);
  EXPECT_EQ(r.field, kConfigFieldFlags);
  config_short.pop_back();  // servo_down_us cut short
  r = DecodeCommand(BodyFrame(MessageType::kConfig, config_short), &out);
  EXPECT_EQ(r.code, ErrorCode::kBadLength);
  EXPECT_EQ(r.field, kConfigFieldServoDown);
  config_short.resize(51 - 1);  // axis_accel[z] cut short
  r = DecodeCommand(BodyFrame(MessageType::kConfig, config_short), &out);
  EXPECT_EQ(r.code, ErrorCode::kBadLength);
  EXPECT_EQ(r.field, kConfigFieldAxisAccel + 2);
  config_short.resize(35);  // a version 2 config: ends after pen_delay_ms
  const DecodeResult v2 = DecodeCommand(BodyFrame(MessageType::kConfig, config_short), &out);
  EXPECT_EQ(v2.code, ErrorCode::kBadLength);
  EXPECT_EQ(v2.field, kConfigFieldTravelRate);
  const Bytes patch_cut = {2, 2, 2, 0, 0, 0, 1, 0, 0, 0, 0, 5};  // one of 32 geometry values
  const DecodeResult p = DecodeCommand(BodyFrame(MessageType::kPatch, patch_cut), &out);
  EXPECT_EQ(p.code, ErrorCode::kBadLength);
  EXPECT_EQ(p.field, kPatchFieldGeometry + 1);
}

TEST(CodecValidation, Varints) {
  Command out;
  auto move = [&](const Bytes& body) {
    return DecodeCommand(BodyFrame(MessageType::kMove, body), &out);
  };
  EXPECT_TRUE(move({0x7F, 0x80, 0x01, 0x00}).ok());
  // Not minimal: 0x80 0x00 encodes 0 in two bytes.
  EXPECT_EQ(move({0x80, 0x00, 0x00, 0x00}).code, ErrorCode::kBadField);
  EXPECT_EQ(move({0x01, 0xFF, 0x00, 0x00}).field, 1);
  // Eleven bytes, and ten bytes with bits beyond 64.
  Bytes eleven(10, 0x80);
  eleven.push_back(0x01);
  eleven.insert(eleven.end(), {0, 0});
  EXPECT_EQ(move(eleven).code, ErrorCode::kBadField);
  Bytes overflow(9, 0xFF);
  overflow.push_back(0x02);
  overflow.insert(overflow.end(), {0, 0});
  EXPECT_EQ(move(overflow).code, ErrorCode::kBadField);
  // Ten bytes that fit 64 bits decode (then fail the range check, same field).
  Bytes max64(9, 0xFF);
  max64.push_back(0x01);
  max64.insert(max64.end(), {0, 0});
  const DecodeResult r = move(max64);
  EXPECT_EQ(r.code, ErrorCode::kBadField);
  EXPECT_EQ(r.field, 0);
  // A varint running into the end of the body is a length error.
  EXPECT_EQ(move({0x01, 0x02, 0x80}).code, ErrorCode::kBadLength);
}

TEST(CodecValidation, UnknownTypes) {
  Command out;
  const Bytes body = {1};
  for (int type = 0; type < 256; ++type) {
    const DecodeResult r = DecodeCommand(BodyFrame(static_cast<MessageType>(type), body), &out);
    if (type >= 0x10 && type <= 0x17) {
      EXPECT_NE(r.code, ErrorCode::kUnknownType);
    } else {
      EXPECT_EQ(r.code, ErrorCode::kUnknownType) << type;
    }
  }
  Reply reply;
  EXPECT_EQ(DecodeReply(BodyFrame(MessageType::kPatch, body), &reply).code,
            ErrorCode::kUnknownType);
}

TEST(Codec, HelloAndEmptyBodies) {
  Bytes wire(kMaxEncodedFrameBytes);
  Bytes storage;
  wire.resize(EncodeHello(0x1234, Hello{kProtocolVersion, kHelloFlagNewSession, 0xCAFE0042},
                          wire.data(), wire.size()));
  const Frame f = Unwire(wire, &storage);
  EXPECT_EQ(f.seq, 0x1234);
  Hello h{};
  ASSERT_TRUE(DecodeHello(f, &h).ok());
  EXPECT_EQ(h.flags, kHelloFlagNewSession);
  EXPECT_EQ(h.session, 0xCAFE0042u);
  // Version 2: the session follows the flags, and 0 is not a session.
  const Bytes no_session = {kProtocolVersion, 0, 0, 0, 0, 0};
  EXPECT_EQ(DecodeHello(BodyFrame(MessageType::kHello, no_session), &h).field, kHelloFieldSession);
  const Bytes short_session = {kProtocolVersion, 0, 1, 0};
  EXPECT_EQ(DecodeHello(BodyFrame(MessageType::kHello, short_session), &h).code,
            ErrorCode::kBadLength);
  const Bytes other_version = {kProtocolVersion + 1, 0, 0, 0};
  DecodeResult r = DecodeHello(BodyFrame(MessageType::kHello, other_version), &h);
  EXPECT_EQ(r.code, ErrorCode::kUnsupportedVersion);
  const Bytes unknown_flag = {kProtocolVersion, 0x02};
  r = DecodeHello(BodyFrame(MessageType::kHello, unknown_flag), &h);
  EXPECT_EQ(r.code, ErrorCode::kBadField);
  EXPECT_EQ(r.field, kHelloFieldFlags);
  const Bytes short_hello = {kProtocolVersion};
  r = DecodeHello(BodyFrame(MessageType::kHello, short_hello), &h);
  EXPECT_EQ(r.code, ErrorCode::kBadLength);
  EXPECT_EQ(r.field, kHelloFieldFlags);

  wire.assign(kMaxEncodedFrameBytes, 0);
  wire.resize(EncodeStatusQuery(9, wire.data(), wire.size()));
  EXPECT_TRUE(DecodeEmpty(Unwire(wire, &storage)).ok());
  wire.assign(kMaxEncodedFrameBytes, 0);
  wire.resize(EncodeStop(10, wire.data(), wire.size()));
  EXPECT_EQ(Unwire(wire, &storage).type, static_cast<uint8_t>(MessageType::kStop));
  EXPECT_EQ(DecodeEmpty(BodyFrame(MessageType::kStop, Bytes{0})).code, ErrorCode::kBadLength);
}

TEST(Codec, PauseResumeAndHaltAreEmptyTokenFrames) {
  using Encoder = size_t (*)(uint16_t, uint8_t*, size_t, uint32_t);
  const struct {
    Encoder encode;
    MessageType type;
  } cases[] = {{EncodePause, MessageType::kPause},
               {EncodeResume, MessageType::kResume},
               {EncodeHalt, MessageType::kHalt}};
  for (const auto& c : cases) {
    Bytes wire(kMaxEncodedFrameBytes, 0);
    Bytes storage;
    wire.resize(c.encode(0x1234, wire.data(), wire.size(), 0));
    const Frame frame = Unwire(wire, &storage);
    EXPECT_EQ(frame.type, static_cast<uint8_t>(c.type));
    EXPECT_EQ(frame.seq, 0x1234);
    EXPECT_EQ(frame.body_size, 0u);
    EXPECT_TRUE(DecodeEmpty(frame).ok());
    EXPECT_FALSE(IsSequenced(c.type));
    const DecodeResult r = DecodeEmpty(BodyFrame(c.type, Bytes{0}));
    EXPECT_EQ(r.code, ErrorCode::kBadLength);
    EXPECT_EQ(r.field, 0);
  }
}

Reply RoundTripReply(const Bytes& wire) {
  Bytes storage;
  Reply reply;
  const DecodeResult r = DecodeReply(Unwire(wire, &storage), &reply);
  EXPECT_TRUE(r.ok()) << ErrorName(r.code) << " field " << int{r.field};
  return reply;
}

TEST(Codec, ReplyRoundTrips) {
  Bytes wire(kMaxEncodedFrameBytes);
  const HelloReply hello{kProtocolVersion, 0xFFFE, 7, 8, 40000, 3, kMaxLines, kFeatureEndstops};
  wire.resize(EncodeHelloReply(77, hello, wire.data(), wire.size()));
  Reply r = RoundTripReply(wire);
  EXPECT_EQ(r.type, MessageType::kHelloReply);
  EXPECT_EQ(r.seq, 77);
  EXPECT_EQ(r.body.hello.next_seq, 0xFFFE);
  EXPECT_EQ(r.body.hello.credits, 7);
  EXPECT_EQ(r.body.hello.queue_capacity, 8);
  EXPECT_EQ(r.body.hello.tick_hz, 40000u);
  EXPECT_EQ(r.body.hello.max_axes, 3);
  EXPECT_EQ(r.body.hello.max_lines, kMaxLines);
  EXPECT_EQ(r.body.hello.features, kFeatureEndstops);

  const StatusReport status{DeviceState::kFault,
                            ErrorCode::kOutOfTravel,
                            4,
                            true,
                            {-1, 0x7FFFFFFF, INT32_MIN},
                            3,
                            5,
                            0x8001,
                            0xFFFFFFFFu,
                            123456789u,
                            0x7F};
  wire.assign(kMaxEncodedFrameBytes, 0);
  wire.resize(EncodeStatusReport(0xABCD, status, wire.data(), wire.size()));
  r = RoundTripReply(wire);
  EXPECT_EQ(r.seq, 0xABCD);
  const StatusReport& s = r.body.status;
  EXPECT_EQ(s.state, DeviceState::kFault);
  EXPECT_EQ(s.error, ErrorCode::kOutOfTravel);
  EXPECT_EQ(s.error_detail, 4);
  EXPECT_TRUE(s.pen_down);
  EXPECT_EQ(s.position[0], -1);
  EXPECT_EQ(s.position[1], 0x7FFFFFFF);
  EXPECT_EQ(s.position[2], INT32_MIN);
  EXPECT_EQ(s.queued, 3);
  EXPECT_EQ(s.credits, 5);
  EXPECT_EQ(s.next_seq, 0x8001);
  EXPECT_EQ(s.executed, 0xFFFFFFFFu);
  EXPECT_EQ(s.moves, 123456789u);
  EXPECT_EQ(s.flags, 0x7F);

  wire.assign(kMaxEncodedFrameBytes, 0);
  wire.resize(EncodeAck(5, Ack{6, 2}, wire.data(), wire.size()));
  r = RoundTripReply(wire);
  EXPECT_EQ(r.type, MessageType::kAck);
  EXPECT_EQ(r.seq, 5);
  EXPECT_EQ(r.body.ack.next_seq, 6);
  EXPECT_EQ(r.body.ack.credits, 2);

  wire.assign(kMaxEncodedFrameBytes, 0);
  wire.resize(EncodeNak(9, Nak{6, 0, ErrorCode::kQueueFull}, wire.data(), wire.size()));
  r = RoundTripReply(wire);
  EXPECT_EQ(r.type, MessageType::kNak);
  EXPECT_EQ(r.seq, 9);
  EXPECT_EQ(r.body.nak.next_seq, 6);
  EXPECT_EQ(r.body.nak.reason, ErrorCode::kQueueFull);

  wire.assign(kMaxEncodedFrameBytes, 0);
  wire.resize(EncodeError(ErrorReply{300, ErrorCode::kBadField, 17}, wire.data(), wire.size()));
  r = RoundTripReply(wire);
  EXPECT_EQ(r.type, MessageType::kError);
  EXPECT_EQ(r.body.error.seq, 300);
  EXPECT_EQ(r.body.error.code, ErrorCode::kBadField);
  EXPECT_EQ(r.body.error.detail, 17);
}

TEST(CodecValidation, Replies) {
  Reply out;
  auto decode = [&](MessageType type, const Bytes& body) {
    return DecodeReply(BodyFrame(type, body), &out);
  };
  // HELLO_REPLY: capacity 0, credits above capacity, tick 0, axes 4, lines 1.
  const Bytes good = {1, 0, 0, 2, 4, 0x10, 0, 0, 0, 3, 0x01, 0x04, 0x01};
  EXPECT_TRUE(decode(MessageType::kHelloReply, good).ok());
  auto hello_with = [&](size_t at, uint8_t value) {
    Bytes b = good;
    b[at] = value;
    return decode(MessageType::kHelloReply, b);
  };
  EXPECT_EQ(hello_with(4, 0).field, kHelloReplyFieldQueueCapacity);
  EXPECT_EQ(hello_with(3, 5).field, kHelloReplyFieldCredits);
  EXPECT_EQ(hello_with(9, 4).field, kHelloReplyFieldMaxAxes);
  EXPECT_EQ(hello_with(10, 1).code, ErrorCode::kNone);           // 0x0401 lines
  EXPECT_EQ(hello_with(11, 0).field, kHelloReplyFieldMaxLines);  // 1 line
  Bytes tick0 = good;
  tick0[5] = 0;
  EXPECT_EQ(decode(MessageType::kHelloReply, tick0).field, kHelloReplyFieldTickHz);
  EXPECT_EQ(hello_with(12, kFeaturePreparedCurves).code, ErrorCode::kNone);
  EXPECT_EQ(hello_with(12, kFeaturePlanner).code, ErrorCode::kNone);
  EXPECT_EQ(hello_with(12, kFeature64BitTables).code, ErrorCode::kNone);
  EXPECT_EQ(hello_with(12, kFeatureNoTurnCaps).code, ErrorCode::kNone);
  EXPECT_EQ(hello_with(12, 0x20).field, kHelloReplyFieldFeatures);  // unknown feature
  const Bytes no_features(good.begin(), good.end() - 1);
  EXPECT_EQ(decode(MessageType::kHelloReply, no_features).field, kHelloReplyFieldFeatures);
  // STATUS_REPORT: state, error code and pen byte ranges.
  Bytes status(29, 0);
  EXPECT_TRUE(decode(MessageType::kStatusReport, status).ok());
  status[0] = 4;  // kPaused (protocol version 3)
  EXPECT_TRUE(decode(MessageType::kStatusReport, status).ok());
  status[0] = static_cast<uint8_t>(DeviceState::kHoming);
  EXPECT_TRUE(decode(MessageType::kStatusReport, status).ok());
  status[0] = 6;
  EXPECT_EQ(decode(MessageType::kStatusReport, status).field, kStatusFieldState);
  status[0] = 0;
  status[28] = 0x80;  // flags: bit 7 is unused
  EXPECT_EQ(decode(MessageType::kStatusReport, status).field, kStatusFieldFlags);
  status[28] = 0;
  status[1] = kLastErrorCode + 1;
  EXPECT_EQ(decode(MessageType::kStatusReport, status).field, kStatusFieldError);
  status[1] = 0;
  status[3] = 2;
  EXPECT_EQ(decode(MessageType::kStatusReport, status).field, kStatusFieldPenDown);
  // NAK and ERROR need a real code.
  EXPECT_EQ(decode(MessageType::kNak, Bytes{0, 0, 0, 0}).code, ErrorCode::kBadField);
  EXPECT_EQ(decode(MessageType::kNak, Bytes{0, 0, 0, 0}).field, kNakFieldReason);
  EXPECT_EQ(decode(MessageType::kError, Bytes{0, 0}).field, kErrorFieldCode);
  const Bytes beyond_last = {kLastErrorCode + 1, 0};
  EXPECT_EQ(decode(MessageType::kError, beyond_last).code, ErrorCode::kBadField);
  EXPECT_EQ(decode(MessageType::kNak, Bytes{0, 0, 0, kLastErrorCode + 1}).code,
            ErrorCode::kBadField);
  EXPECT_EQ(decode(MessageType::kAck, Bytes{0, 0}).code, ErrorCode::kBadLength);
}

TEST(Codec, ErrorNames) {
  EXPECT_STREQ(ErrorName(ErrorCode::kBadField), "bad field");
  EXPECT_STREQ(ErrorName(ErrorCode::kQueueFull), "queue full");
  EXPECT_STREQ(ErrorName(static_cast<ErrorCode>(200)), "unknown error");
  for (int code = 0; code <= kLastErrorCode; ++code) {
    EXPECT_STRNE(ErrorName(static_cast<ErrorCode>(code)), "unknown error");
  }
}

// The worked examples of docs/protocol.md. The expected CRCs were computed
// independently of this code, with Python's zlib when the document was
// written: zlib.crc32(bytes.fromhex('13 01 00 e8 07 d0 0f 00')) == 0xbe037f4d,
// zlib.crc32(bytes.fromhex('83 01 00 02 00 07')) == 0x8966afa8.
TEST(Codec, WorkedExampleFrames) {
  const Bytes move_wire = {0x03, 0x13, 0x01, 0x05, 0xE8, 0x07, 0xD0,
                           0x0F, 0x05, 0x4D, 0x7F, 0x03, 0xBE, 0x00};
  Command move = Move(1000, 2000, 0);
  move.seq = 1;
  EXPECT_EQ(Wire(move), move_wire);
  const Bytes ack_wire = {0x03, 0x83, 0x01, 0x02, 0x02, 0x06, 0x07, 0xA8, 0xAF, 0x66, 0x89, 0x00};
  Bytes wire(kMaxEncodedFrameBytes);
  wire.resize(EncodeAck(1, Ack{2, 7}, wire.data(), wire.size()));
  EXPECT_EQ(wire, ack_wire);
}

// Random bodies with a valid CRC for every type: the decoders return a
// result and never touch memory outside the body (ASan/UBSan build).
TEST(Codec, DecoderFuzz) {
  std::mt19937_64 rng(21);
  uint64_t accepted = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    Bytes body(rng() % 80);
    for (auto& b : body) {
      // Small values and varint continuation bytes are the interesting ones.
      const uint64_t pick = rng() % 4;
      b = pick == 0   ? static_cast<uint8_t>(rng() % 4)
          : pick == 1 ? static_cast<uint8_t>(0x80 | rng())
                      : static_cast<uint8_t>(rng());
    }
    const auto type = static_cast<MessageType>(rng() % 4 == 0 ? rng() : 0x10 + rng() % 7);
    const Frame frame{static_cast<uint8_t>(type), static_cast<uint16_t>(rng()), body.data(),
                      body.size(), true};
    Command command;
    Reply reply;
    Hello hello;
    if (DecodeCommand(frame, &command).ok()) {
      ++accepted;
      // Whatever decodes re-encodes to the same bytes (one encoding per value).
      EXPECT_EQ(CommandBody(command), body);
    }
    // Arbitrary bytes: these must only not crash or read out of bounds
    // (ASan); whether they decode is not the point.
    (void)DecodeReply(frame, &reply);
    (void)DecodeHello(frame, &hello);
  }
  EXPECT_GT(accepted, 0u);
}

}  // namespace
}  // namespace fdsurf::protocol
