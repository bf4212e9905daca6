// SPDX-License-Identifier: MIT
// libFuzzer target, structure-aware: the input is read (FuzzedDataProvider)
// as a sequence of host actions -- HELLO, CONFIG, PATCH, CURVE, MOVE, PEN,
// STATUS, STOP with fuzzed fields, runs of ticks, and now and then a
// corrupted frame -- which are encoded with the firmware's own encoder
// (fdsurf/protocol/codec.h) as valid COBS + CRC frames at the sequence
// number the device expects (learned from its ACK/NAK/HELLO replies, as
// HostLink does), or on purpose at a stale or early one. So field
// validation, the sink's range checks and execution are all reached.
//
// Checks (device_harness.h): no accepted command faults the device when it
// runs; no frame and no Fill() costs more than 50 ms of thread CPU time;
// every reply decodes; the sanitizers. Known defects 1 and 2 (issue 12) are
// findings only with FDSURF_FUZZ_KNOWN_DEFECTS=1; without it, the harness
// drops frames that would hit defect 2 expensively, so a run stays fast.
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "device_harness.h"
#include "fdsurf/adaptive.h"

namespace {

using fdsurf::fuzz::DeviceHarness;
namespace protocol = fdsurf::protocol;

constexpr int kMaxActions = 48;
constexpr std::uint32_t kMaxTicksPerRun = 4096;
constexpr std::uint32_t kMaxTicks = 60000;  // per input, the final run included

constexpr std::int64_t kOneStep = std::int64_t{1} << fdsurf::kCoefficientFracBits;
constexpr std::int64_t kGeometryLimit = fdsurf::kGeometryLimitRaw - 1;

class Session {
 public:
  explicit Session(FuzzedDataProvider& in) : in_(in), harness_(std::make_unique<DeviceHarness>()) {}

  // Most sessions begin with a configuration, so that motion commands are
  // validated against the machine and run rather than refused unconfigured.
  // Sessions (protocol version 2): almost every input opens one with a
  // new-session HELLO first, since the device drops everything else before.
  void Begin() {
    session_ = 1 + in_.ConsumeIntegral<std::uint16_t>();
    harness_->SetSession(session_);
    if (in_.ConsumeIntegralInRange<int>(0, 7) != 7) NewSessionHello();
    if (in_.ConsumeIntegralInRange<int>(0, 3) != 3) Config();
  }

  void Act() {
    switch (in_.ConsumeIntegralInRange<int>(0, 11)) {
      case 0:
        Hello();
        break;
      case 1:
        Config();
        break;
      case 2:
      case 3:
        Patch();
        break;
      case 4:
        Curve();
        break;
      case 5:
        Move();
        break;
      case 6:
        Pen();
        break;
      case 7:
        Send(frame_, protocol::EncodeStatusQuery(token_++, frame_, sizeof frame_, Tag()));
        break;
      case 8:
        Send(frame_, protocol::EncodeStop(token_++, frame_, sizeof frame_, Tag()));
        break;
      case 9:
        Run(in_.ConsumeIntegralInRange<std::uint32_t>(0, kMaxTicksPerRun));
        break;
      case 10:
        PreparedCurve();
        break;
      default:
        Corrupted();
        break;
    }
  }

  void Finish() {
    Run(kMaxTicks);
    harness_->Drain();
  }

 private:
  // --- Fields: mostly valid (so that execution is reached), sometimes not.
  // FuzzedDataProvider gives the minimum once the input is used up, so the
  // choices of the common case are the ones at 0.

  bool Rare() { return in_.ConsumeIntegralInRange<int>(0, 15) == 15; }

  std::int32_t Travel() {
    switch (in_.ConsumeIntegralInRange<int>(0, 15)) {
      case 15:
        return in_.ConsumeIntegral<std::int32_t>();
      case 14:
        return in_.ConsumeIntegralInRange<std::int32_t>(1, protocol::kMaxTravelSteps);
      case 13:
      case 12:
        return in_.ConsumeIntegralInRange<std::int32_t>(1, 1 << 20);
      default:
        return in_.ConsumeIntegralInRange<std::int32_t>(1, 4096);
    }
  }

