// SPDX-License-Identifier: MIT
// FitJobToDevice (runners/transport_loop.h) against what HELLO_REPLY says:
// a device without a planner of its own (FDSURF_DEVICE_PLANNER=0) is given
// PREPARED_CURVEs only; a job of patches or curves is refused before anything
// is sent, naming the option that plans it on the host.
#include <gtest/gtest.h>

#include <string>

#include "../fdsurf/runners/runner.h"
#include "../fdsurf/runners/transport_loop.h"
#include "../fdsurf/stream_command.h"
#include "fdsurf/adaptive.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf::host {
namespace {

protocol::Command OfType(protocol::MessageType type) {
  protocol::Command command;
  command.type = type;
  command.seq = 0;
  return command;
}

StreamJob JobOf(protocol::MessageType type) {
  StreamJob job;
  job.config.axes = 2;
  job.config.max_rate = 1000;
  job.config.travel_rate = 1000;
  job.config.travel_steps[0] = 20000;
  job.config.travel_steps[1] = 20000;
  job.commands = {OfType(protocol::MessageType::kConfig), OfType(type)};
  job.labels = {"the machine configuration", "the drawing"};
  return job;
}

protocol::HelloReply Hello(std::uint8_t features) {
  protocol::HelloReply hello{};
  hello.version = protocol::kProtocolVersion;
  hello.credits = 4;
  hello.queue_capacity = 4;
  hello.tick_hz = 40000;
  hello.max_axes = 2;
  hello.max_lines = protocol::kMaxLines;
  hello.features = features;
  return hello;
}

AdaptiveSettings StepExact(std::uint32_t tolerance_q8) {
  AdaptiveSettings settings;
  settings.mode = AdaptiveMode::kStepExact;
  settings.tolerance_q8 = tolerance_q8;
  return settings;
}

// A job of one PREPARED_CURVE: `line` at a tolerance of one step, at the
// level this host's planner chooses, on a travel of 20,000 steps per axis.
template <int kDims>
StreamJob PreparedJobOf(const PowerCurve1 (&line)[kDims]) {
  StreamJob job = JobOf(protocol::MessageType::kPreparedCurve);
  job.config.axes = kDims;
  job.config.travel_steps[2] = kDims == 3 ? 20000 : 0;
  protocol::PreparedCurveCommand& curve = job.commands[1].body.prepared_curve;
  curve.dims = kDims;
  curve.tolerance_q8 = 256;
  for (int c = 0; c < kDims; ++c) curve.power[c] = line[c];
  PreparedAdaptiveCurve<kDims> planned;
  EXPECT_EQ(PrepareAdaptiveCurve(line, StepExact(curve.tolerance_q8), &planned), Status::kOk);
  curve.level = planned.finest_level;
  return job;
}

TEST(FitJobToDevice, ADeviceWithoutAPlannerIsGivenPreparedCurvesOnly) {
  StreamOptions options;
  options.quiet = true;
  const protocol::HelloReply lean = Hello(protocol::kFeaturePreparedCurves);
  for (const protocol::MessageType type :
       {protocol::MessageType::kPatch, protocol::MessageType::kCurve}) {
    try {
      (void)FitJobToDevice(JobOf(type), lean, "/dev/ttyACM0", options);
      ADD_FAILURE() << "a job of PATCH or CURVE was fitted to a device without a planner";
    } catch (const DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("/dev/ttyACM0: the device has no planner of its own"),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("--prepare-on-host"), std::string::npos);
    }
  }
  EXPECT_EQ(FitJobToDevice(JobOf(protocol::MessageType::kPreparedCurve), lean, "d", options)
                .commands.size(),
            2u);
  const protocol::HelloReply full =
      Hello(protocol::kFeaturePlanner | protocol::kFeaturePreparedCurves);
  EXPECT_EQ(
      FitJobToDevice(JobOf(protocol::MessageType::kPatch), full, "d", options).commands.size(), 2u);
}

// A device of 64-bit tables (the Arduino Uno) is sent a line whose table
// needs Int128 in pieces; another device gets the line whole.
TEST(FitJobToDevice, ADeviceOfSixtyFourBitTablesIsSentLongLinesInPieces) {
  StreamOptions options;
  options.quiet = true;
  const PowerCurve1 line[2] = {
      PowerCurve1{{0, std::int64_t{500} << 16, std::int64_t{3000} << 16, 100 << 16}},
      PowerCurve1{{std::int64_t{-700} << 16, 0, std::int64_t{2000} << 16, 50 << 16}}};
  const StreamJob job = PreparedJobOf(line);
  const protocol::PreparedCurveCommand& curve = job.commands[1].body.prepared_curve;
  PreparedAdaptiveCurve<2> planned;
  ASSERT_EQ(PrepareAdaptiveCurve(line, StepExact(curve.tolerance_q8), &planned), Status::kOk);
  ASSERT_EQ(planned.format.acc_bits, 128);

  const StreamJob whole =
      FitJobToDevice(job, Hello(protocol::kFeaturePreparedCurves), "d", options);
  EXPECT_EQ(whole.commands.size(), 2u);
  const StreamJob pieces = FitJobToDevice(
      job, Hello(protocol::kFeaturePreparedCurves | protocol::kFeature64BitTables), "d", options);
  ASSERT_GT(pieces.commands.size(), 3u);
  ASSERT_EQ(pieces.labels.size(), pieces.commands.size());
  const std::string of = " of " + std::to_string(pieces.commands.size() - 1);
  EXPECT_EQ(pieces.labels[1], "the drawing, piece 1" + of);
  EXPECT_EQ(pieces.labels.back(),
            "the drawing, piece " + std::to_string(pieces.commands.size() - 1) + of);
  // The pieces run from the line's start to its end.
  EXPECT_EQ(pieces.commands[1].body.prepared_curve.power[0].c[3], curve.power[0].c[3]);
  const PowerCurve1& last = pieces.commands.back().body.prepared_curve.power[1];
  EXPECT_EQ(last.c[0] + last.c[1] + last.c[2] + last.c[3], (2000 - 700 + 50) << 16);
}

