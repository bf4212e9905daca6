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
#include "fdsurf/host/stream.h"
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

}  // namespace
}  // namespace fdsurf::host
