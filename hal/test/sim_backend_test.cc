// SPDX-License-Identifier: MIT
// The in-memory backend: recorded events with virtual timestamps, the
// transport pair's delivery-time arithmetic, and unplugging.
#include "fdsurf/hal/sim.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace fdsurf::hal {
namespace {

TEST(IoStatus, NamesEveryStatus) {
  EXPECT_STREQ(IoStatusName(IoStatus::kOk), "ok");
  EXPECT_STREQ(IoStatusName(IoStatus::kTimeout), "timeout");
  EXPECT_STREQ(IoStatusName(IoStatus::kDisconnected), "disconnected");
  EXPECT_STREQ(IoStatusName(IoStatus::kNotFound), "not found");
  EXPECT_STREQ(IoStatusName(IoStatus::kBusy), "busy");
  EXPECT_STREQ(IoStatusName(IoStatus::kPermissionDenied), "permission denied");
  EXPECT_STREQ(IoStatusName(IoStatus::kInvalidArgument), "invalid argument");
  EXPECT_STREQ(IoStatusName(IoStatus::kIoError), "I/O error");
}

TEST(SimClock, SleepJumpsAndNeverGoesBack) {
  SimClock clock(100);
  Clock& base = clock;
  EXPECT_EQ(base.NowMicros(), 100u);
  base.SleepUntilMicros(250);
  EXPECT_EQ(base.NowMicros(), 250u);
  base.SleepUntilMicros(200);  // in the past: returns at once
  EXPECT_EQ(base.NowMicros(), 250u);
  clock.Advance(50);
  EXPECT_EQ(base.NowMicros(), 300u);
  clock.Set(10);
  EXPECT_EQ(clock.now_us(), 300u);
}

TEST(SimStepDir, RecordsStepsAndChangesWithTimestamps) {
  SimClock clock;
  SimStepDir outputs(clock, 2);
  StepDirOutputs& base = outputs;
  EXPECT_EQ(base.axes(), 2);

  ASSERT_EQ(base.SetEnabled(true), IoStatus::kOk);
  clock.Advance(10);
  ASSERT_EQ(base.Step(0b01), IoStatus::kOk);
  clock.Advance(5);
  ASSERT_EQ(base.SetDirections(0b10), IoStatus::kOk);
  ASSERT_EQ(base.SetDirections(0b10), IoStatus::kOk);  // no change: no event
  clock.Advance(5);
  ASSERT_EQ(base.Step(0b11), IoStatus::kOk);
  ASSERT_EQ(base.Step(0), IoStatus::kOk);  // nothing pulsed: no event
  clock.Advance(100);
  ASSERT_EQ(base.SetEnabled(false), IoStatus::kOk);

  const std::vector<StepDirEvent> expected = {
      {0, 0, 0b00, true},     {10, 0b01, 0b00, true}, {15, 0, 0b10, true},
      {20, 0b11, 0b10, true}, {120, 0, 0b10, false},
  };
  EXPECT_EQ(outputs.events(), expected);
  EXPECT_EQ(outputs.position(0), 2);
  EXPECT_EQ(outputs.position(1), -1);
  EXPECT_STREQ(base.LastError(), "");
}

TEST(SimStepDir, RefusesMasksBeyondItsAxes) {
  SimClock clock;
  SimStepDir outputs(clock, 2);
  StepDirOutputs& base = outputs;
  EXPECT_EQ(base.Step(0b100), IoStatus::kInvalidArgument);
  EXPECT_STREQ(base.LastError(), "sim step/dir: step mask 0x04 has bits beyond 2 axes");
  EXPECT_EQ(base.SetDirections(0b1000), IoStatus::kInvalidArgument);
  EXPECT_STREQ(base.LastError(), "sim step/dir: direction mask 0x08 has bits beyond 2 axes");
  EXPECT_TRUE(outputs.events().empty());

  SimStepDir three(clock, 3);
  EXPECT_EQ(static_cast<StepDirOutputs&>(three).Step(0b100), IoStatus::kOk);
  SimStepDir four(clock, 4);
  EXPECT_EQ(static_cast<StepDirOutputs&>(four).Step(1), IoStatus::kInvalidArgument);
  EXPECT_STREQ(static_cast<StepDirOutputs&>(four).LastError(),
               "sim step/dir: 4 axes (2 or 3 supported)");
}

TEST(SimStepDir, InjectedErrorFailsOnlyTheNextCall) {
  SimClock clock;
  SimStepDir outputs(clock, 3);
  StepDirOutputs& base = outputs;
  outputs.InjectError(IoStatus::kIoError);
  EXPECT_EQ(base.Step(1), IoStatus::kIoError);
  EXPECT_STREQ(base.LastError(), "sim step/dir: injected I/O error");
  EXPECT_EQ(base.Step(1), IoStatus::kOk);
  EXPECT_EQ(outputs.events().size(), 1u);
}

TEST(SimPen, RecordsChangesWithTimestamps) {
  SimClock clock(7);
  SimPen pen(clock);
  PenOutput& base = pen;
  ASSERT_EQ(base.SetPen(false), IoStatus::kOk);  // already up: nothing
  ASSERT_EQ(base.SetPen(true), IoStatus::kOk);
  clock.Advance(300);
  ASSERT_EQ(base.SetPen(true), IoStatus::kOk);
  ASSERT_EQ(base.SetPen(false), IoStatus::kOk);
  const std::vector<PenEvent> expected = {{7, true}, {307, false}};
  EXPECT_EQ(pen.events(), expected);
  pen.InjectError(IoStatus::kDisconnected);
  EXPECT_EQ(base.SetPen(true), IoStatus::kDisconnected);
  EXPECT_STREQ(base.LastError(), "sim pen: injected disconnected");
  EXPECT_FALSE(pen.down());
}

std::string ReadAll(Transport& end, size_t capacity = 64) {
  std::vector<uint8_t> buffer(capacity);
  size_t received = 0;
  std::string text;
  while (end.Read(buffer.data(), buffer.size(), &received, 0) == IoStatus::kOk) {
    text.append(buffer.begin(), buffer.begin() + static_cast<ptrdiff_t>(received));
  }
  return text;
}

IoStatus WriteText(Transport& end, const std::string& text) {
  return end.Write(reinterpret_cast<const uint8_t*>(text.data()), text.size(), 0);
}

TEST(SimTransportPair, UnlimitedLinkDeliversAtOnceBothWays) {
  SimClock clock;
  SimTransportPair pair(clock);
  ASSERT_EQ(WriteText(pair.host(), "hello"), IoStatus::kOk);
  ASSERT_EQ(WriteText(pair.device(), "world"), IoStatus::kOk);
  EXPECT_EQ(ReadAll(pair.device()), "hello");
  EXPECT_EQ(ReadAll(pair.host()), "world");
  uint8_t byte = 0;
  size_t received = 99;
  EXPECT_EQ(pair.host().Read(&byte, 1, &received, 1000), IoStatus::kTimeout);
  EXPECT_EQ(received, 0u);
  EXPECT_STREQ(pair.host().LastError(), "sim link (host end): nothing to read");
  EXPECT_EQ(clock.now_us(), 0u);  // Read never waits in virtual time
}

TEST(SimTransportPair, LatencyAndBandwidthArithmetic) {
  SimClock clock(1000);
  SimLinkOptions options;
  options.latency_us = 250;
  options.bytes_per_second = 100000;  // 10 us per byte
  SimTransportPair pair(clock, options);

  // 10 bytes at t=1000: sent by 1100, readable at 1350.
  ASSERT_EQ(WriteText(pair.host(), "0123456789"), IoStatus::kOk);
  // 3 bytes right after: queued behind the first, sent 1100..1130, readable at 1380.
  ASSERT_EQ(WriteText(pair.host(), "abc"), IoStatus::kOk);
  EXPECT_EQ(pair.in_flight_to_device(), 13u);

  clock.Set(1349);
  EXPECT_EQ(ReadAll(pair.device()), "");
  EXPECT_STREQ(pair.device().LastError(),
               "sim link (device end): nothing to read until t = 1350 us");
  clock.Set(1350);
  EXPECT_EQ(ReadAll(pair.device(), 4), "0123456789");
  clock.Set(1379);
  EXPECT_EQ(ReadAll(pair.device()), "");
  clock.Set(1380);
  EXPECT_EQ(ReadAll(pair.device()), "abc");
  EXPECT_EQ(pair.in_flight_to_device(), 0u);

  // An idle link starts at once: 1 byte takes 10 us, plus the 250 us latency.
  clock.Set(5000);
  ASSERT_EQ(WriteText(pair.device(), "x"), IoStatus::kOk);
  clock.Set(5259);
  EXPECT_EQ(ReadAll(pair.host()), "");
  clock.Set(5260);
  EXPECT_EQ(ReadAll(pair.host()), "x");
}

TEST(SimTransportPair, BandwidthRoundsUpToWholeMicroseconds) {
  SimClock clock;
  SimLinkOptions options;
  options.bytes_per_second = 3;  // 1 byte = 333333.33 us -> 333334 us
  SimTransportPair pair(clock, options);
  ASSERT_EQ(WriteText(pair.host(), "z"), IoStatus::kOk);
  clock.Set(333333);
  EXPECT_EQ(ReadAll(pair.device()), "");
  clock.Set(333334);
  EXPECT_EQ(ReadAll(pair.device()), "z");
}

TEST(SimTransportPair, FullLinkTimesOutWithoutSending) {
  SimClock clock;
  SimLinkOptions options;
  options.max_in_flight = 8;
  SimTransportPair pair(clock, options);
  ASSERT_EQ(WriteText(pair.host(), "12345"), IoStatus::kOk);
  EXPECT_EQ(WriteText(pair.host(), "6789"), IoStatus::kTimeout);
  EXPECT_STREQ(pair.host().LastError(),
               "sim link (host end): 4 bytes do not fit: 5 of 8 bytes in flight (the other end "
               "is not reading)");
  EXPECT_EQ(ReadAll(pair.device()), "12345");
  EXPECT_EQ(WriteText(pair.host(), "6789"), IoStatus::kOk);
}

TEST(SimTransportPair, DisconnectDropsDataUntilBothEndsReconnect) {
  SimClock clock;
  SimTransportPair pair(clock);
  ASSERT_EQ(WriteText(pair.host(), "lost"), IoStatus::kOk);
  pair.Disconnect();
  EXPECT_FALSE(pair.connected());
  EXPECT_EQ(WriteText(pair.host(), "x"), IoStatus::kDisconnected);
  EXPECT_STREQ(pair.host().LastError(), "sim link (host end): disconnected; call Reconnect()");
  uint8_t byte = 0;
  size_t received = 0;
  EXPECT_EQ(pair.device().Read(&byte, 1, &received, 0), IoStatus::kDisconnected);

  // Not plugged back: Reconnect waits out its timeout in virtual time.
  EXPECT_EQ(pair.host().Reconnect(500), IoStatus::kTimeout);
  EXPECT_STREQ(pair.host().LastError(), "sim link (host end): not plugged back within 500 ms");
  EXPECT_EQ(clock.now_us(), 500000u);

  // Plugged back later than the next timeout, then within it.
  pair.PlugInAt(2000000);
  EXPECT_EQ(pair.host().Reconnect(1000), IoStatus::kTimeout);
  EXPECT_EQ(clock.now_us(), 1500000u);
  EXPECT_EQ(pair.host().Reconnect(1000), IoStatus::kOk);
  EXPECT_EQ(clock.now_us(), 2000000u);  // waited exactly until the plug-in
  EXPECT_TRUE(pair.connected());

  // The host end is back; the device end must reopen too.
  ASSERT_EQ(WriteText(pair.host(), "again"), IoStatus::kOk);
  EXPECT_EQ(pair.device().Read(&byte, 1, &received, 0), IoStatus::kDisconnected);
  EXPECT_EQ(pair.device().Reconnect(0), IoStatus::kOk);
  EXPECT_EQ(ReadAll(pair.device()), "again");  // "lost" was dropped by the unplug
}

TEST(SimTransportPair, RejectsBadArguments) {
  SimClock clock;
  SimTransportPair pair(clock);
  size_t received = 5;
  uint8_t byte = 0;
  EXPECT_EQ(pair.host().Read(nullptr, 1, &received, 0), IoStatus::kInvalidArgument);
  EXPECT_EQ(received, 0u);
  EXPECT_EQ(pair.host().Read(&byte, 0, &received, 0), IoStatus::kInvalidArgument);
  EXPECT_EQ(pair.host().Write(nullptr, 3, 0), IoStatus::kInvalidArgument);
  EXPECT_EQ(pair.host().Write(nullptr, 0, 0), IoStatus::kOk);
}

}  // namespace
}  // namespace fdsurf::hal
