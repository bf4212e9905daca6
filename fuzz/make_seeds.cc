// SPDX-License-Identifier: MIT
// Writes the hand-made inputs of fuzz_device_bytes: whole sessions encoded
// with the firmware's encoder (fdsurf/protocol/codec.h), as a host would
// send them. Run once; the files are committed (fuzz/README.md):
//
//   build-fuzz/fuzz/fuzz_make_seeds fuzz
//
// corpus/fuzz_device_bytes/session-draw.bin: configure, pen, move, patch,
// curve, status; session-stop.bin: moves cut short by STOP.
// regressions/fuzz_device_bytes/known-*.bin: the two known defects of issue 12 (a 2^27-step move; a
// 1025 x 1025-line patch whose every line's hull crosses the travel limit while its points stay
// inside it).
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/messages.h"

namespace {

namespace protocol = fdsurf::protocol;
using Bytes = std::vector<std::uint8_t>;

// The session every seed runs in (protocol version 2: the frames after the
// HELLO carry its tag in their CRC).
constexpr std::uint32_t kSession = 0x5EED;

class Session {
 public:
  void Hello() {
    std::uint8_t frame[protocol::kMaxEncodedFrameBytes];
    Append(frame,
           protocol::EncodeHello(
               token_++, {protocol::kProtocolVersion, protocol::kHelloFlagNewSession, kSession},
               frame, sizeof frame));
    seq_ = 0;
  }
  void Status() {
    std::uint8_t frame[protocol::kMaxEncodedFrameBytes];
    Append(frame, protocol::EncodeStatusQuery(token_++, frame, sizeof frame, kSession));
  }
  void Stop() {
    std::uint8_t frame[protocol::kMaxEncodedFrameBytes];
    Append(frame, protocol::EncodeStop(token_++, frame, sizeof frame, kSession));
  }
  void Command(protocol::Command command) {
    command.seq = seq_++;
    std::uint8_t frame[protocol::kMaxEncodedFrameBytes];
    Append(frame, protocol::EncodeCommand(command, frame, sizeof frame, kSession));
  }
  void Write(const std::string& path) const {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (file == nullptr || std::fwrite(bytes_.data(), 1, bytes_.size(), file) != bytes_.size()) {
      std::perror(path.c_str());
      std::exit(1);
    }
    std::fclose(file);
    std::printf("%s: %zu bytes\n", path.c_str(), bytes_.size());
  }

 private:
  void Append(const std::uint8_t* frame, std::size_t n) {
    if (n == 0) std::exit(2);
    bytes_.insert(bytes_.end(), frame, frame + n);
  }
  Bytes bytes_;
  std::uint16_t token_ = 0x100;
  std::uint16_t seq_ = 0;
};

protocol::Command Config(std::int32_t travel) {
  protocol::Command command;
  command.type = protocol::MessageType::kConfig;
  protocol::MachineConfig& c = command.body.config;
  c.axes = 2;
  c.steps_per_meter[0] = c.steps_per_meter[1] = 80000;
  c.steps_per_meter[2] = 0;
  c.travel_steps[0] = c.travel_steps[1] = travel;
  c.travel_steps[2] = 0;
  c.max_rate = 8000;
  c.accel = 160000;
  c.pen_delay_ms = 2;
  c.travel_rate = 8000;
  c.axis_accel[0] = c.axis_accel[1] = 320000;
  c.axis_accel[2] = 0;
  return command;
}

protocol::Command Move(std::int32_t x, std::int32_t y) {
  protocol::Command command;
  command.type = protocol::MessageType::kMove;
  command.body.move.target[0] = x;
  command.body.move.target[1] = y;
  command.body.move.target[2] = 0;
  return command;
}

protocol::Command Pen(bool down) {
  protocol::Command command;
  command.type = protocol::MessageType::kPen;
  command.body.pen.down = down;
  return command;
}

fdsurf::GeometryFixed Steps(double steps) {
  return fdsurf::GeometryFixed::FromRaw(static_cast<std::int64_t>(steps * 65536));
}

// A Bézier patch: x along s and y along t each through `profile`.
protocol::Command Patch(const double (&profile)[4], std::uint16_t lines) {
  protocol::Command command;
  command.type = protocol::MessageType::kPatch;
  protocol::PatchCommand& p = command.body.patch;
  p.basis = fdsurf::Basis::kBezier;
  p.dims = 2;
  p.lines_s = lines;
  p.lines_t = lines;
  p.tolerance_q8 = 256;
  p.skip_lines = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      p.geometry[0].g[i][j] = Steps(profile[i]);
      p.geometry[1].g[i][j] = Steps(profile[j]);
      p.geometry[2].g[i][j] = Steps(0);
    }
  }
  return command;
}

protocol::Command Curve() {
  protocol::Command command;
  command.type = protocol::MessageType::kCurve;
  protocol::CurveCommand& c = command.body.curve;
  c.basis = fdsurf::Basis::kHermite;
  c.dims = 2;
  c.tolerance_q8 = 256;
  const double x[4] = {500, 1500, 2000, -2000};  // P0, P1, T0, T1
  const double y[4] = {500, 900, 0, 1000};
  for (int i = 0; i < 4; ++i) {
    c.geometry[0].g[i] = Steps(x[i]);
    c.geometry[1].g[i] = Steps(y[i]);
    c.geometry[2].g[i] = Steps(0);
  }
  return command;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string root = argc > 1 ? argv[1] : "fuzz";
  {
    Session s;
    s.Hello();
    s.Command(Config(4000));
    s.Command(Move(100, 100));
    s.Command(Pen(true));
    const double bump[4] = {200, 600, 1400, 1800};
    s.Command(Patch(bump, 4));
    s.Command(Curve());
    s.Command(Pen(false));
    s.Status();
    s.Write(root + "/corpus/fuzz_device_bytes/session-draw.bin");
  }
  {
    Session s;
    s.Hello();
    s.Command(Config(4000));
    s.Command(Pen(true));
    s.Command(Move(3000, 2000));
    s.Command(Move(0, 0));
    s.Stop();
    s.Command(Move(10, 10));  // refused while stopping, or accepted after
    s.Status();
    s.Write(root + "/corpus/fuzz_device_bytes/session-stop.bin");
  }
  {
    // Known defect 1: accepted, then "planner refused (detail 4)" when run.
    Session s;
    s.Hello();
    s.Command(Config(protocol::kMaxTravelSteps));
    s.Command(Move(1 << 27, 0));
    s.Status();
    s.Write(root + "/regressions/fuzz_device_bytes/known-long-move.bin");
  }
  {
    // Known defect 2: at travel 16,000 every line's hull leaves [0, 16000]
    // (control values -500 and 16,500) while the curve stays inside it, so
    // validation steps all 2 x 1025 lines of ~15,000 steps in one OnByte().
    Session s;
    s.Hello();
    s.Command(Config(16000));
    const double crossing[4] = {1000, -500, 16500, 15000};
    s.Command(Patch(crossing, protocol::kMaxLines));
    s.Status();
    s.Write(root + "/regressions/fuzz_device_bytes/known-slow-validation.bin");
  }
  return 0;
}
