// SPDX-License-Identifier: MIT
// HOME and MOTORS on the firmware's Device against the simulated endstops
// (hal/sim_endstops.h): where homing leaves the machine, the search at the
// commanded rate, kHomingFailed when a switch never triggers or never
// releases, kNotHomed while a configuration requires homing, MOTORS 0
// forgetting it, and the switches as hard limits outside HOME (kEndstopHit).
// Then the same through the simulated plotter and the host link.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/hal/sim_endstops.h"
#include "fdsurf/host/link.h"
#include "fdsurf/sim/plotter.h"

namespace fdsurf {
namespace {

constexpr std::uint32_t kTickHz = 40000;
constexpr std::int32_t kTravel = 4000;

protocol::Command ConfigCommand(std::uint8_t flags = 0) {
  protocol::Command command;
  command.type = protocol::MessageType::kConfig;
  protocol::MachineConfig& config = command.body.config;
  config = protocol::MachineConfig{};
  config.axes = 2;
  config.steps_per_meter[0] = config.steps_per_meter[1] = 80000;
  config.travel_steps[0] = config.travel_steps[1] = kTravel;
  config.max_rate = 8000;
  config.accel = 160000;
  config.pen_delay_ms = 10;
  config.travel_rate = config.max_rate;
  config.axis_accel[0] = config.axis_accel[1] = 2 * config.accel;
  config.flags = flags;
  return command;
}

protocol::Command HomeCommand(std::uint8_t axes, std::uint8_t toward_max, std::uint32_t rate,
                              std::uint32_t backoff) {
  protocol::Command command;
  command.type = protocol::MessageType::kHome;
  command.body.home = protocol::HomeCommand{axes, toward_max, rate, backoff};
  return command;
}

protocol::Command MoveCommand(std::int32_t x, std::int32_t y) {
  protocol::Command command;
  command.type = protocol::MessageType::kMove;
  command.body.move = protocol::MoveCommand{{x, y, 0}};
  return command;
}

protocol::Command MotorsCommand(bool enabled) {
  protocol::Command command;
  command.type = protocol::MessageType::kMotors;
  command.body.motors.enabled = enabled;
  return command;
}

protocol::Command PenCommand(bool down) {
  protocol::Command command;
  command.type = protocol::MessageType::kPen;
  command.body.pen.down = down;
  return command;
}

// The carriage stands 300 steps right of and 200 steps above the min
// switches at power-on; the X max switch is at 4100 real steps.
hal::SimEndstopOptions Switches() {
  hal::SimEndstopOptions options;
  options.start_offset[0] = 300;
  options.start_offset[1] = 200;
  options.travel[0] = 4100;
  options.min_switches = 0x03;
  return options;
}

class HomingTest : public ::testing::Test {
 protected:
  explicit HomingTest(hal::SimEndstopOptions options = Switches())
      : steps_(clock_, 2), pen_(clock_), endstops_(steps_, options), device_(kTickHz) {
    device_.set_endstops(&endstops_);
  }

  protocol::ErrorCode Accept(const protocol::Command& command, std::uint8_t* detail = nullptr) {
    std::uint8_t ignored = 0;
    return device_.Accept(command, detail != nullptr ? detail : &ignored);
  }
  void AcceptAll(const std::vector<protocol::Command>& commands) {
    for (const protocol::Command& command : commands) {
      std::uint8_t detail = 0;
      ASSERT_EQ(Accept(command, &detail), protocol::ErrorCode::kNone) << int{detail};
    }
  }
  // Main loop and step timer until idle or faulted; false after `limit`.
  bool Run(std::uint64_t limit = 4'000'000) {
    for (std::uint64_t t = 0; t < limit; ++t) {
      device_.Fill();
      EXPECT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
      clock_.Advance(1'000'000 / kTickHz);
      const protocol::StatusReport report = Status();
      if (device_.Idle() || report.state == protocol::DeviceState::kFault) return true;
    }
    return false;
  }
  protocol::StatusReport Status() {
    protocol::StatusReport report{};
    device_.FillStatus(&report);
    return report;
  }