  std::uint16_t Lines() {
    switch (in_.ConsumeIntegralInRange<int>(0, 15)) {
      case 15:
        return in_.ConsumeIntegral<std::uint16_t>();
      case 14:
        return 0;
      case 13:
      case 12:
        return in_.ConsumeIntegralInRange<std::uint16_t>(2, protocol::kMaxLines);
      case 11:
      case 10:
        return in_.ConsumeIntegralInRange<std::uint16_t>(2, 33);
      default:
        return in_.ConsumeIntegralInRange<std::uint16_t>(2, 6);
    }
  }

  std::uint32_t Tolerance() {
    if (Rare()) return in_.ConsumeIntegral<std::uint32_t>();
    return in_.ConsumeIntegralInRange<std::uint32_t>(64, 4096);
  }

  // A coordinate (Q47.16 steps) on an axis of travel `travel`.
  fdsurf::GeometryFixed Coordinate(std::int32_t travel) {
    std::int64_t raw = 0;
    switch (in_.ConsumeIntegralInRange<int>(0, 15)) {
      case 15:
        raw = in_.ConsumeIntegral<std::int64_t>();
        break;
      case 14:
        raw = in_.ConsumeIntegralInRange<std::int64_t>(-kGeometryLimit, kGeometryLimit);
        break;
      case 13:  // a little outside the travel
      case 12:
        raw = in_.ConsumeIntegralInRange<std::int64_t>(-64 * kOneStep,
                                                       (std::int64_t{travel} + 64) * kOneStep);
        break;
      default:  // inside it, on whole steps
        raw = in_.ConsumeIntegralInRange<std::int64_t>(0, std::max(travel, 0)) * kOneStep;
        break;
    }
    return fdsurf::GeometryFixed::FromRaw(raw);
  }

  fdsurf::Basis Basis() {
    // One value past the last basis, so the decoder's refusal is reached too.
    return static_cast<fdsurf::Basis>(in_.ConsumeIntegralInRange<int>(0, fdsurf::kBasisCount));
  }

  std::uint8_t Dims() { return Rare() ? 3 : 2; }

  // --- Actions.

  // A HELLO: mostly of this session (a resume or a repeated new-session
  // HELLO), sometimes a new session, sometimes any version, flags, session.
  void Hello() {
    protocol::Hello hello;
    hello.version = Rare() ? in_.ConsumeIntegral<std::uint8_t>() : protocol::kProtocolVersion;
    hello.flags = Rare() ? in_.ConsumeIntegral<std::uint8_t>()
                         : (in_.ConsumeBool() ? protocol::kHelloFlagNewSession : 0);
    hello.session = Rare() ? in_.ConsumeIntegral<std::uint32_t>() : session_;
    const bool opens = hello.version == protocol::kProtocolVersion &&
                       hello.flags == protocol::kHelloFlagNewSession && hello.session != 0;
    if (opens) {
      // The device answers in the new session; follow it.
      session_ = hello.session;
      harness_->SetSession(session_);
    }
    Send(frame_, protocol::EncodeHello(token_++, hello, frame_, sizeof frame_));
  }

  void NewSessionHello() {
    protocol::Hello hello;
    hello.version = protocol::kProtocolVersion;
    hello.flags = protocol::kHelloFlagNewSession;
    hello.session = session_;
    Send(frame_, protocol::EncodeHello(token_++, hello, frame_, sizeof frame_));
  }

  // The session a frame is tagged with: this one, rarely another (a stale
  // frame of an old host, which the device must drop).
  std::uint32_t Tag() {
    return Rare() ? session_ ^ (1u + in_.ConsumeIntegral<std::uint8_t>()) : session_;
  }