// The same for a 3-D job: every piece of a long 3-D line passes the device's
// checks, and the pieces run from the line's start to its end on every axis.
TEST(FitJobToDevice, ADeviceOfSixtyFourBitTablesIsSentLong3DLinesInPieces) {
  StreamOptions options;
  options.quiet = true;
  const PowerCurve1 line[3] = {
      PowerCurve1{{0, std::int64_t{500} << 16, std::int64_t{3000} << 16, 100 << 16}},
      PowerCurve1{{std::int64_t{-700} << 16, 0, std::int64_t{2000} << 16, 50 << 16}},
      PowerCurve1{
          {std::int64_t{300} << 16, std::int64_t{-900} << 16, std::int64_t{4000} << 16, 10 << 16}}};
  const StreamJob job = PreparedJobOf(line);
  const protocol::PreparedCurveCommand& curve = job.commands[1].body.prepared_curve;
  const AdaptiveSettings settings = StepExact(curve.tolerance_q8);
  protocol::HelloReply hello =
      Hello(protocol::kFeaturePreparedCurves | protocol::kFeature64BitTables);
  hello.max_axes = 3;
  const StreamJob pieces = FitJobToDevice(job, hello, "d", options);
  ASSERT_GT(pieces.commands.size(), 3u);
  for (std::size_t k = 1; k < pieces.commands.size(); ++k) {
    const protocol::PreparedCurveCommand& piece = pieces.commands[k].body.prepared_curve;
    ASSERT_EQ(piece.dims, 3);
    PowerCurve1 power[3] = {piece.power[0], piece.power[1], piece.power[2]};
    PowerCurve1 relative[3];
    std::int32_t first[3];
    motion::RelativeToFirstPoint(power, relative, first);
    PreparedAdaptiveCurve<3, std::int64_t> table;
    EXPECT_EQ(PrepareAdaptiveCurveAtLevel(relative, piece.level, settings, &table), Status::kOk)
        << k;
    EXPECT_TRUE(motion::HullWithinTravel(power, job.config.travel_steps)) << k;
  }
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(pieces.commands[1].body.prepared_curve.power[c].c[3], curve.power[c].c[3]) << c;
    const PowerCurve1& last = pieces.commands.back().body.prepared_curve.power[c];
    const PowerCurve1& whole = curve.power[c];
    EXPECT_EQ(last.c[0] + last.c[1] + last.c[2] + last.c[3],
              whole.c[0] + whole.c[1] + whole.c[2] + whole.c[3])
        << c;
  }
}

// Such a device does not halve a line whose Bernstein hull crosses the
// travel's edge (it refuses it), so the host does: a parabola that touches
// x = 0 at u = 1/2 from inside is sent as pieces whose hulls are inside.
TEST(FitJobToDevice, ADeviceOfSixtyFourBitTablesIsSentALineGrazingTheEdgeInPieces) {
  StreamOptions options;
  options.quiet = true;
  // x(u) = 400u² − 400u + 100: 100 at both ends, 0 at u = 1/2.
  const PowerCurve1 line[2] = {
      PowerCurve1{{0, std::int64_t{400} << 16, std::int64_t{-400} << 16, 100 << 16}},
      PowerCurve1{{0, 0, std::int64_t{50} << 16, 50 << 16}}};
  StreamJob job = PreparedJobOf(line);
  protocol::PreparedCurveCommand& curve = job.commands[1].body.prepared_curve;
  ASSERT_FALSE(motion::HullWithinTravel(line, job.config.travel_steps));
  std::uint8_t detail = 0;
  ASSERT_EQ(motion::ValidateCommand<2>(job.commands[1], job.config, &detail),
            protocol::ErrorCode::kNone);  // a full device halves it and takes it

  const StreamJob pieces = FitJobToDevice(
      job, Hello(protocol::kFeaturePreparedCurves | protocol::kFeature64BitTables), "d", options);
  ASSERT_GE(pieces.commands.size(), 3u);  // the CONFIG and two pieces at least
  for (std::size_t k = 1; k < pieces.commands.size(); ++k) {
    const protocol::PreparedCurveCommand& piece = pieces.commands[k].body.prepared_curve;
    const PowerCurve1 power[2] = {piece.power[0], piece.power[1]};
    EXPECT_TRUE(motion::HullWithinTravel(power, job.config.travel_steps)) << k;
  }
  // One step further left the line leaves the travel: no piece can pass.
  curve.power[0].c[3] -= std::int64_t{1} << 16;
  try {
    (void)FitJobToDevice(
        job, Hello(protocol::kFeaturePreparedCurves | protocol::kFeature64BitTables), "d", options);
    ADD_FAILURE() << "a line leaving the travel was split for the device";
  } catch (const EngineError& e) {
    EXPECT_NE(std::string(e.what()).find("the drawing: its hull crosses the edge of the travel"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace fdsurf::host