  hal::SimClock clock_;
  hal::SimStepDir steps_;
  hal::SimPen pen_;
  hal::SimEndstops endstops_;
  device::Device<2, 4, 256> device_;
};

TEST_F(HomingTest, HomesBothAxesToTheirMinSwitchesAndBacksOff) {
  EXPECT_EQ(device_.Features(), protocol::kFeatureEndstops | protocol::kFeaturePlanner |
                                    protocol::kFeaturePreparedCurves);
  AcceptAll({ConfigCommand(), HomeCommand(0x03, 0, 2000, 10)});
  device_.Fill();
  ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
  EXPECT_EQ(Status().state, protocol::DeviceState::kHoming);
  ASSERT_TRUE(Run());
  const protocol::StatusReport report = Status();
  EXPECT_EQ(report.state, protocol::DeviceState::kIdle);
  EXPECT_EQ(report.position[0], 0);
  EXPECT_EQ(report.position[1], 0);
  // Position 0 is 10 steps off each switch; the switches released again.
  EXPECT_EQ(endstops_.real_position(0), 10);
  EXPECT_EQ(endstops_.real_position(1), 10);
  EXPECT_EQ(report.flags, protocol::kStatusFlagMotorsEnabled | 0x06);  // X, Y homed, no switch
  EXPECT_EQ(device_.homed(), 0x03);
  EXPECT_EQ(report.executed, 2u);
  // 300 + 10 + 200 + 10 steps, X first (axis order), at 2000 steps/s:
  // one step every 20 ticks of 25 µs.
  std::vector<std::uint64_t> x_steps;
  for (const hal::StepDirEvent& event : steps_.events()) {
    if (event.axis_mask == 0x01) x_steps.push_back(event.time_us);
    EXPECT_NE(event.axis_mask, 0x03);  // one axis at a time
  }
  ASSERT_EQ(x_steps.size(), 310u);
  for (std::size_t i = 1; i < x_steps.size(); ++i) {
    // The step time at which the switch is seen is spent turning round.
    EXPECT_EQ(x_steps[i] - x_steps[i - 1], i == 300 ? 1000u : 500u) << i;
  }
}

TEST_F(HomingTest, TowardMaxSetsTheTravelAndAMoveStartsFromThere) {
  AcceptAll({ConfigCommand(), HomeCommand(0x01, 0x01, 4000, 25), MoveCommand(100, 0)});
  ASSERT_TRUE(Run());
  const protocol::StatusReport report = Status();
  EXPECT_EQ(report.error, protocol::ErrorCode::kNone);
  EXPECT_EQ(report.position[0], 100);
  // Homed at real 4100 - 25 = 4075 as position 4000; then 3900 steps back.
  EXPECT_EQ(endstops_.real_position(0), 175);
  EXPECT_EQ(device_.homed(), 0x01);
}

TEST_F(HomingTest, TheEndstopFlagsShowTheSwitchesNow) {
  AcceptAll({ConfigCommand(), HomeCommand(0x01, 0, 4000, 0)});
  ASSERT_TRUE(Run());
  // No back-off: the carriage rests on the X min switch, homed all the same.
  EXPECT_EQ(Status().error, protocol::ErrorCode::kNone);
  EXPECT_EQ(device_.homed(), 0x01);
  EXPECT_EQ(endstops_.real_position(0), 0);
  EXPECT_EQ(Status().flags & 0x70, protocol::kStatusFlagEndstopX);
}

// A back-off beyond the travel, a rate above the tick rate, and a direction
// with no switch are refused when HOME arrives.
TEST_F(HomingTest, HomeIsRefusedOutsideItsLimits) {
  std::uint8_t detail = 0;
  ASSERT_EQ(Accept(ConfigCommand()), protocol::ErrorCode::kNone);
  EXPECT_EQ(Accept(HomeCommand(0x01, 0, 1000, kTravel + 1), &detail),
            protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kHomeFieldBackoff);
  EXPECT_EQ(Accept(HomeCommand(0x01, 0, kTickHz + 1, 0), &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kHomeFieldRate);
  EXPECT_EQ(Accept(HomeCommand(0x02, 0x02, 1000, 0), &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kHomeFieldAxes);  // Y has no max switch
}

class BrokenSwitchTest : public HomingTest {
 protected:
  static hal::SimEndstopOptions Broken() {
    hal::SimEndstopOptions options = Switches();
    options.broken_min = 0x02;  // Y's wire is cut
    return options;
  }
  BrokenSwitchTest() : HomingTest(Broken()) {}
};

TEST_F(BrokenSwitchTest, ASwitchThatNeverTriggersFailsWithinTheTravelAndAMargin) {
  AcceptAll({ConfigCommand(), HomeCommand(0x03, 0, kTickHz, 3), MoveCommand(10, 10)});
  ASSERT_TRUE(Run());
  const protocol::StatusReport report = Status();
  EXPECT_EQ(report.state, protocol::DeviceState::kFault);
  EXPECT_EQ(report.error, protocol::ErrorCode::kHomingFailed);
  EXPECT_EQ(report.error_detail, 1);  // Y
  EXPECT_EQ(device_.homed(), 0x01);   // X was homed first
  // Y searched travel + travel/8 + 1 steps, then gave up; the MOVE was dropped.
  EXPECT_EQ(steps_.position(1), -(kTravel + kTravel / 8 + 1));
  EXPECT_EQ(endstops_.real_position(0), 3);
  device_.Fill();  // the main loop drops the queue after a fault
  EXPECT_EQ(Status().queued, 0);
}

TEST_F(HomingTest, MotionIsRefusedUntilHomedWhenTheConfigurationRequiresIt) {
  ASSERT_EQ(Accept(ConfigCommand(protocol::kConfigFlagHomingRequired)), protocol::ErrorCode::kNone);
  EXPECT_EQ(Accept(MoveCommand(10, 10)), protocol::ErrorCode::kNotHomed);
  EXPECT_EQ(Accept(PenCommand(false)), protocol::ErrorCode::kNone);  // the pen may move
  // Homing X alone is not enough; with Y queued too, motion is accepted.
  ASSERT_EQ(Accept(HomeCommand(0x01, 0, 4000, 5)), protocol::ErrorCode::kNone);
  EXPECT_EQ(Accept(MoveCommand(10, 10)), protocol::ErrorCode::kNotHomed);
  ASSERT_EQ(Accept(HomeCommand(0x02, 0, 4000, 5)), protocol::ErrorCode::kNone);
  ASSERT_TRUE(Run());
  EXPECT_EQ(Accept(MoveCommand(10, 10)), protocol::ErrorCode::kNone);
  ASSERT_TRUE(Run());
  EXPECT_EQ(Status().position[0], 10);
  // MOTORS 0 forgets homing: the next move is refused again.
  ASSERT_EQ(Accept(MotorsCommand(false)), protocol::ErrorCode::kNone);
  EXPECT_EQ(Accept(MoveCommand(20, 20)), protocol::ErrorCode::kNotHomed);
  ASSERT_TRUE(Run());
  EXPECT_EQ(device_.homed(), 0);
  EXPECT_FALSE(steps_.enabled());
  EXPECT_EQ(Status().flags, 0);
  ASSERT_EQ(Accept(MotorsCommand(true)), protocol::ErrorCode::kNone);
  ASSERT_TRUE(Run());
  EXPECT_TRUE(steps_.enabled());
  EXPECT_EQ(Status().flags, protocol::kStatusFlagMotorsEnabled);
}

TEST_F(HomingTest, StopDuringHomingLeavesTheAxisUnhomed) {
  AcceptAll({ConfigCommand(), HomeCommand(0x01, 0, 1000, 5)});
  for (int t = 0; t < 400; ++t) {
    device_.Fill();
    ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
  }
  ASSERT_EQ(Status().state, protocol::DeviceState::kHoming);
  device_.Stop();
  ASSERT_TRUE(Run());
  EXPECT_EQ(device_.homed(), 0);
  EXPECT_EQ(Status().state, protocol::DeviceState::kIdle);
  EXPECT_EQ(Status().position[0], -10);  // 400 ticks at 1000 steps/s of 40000
  // A new session keeps the position (the motors held it).
  device_.Reset();
  EXPECT_EQ(Status().position[0], -10);
}

TEST_F(HomingTest, AFailingEndstopReadFaultsTheDevice) {
  AcceptAll({ConfigCommand(), HomeCommand(0x01, 0, 1000, 5)});
  device_.Fill();
  endstops_.InjectError(hal::IoStatus::kIoError);
  EXPECT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kIoError);
  EXPECT_EQ(Status().error, protocol::ErrorCode::kOutputFailed);
}

TEST(HomingWithoutEndstops, HomeIsRefusedAndNoFeatureIsReported) {
  device::Device<2, 4, 256> device(kTickHz);
  EXPECT_EQ(device.Features(), protocol::kFeaturePlanner | protocol::kFeaturePreparedCurves);
  std::uint8_t detail = 0;
  ASSERT_EQ(device.Accept(ConfigCommand(), &detail), protocol::ErrorCode::kNone);
  EXPECT_EQ(device.Accept(HomeCommand(0x01, 0, 1000, 0), &detail), protocol::ErrorCode::kBadField);
  EXPECT_EQ(detail, protocol::kHomeFieldAxes);
}

// A carriage 100 steps further down than the device believes: its X min
// switch is triggered at counted X <= 100. It starts on the switch (real
// X -100); moving away is allowed, coming back is not.
class OffsetCarriageTest : public HomingTest {
 protected:
  static hal::SimEndstopOptions Offset() {
    hal::SimEndstopOptions options;
    options.start_offset[0] = -100;
    options.start_offset[1] = 50;
    options.min_switches = 0x03;
    return options;
  }
  OffsetCarriageTest() : HomingTest(Offset()) {}
};

// Four commands: the fixture's queue holds four.
std::vector<protocol::Command> OutAndBack() {
  return {MoveCommand(1000, 500), PenCommand(true), MoveCommand(0, 0), MoveCommand(300, 300)};
}

TEST_F(OffsetCarriageTest, AMoveIntoATriggeredMinSwitchStopsAtOnceAndFaults) {
  AcceptAll({ConfigCommand(), HomeCommand(0x02, 0, 2000, 0)});  // Y homed, resting on its switch
  ASSERT_TRUE(Run());
  ASSERT_EQ(Status().flags & 0x06, 0x04);
  AcceptAll(OutAndBack());
  ASSERT_TRUE(Run());
  const protocol::StatusReport report = Status();
  ASSERT_EQ(report.state, protocol::DeviceState::kFault);
  EXPECT_EQ(report.error, protocol::ErrorCode::kEndstopHit);
  EXPECT_EQ(report.error_detail, 0);  // X, min switch
  // No step into the switch: the carriage is exactly on it, and the
  // reported position is the steps made.
  EXPECT_EQ(endstops_.real_position(0), 0);
  EXPECT_EQ(steps_.position(0), 100);
  EXPECT_EQ(report.position[0], 100);
  EXPECT_EQ(report.position[1], steps_.position(1) + 50);  // homing counted Y from the switch
  EXPECT_FALSE(pen_.down());
  EXPECT_EQ(report.flags & 0x06, 0);  // homing forgotten
  // The rest of the job was dropped: ticks go by, nothing moves.
  const std::int64_t y = steps_.position(1);
  for (int t = 0; t < 1000; ++t) {
    device_.Fill();
    ASSERT_EQ(device_.Tick(steps_, pen_), hal::IoStatus::kOk);
  }
  EXPECT_EQ(steps_.position(0), 100);
  EXPECT_EQ(steps_.position(1), y);
  EXPECT_EQ(Status().queued, 0);
}

// The mutation side: the same job on a device without switches runs to the
// end, through where the switch would be.
TEST(HardLimitWithoutSwitches, TheSameJobRunsToTheEnd) {
  hal::SimClock clock;
  hal::SimStepDir steps(clock, 2);
  hal::SimPen pen(clock);
  device::Device<2, 4, 256> device(kTickHz);
  std::uint8_t detail = 0;
  ASSERT_EQ(device.Accept(ConfigCommand(), &detail), protocol::ErrorCode::kNone);
  device.Fill();
  for (const protocol::Command& command : OutAndBack()) {
    ASSERT_EQ(device.Accept(command, &detail), protocol::ErrorCode::kNone);
  }
  for (int t = 0; t < 4'000'000 && !device.Idle(); ++t) {
    device.Fill();
    ASSERT_EQ(device.Tick(steps, pen), hal::IoStatus::kOk);
    clock.Advance(1'000'000 / kTickHz);
  }
  protocol::StatusReport report{};
  device.FillStatus(&report);
  ASSERT_TRUE(device.Idle()) << static_cast<int>(report.state) << " "
                             << static_cast<int>(report.error);
  EXPECT_EQ(steps.position(0), 300);
  EXPECT_EQ(steps.position(1), 300);
}

TEST_F(OffsetCarriageTest, AMaxSwitchStopsMotionTowardsIt) {
  hal::SimEndstopOptions options = Offset();
  options.travel[0] = 1100;  // the X max switch at counted X >= 1200
  hal::SimEndstops switches(steps_, options);
  device_.set_endstops(&switches);
  AcceptAll({ConfigCommand(), MoveCommand(1500, 0)});
  ASSERT_TRUE(Run());
  const protocol::StatusReport report = Status();
  ASSERT_EQ(report.state, protocol::DeviceState::kFault);
  EXPECT_EQ(report.error, protocol::ErrorCode::kEndstopHit);
  EXPECT_EQ(report.error_detail, protocol::kEndstopHitMax);  // X, max switch
  EXPECT_EQ(steps_.position(0), 1200);
  EXPECT_EQ(report.position[0], 1200);
}

// Through the protocol: the host link's job CONFIG, HOME, MOVE on the
// simulated plotter with its switches.
TEST(SimulatedPlotterHoming, HomesThroughTheLink) {
  sim::PlotterOptions options;
  options.endstops = true;
  options.endstop_options = Switches();
  sim::SimulatedPlotter plotter(options);
  host::HostLink link;
  ASSERT_TRUE(link.Enqueue(ConfigCommand(protocol::kConfigFlagHomingRequired)).ok());
  ASSERT_TRUE(link.Enqueue(HomeCommand(0x03, 0, 4000, 8)).ok());
  ASSERT_TRUE(link.Enqueue(MoveCommand(1000, 500)).ok());
  const sim::RunResult result = plotter.Run(link, 60'000'000);
  ASSERT_TRUE(result.finished) << result.error;
  ASSERT_TRUE(link.hello().has_value());
  EXPECT_EQ(link.hello()->features, protocol::kFeatureEndstops | protocol::kFeaturePlanner |
                                        protocol::kFeaturePreparedCurves);
  EXPECT_EQ(plotter.endstops()->real_position(0), 1008);
  EXPECT_EQ(plotter.endstops()->real_position(1), 508);
  ASSERT_TRUE(link.status().has_value());
  EXPECT_EQ(link.status()->flags & 0x06, 0x06);
}

// The host's words for a hard limit: axis, end, step, and what to do.
TEST(SimulatedPlotterHoming, AnEndstopHitFailsTheJobWithAClearMessage) {
  sim::PlotterOptions options;
  options.endstops = true;
  options.endstop_options.start_offset[0] = -100;
  options.endstop_options.start_offset[1] = 50;
  options.endstop_options.min_switches = 0x03;
  sim::SimulatedPlotter plotter(options);
  host::HostLink link;
  ASSERT_TRUE(link.Enqueue(ConfigCommand()).ok());
  for (const protocol::Command& command : OutAndBack()) ASSERT_TRUE(link.Enqueue(command).ok());
  const sim::RunResult result = plotter.Run(link, 60'000'000);
  ASSERT_FALSE(result.finished);
  EXPECT_NE(result.error.find("X min endstop hit during motion at step 100: the position is "
                              "lost; home the machine (fdsurf machine home)"),
            std::string::npos)
      << result.error;
  EXPECT_EQ(plotter.endstops()->real_position(0), 0);
}

}  // namespace
}  // namespace fdsurf