  void Config() {
    protocol::Command command;
    command.type = protocol::MessageType::kConfig;
    protocol::MachineConfig& config = command.body.config;
    config.axes = Dims();
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      if (a >= config.axes && !Rare()) {
        config.steps_per_meter[a] = 0;  // an unused axis must have neither
        config.travel_steps[a] = 0;
        continue;
      }
      config.steps_per_meter[a] = Rare() ? in_.ConsumeIntegral<std::uint32_t>()
                                         : in_.ConsumeIntegralInRange<std::uint32_t>(1, 1'000'000);
      config.travel_steps[a] = Travel();
    }
    config.max_rate = Rare() ? in_.ConsumeIntegral<std::uint32_t>()
                             : in_.ConsumeIntegralInRange<std::uint32_t>(1, fdsurf::fuzz::kTickHz);
    config.accel = Rare() ? in_.ConsumeIntegral<std::uint32_t>()
                          : in_.ConsumeIntegralInRange<std::uint32_t>(1000, 10'000'000);
    config.pen_delay_ms = Rare() ? in_.ConsumeIntegral<std::uint16_t>()
                                 : in_.ConsumeIntegralInRange<std::uint16_t>(0, 20);
    config.travel_rate = Rare()
                             ? in_.ConsumeIntegral<std::uint32_t>()
                             : in_.ConsumeIntegralInRange<std::uint32_t>(1, fdsurf::fuzz::kTickHz);
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      const bool used = a < config.axes;
      config.axis_accel[a] = Rare() ? in_.ConsumeIntegral<std::uint32_t>()
                             : used ? in_.ConsumeIntegralInRange<std::uint32_t>(1000, 10'000'000)
                                    : 0;
    }
    pending_config_ = config;
    SendCommand(command);
  }

  void Patch() {
    protocol::Command command;
    command.type = protocol::MessageType::kPatch;
    protocol::PatchCommand& patch = command.body.patch;
    patch.basis = Basis();
    patch.dims = Dims();
    patch.lines_s = Lines();
    patch.lines_t = Lines();
    patch.tolerance_q8 = Tolerance();
    patch.skip_lines = Rare()
                           ? in_.ConsumeIntegral<std::uint8_t>()
                           : in_.ConsumeIntegralInRange<std::uint8_t>(0, protocol::kSkipLinesMask);
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      for (auto& row : patch.geometry[a].g) {
        for (auto& value : row) value = Coordinate(travel_[a]);
      }
    }
    SendCommand(command);
  }

  void Curve() {
    protocol::Command command;
    command.type = protocol::MessageType::kCurve;
    protocol::CurveCommand& curve = command.body.curve;
    curve.basis = Basis();
    curve.dims = Dims();
    curve.tolerance_q8 = Tolerance();
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      for (auto& value : curve.geometry[a].g) value = Coordinate(travel_[a]);
    }
    SendCommand(command);
  }

  // A PREPARED_CURVE: a Bézier curve's power coefficients, mostly at the
  // level the planner chooses or one off it (executed, or refused on
  // arrival), sometimes at any level.
  void PreparedCurve() {
    protocol::Command command;
    command.type = protocol::MessageType::kPreparedCurve;
    protocol::PreparedCurveCommand& curve = command.body.prepared_curve;
    curve.dims = Dims();
    curve.tolerance_q8 = Tolerance();
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      const std::int64_t p0 = Coordinate(travel_[a]).Raw();
      const std::int64_t p1 = Coordinate(travel_[a]).Raw();
      const std::int64_t p2 = Coordinate(travel_[a]).Raw();
      const std::int64_t p3 = Coordinate(travel_[a]).Raw();
      // Wrapping arithmetic: out-of-range values are for the decoder to refuse.
      const auto wrap = [](std::uint64_t v) { return static_cast<std::int64_t>(v); };
      const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v); };
      curve.power[a].c[0] = wrap(u(p3) - u(p0) + 3 * (u(p1) - u(p2)));
      curve.power[a].c[1] = wrap(3 * (u(p0) - 2 * u(p1) + u(p2)));
      curve.power[a].c[2] = wrap(3 * (u(p1) - u(p0)));
      curve.power[a].c[3] = p0;
    }
    int level = in_.ConsumeIntegralInRange<int>(0, 24);
    if (!Rare() && curve.dims == 2) {
      fdsurf::AdaptiveSettings settings;
      settings.mode = fdsurf::AdaptiveMode::kStepExact;
      settings.tolerance_q8 = curve.tolerance_q8;
      fdsurf::PowerCurve1 power[2] = {curve.power[0], curve.power[1]};
      fdsurf::PreparedAdaptiveCurve<2> prepared;
      if (fdsurf::PrepareAdaptiveCurve(power, settings, &prepared) == fdsurf::Status::kOk) {
        level = prepared.finest_level + in_.ConsumeIntegralInRange<int>(-1, 1);
      }
    }
    curve.level = static_cast<std::uint8_t>(Rare() ? in_.ConsumeIntegral<std::uint8_t>()
                                                   : std::max(level, 0));
    SendCommand(command);
  }

  void Move() {
    protocol::Command command;
    command.type = protocol::MessageType::kMove;
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      command.body.move.target[a] =
          Rare() ? in_.ConsumeIntegral<std::int32_t>()
                 : in_.ConsumeIntegralInRange<std::int32_t>(0, std::max(travel_[a], 0));
    }
    SendCommand(command);
  }

  void Pen() {
    protocol::Command command;
    command.type = protocol::MessageType::kPen;
    command.body.pen.down = in_.ConsumeBool();
    SendCommand(command);
  }

  // A valid frame with one byte changed (CRC, COBS or length errors), or a
  // lone delimiter.
  void Corrupted() {
    const std::size_t n = protocol::EncodeStatusQuery(token_++, frame_, sizeof frame_, session_);
    if (in_.ConsumeBool()) {
      frame_[in_.ConsumeIntegralInRange<std::size_t>(0, n - 1)] =
          in_.ConsumeIntegral<std::uint8_t>();
      Send(frame_, n);
    } else {
      const std::uint8_t delimiter = 0;
      Send(&delimiter, 1);
    }
  }

  void Run(std::uint32_t ticks) {
    ticks = std::min(ticks, kMaxTicks - ticks_);
    ticks_ += ticks;
    harness_->Run(ticks);
    harness_->Drain([this](const protocol::Reply& reply) { OnReply(reply); });
  }

  // --- Frames.

  // The seq: mostly the expected one; sometimes a duplicate, one ahead, any.
  std::uint16_t Seq() {
    switch (in_.ConsumeIntegralInRange<int>(0, 31)) {
      case 31:
        return static_cast<std::uint16_t>(next_seq_ - 1);
      case 30:
        return static_cast<std::uint16_t>(next_seq_ + 1);
      case 29:
        return in_.ConsumeIntegral<std::uint16_t>();
      default:
        return next_seq_;
    }
  }

  void SendCommand(protocol::Command& command) {
    command.seq = Seq();
    const std::size_t n = protocol::EncodeCommand(command, frame_, sizeof frame_, Tag());
    if (n == 0) __builtin_trap();  // kMaxEncodedFrameBytes always fits
    sent_type_ = command.type;
    sent_seq_ = command.seq;
    Send(frame_, n);
  }

  void Send(const std::uint8_t* frame, std::size_t n) {
    harness_->Feed(frame, n);
    harness_->Drain([this](const protocol::Reply& reply) { OnReply(reply); });
    sent_type_ = protocol::MessageType::kStatusQuery;  // nothing sequenced pending
  }

  // Keeps next_seq as HostLink does, and the travel the device validates
  // against: a CONFIG's ACK means Accept() took it.
  void OnReply(const protocol::Reply& reply) {
    switch (reply.type) {
      case protocol::MessageType::kAck:
        if (sent_type_ == protocol::MessageType::kConfig && reply.seq == sent_seq_ &&
            reply.body.ack.next_seq == static_cast<std::uint16_t>(sent_seq_ + 1) &&
            sent_seq_ == next_seq_) {
          for (int a = 0; a < protocol::kMaxAxes; ++a) travel_[a] = pending_config_.travel_steps[a];
        }
        next_seq_ = reply.body.ack.next_seq;
        break;
      case protocol::MessageType::kError:
        if (std::getenv("FDSURF_FUZZ_TRACE") != nullptr) {
          std::fprintf(stderr, "error: sent type 0x%02x, code %d, detail %d\n",
                       static_cast<int>(sent_type_), static_cast<int>(reply.body.error.code),
                       reply.body.error.detail);
        }
        break;
      case protocol::MessageType::kNak:
        next_seq_ = reply.body.nak.next_seq;
        break;
      case protocol::MessageType::kHelloReply:
        next_seq_ = reply.body.hello.next_seq;
        break;
      case protocol::MessageType::kStatusReport:
        next_seq_ = reply.body.status.next_seq;
        break;
      default:
        break;
    }
  }

  FuzzedDataProvider& in_;
  std::unique_ptr<DeviceHarness> harness_;
  std::uint8_t frame_[protocol::kMaxEncodedFrameBytes];
  std::uint16_t token_ = 0;
  std::uint32_t session_ = 1;
  std::uint16_t next_seq_ = 0;
  protocol::MessageType sent_type_ = protocol::MessageType::kStatusQuery;
  std::uint16_t sent_seq_ = 0;
  protocol::MachineConfig pending_config_{};
  // The travel of the configuration the device accepted last (steps).
  std::int32_t travel_[protocol::kMaxAxes] = {4000, 4000, 4000};
  std::uint32_t ticks_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  Session session(in);
  session.Begin();
  for (int i = 0; i < kMaxActions && in.remaining_bytes() > 0; ++i) session.Act();
  session.Finish();
  return 0;
}
