// SPDX-License-Identifier: MIT
// The servo pen on the simulator: the firmware Device drives a hal::ServoPen
// on a hal::SimPwm; the PWM's recorded settings become SERVO pulses
// (ServoTransitionsFromPwm), which go through the waveform file format and
// the decoder like a board's recording. Checked: the pulse width of each pen
// state (the CONFIG's widths, not the pen's defaults), the 20 ms period, and
// that the motion waits the pen delay after each pen change.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/pwm.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/sim/waveform.h"

namespace fdsurf::sim {
namespace {

constexpr std::uint32_t kTickHz = 40000;
constexpr std::uint64_t kTickUs = 1'000'000 / kTickHz;
constexpr std::uint16_t kPenDelayMs = 100;
constexpr std::uint16_t kUpUs = 1200;
constexpr std::uint16_t kDownUs = 1850;

protocol::Command Config(std::uint16_t up_us, std::uint16_t down_us) {
  protocol::Command c;
  c.type = protocol::MessageType::kConfig;
  c.seq = 0;
  c.body.config =
      protocol::MachineConfig{2,    {80000, 80000, 0}, {4000, 4000, 0}, 4000,    20000, kPenDelayMs,
                              4000, {40000, 40000, 0}, up_us,           down_us, 0};
  return c;
}

protocol::Command Pen(bool down) {
  protocol::Command c;
  c.type = protocol::MessageType::kPen;
  c.seq = 0;
  c.body.pen.down = down;
  return c;
}

protocol::Command Move(std::int32_t x, std::int32_t y) {
  protocol::Command c;
  c.type = protocol::MessageType::kMove;
  c.seq = 0;
  c.body.move = protocol::MoveCommand{{x, y, 0}};
  return c;
}

struct ServoRun {
  std::vector<hal::StepDirEvent> steps;
  std::vector<hal::PwmEvent> pwm;
  std::uint64_t end_us = 0;
};

// CONFIG, pen down, a move, pen up, a move: run to rest, then 100 ms more.
ServoRun RunServoJob(std::uint16_t up_us, std::uint16_t down_us) {
  hal::SimClock clock;
  hal::SimStepDir steps(clock, 2);
  hal::SimPwm pwm(clock);
  hal::ServoPen pen(pwm, 1000, 2000);  // the defaults the CONFIG replaces
  EXPECT_EQ(pen.Start(), hal::IoStatus::kOk);
  device::Device<2, 8, 256> device(kTickHz);
  std::uint8_t detail = 0;
  for (const protocol::Command& c :
       {Config(up_us, down_us), Pen(true), Move(400, 300), Pen(false), Move(0, 0)}) {
    EXPECT_EQ(device.Accept(c, &detail), protocol::ErrorCode::kNone);
  }
  for (std::uint64_t tick = 0; tick < 10'000'000 && !device.Idle(); ++tick) {
    device.Fill();
    EXPECT_EQ(device.Tick(steps, pen), hal::IoStatus::kOk);
    clock.Advance(kTickUs);
  }
  EXPECT_TRUE(device.Idle());
  return {steps.events(), pwm.events(), clock.now_us() + 100'000};
}

DecodedWaveform Decode(const ServoRun& run, std::uint32_t header_up, std::uint32_t header_down) {
  WaveformHeader header;
  header.pen = PenKind::kServo;
  header.servo_up_us = header_up;
  header.servo_down_us = header_down;
  header.extra["tick_hz"] = std::to_string(kTickHz);
  std::stringstream file;
  WriteWaveform(file, header,
                TransitionsFromServoEvents(header, run.steps, run.pwm, {}, run.end_us));
  return DecodeWaveform(ReadWaveform(file, "servo run"));
}

// Every SERVO pulse: its rise and width, from the waveform's transitions.
struct Pulse {
  std::int64_t rise_ns;
  std::int64_t width_ns;
};
std::vector<Pulse> Pulses(const std::vector<Transition>& transitions) {
  std::vector<Pulse> pulses;
  std::int64_t rise = -1;
  for (const Transition& t : transitions) {
    if (t.signal != WaveSignal::kServo) continue;
    if (t.level == 1) rise = t.time_ns;
    if (t.level == 0 && rise >= 0) pulses.push_back({rise, t.time_ns - rise});
  }
  return pulses;
}

TEST(ServoWaveform, TheConfigsWidthsEvery20msAndThePenDelayKept) {
  const ServoRun run = RunServoJob(kUpUs, kDownUs);
  const DecodedWaveform decoded = Decode(run, kUpUs, kDownUs);
  // Down, then up: read back from the pulse widths alone.
  ASSERT_EQ(decoded.pens.size(), 2u);
  EXPECT_TRUE(decoded.pens[0].down);
  EXPECT_FALSE(decoded.pens[1].down);
  EXPECT_EQ(decoded.pens[0].moves_before, 0u);

  WaveformHeader header;
  header.pen = PenKind::kServo;
  const std::vector<Pulse> pulses =
      Pulses(TransitionsFromServoEvents(header, run.steps, run.pwm, {}, run.end_us));
  ASSERT_GT(pulses.size(), 10u);
  std::size_t down_pulses = 0;
  for (std::size_t i = 0; i < pulses.size(); ++i) {
    // Exactly the CONFIG's widths (the pen's defaults 1000/2000 never show
    // once the CONFIG took effect, before the first pen change).
    const bool down =
        pulses[i].rise_ns >= decoded.pens[0].time_ns && pulses[i].rise_ns < decoded.pens[1].time_ns;
    down_pulses += down ? 1 : 0;
    if (i == 0) continue;  // the pen's start, before the CONFIG
    EXPECT_EQ(pulses[i].width_ns, (down ? kDownUs : kUpUs) * 1000) << "pulse " << i;
    // 50 Hz: 20 ms between rises, ± 1 µs.
    EXPECT_NEAR(pulses[i].rise_ns - pulses[i - 1].rise_ns, 20'000'000, 1000);
  }
  EXPECT_GT(down_pulses, 5u);
  EXPECT_NEAR(static_cast<double>(decoded.timing.servo_period_ns), 20e6, 1e3);

  // The device rests the pen delay after commanding each change (the
  // PwmEvent), and the new width shows at the next period start, at most
  // one period later: so the motion resumes at least delay - period after
  // the pulse that shows it, and at least the delay after the command.
  // The last PWM setting of `width` (the up width is also set by the CONFIG).
  const auto command_us = [&](std::uint32_t width) {
    std::int64_t last = -1;
    for (const hal::PwmEvent& e : run.pwm) {
      if (e.pulse_us == width) last = static_cast<std::int64_t>(e.time_us);
    }
    return last;
  };
  const auto first_step_after_ns = [&](std::int64_t t_ns) {
    for (const UnitMove& m : decoded.moves) {
      if (m.time_ns > t_ns) return m.time_ns;
    }
    return std::int64_t{-1};
  };
  const std::int64_t delay_ns = std::int64_t{kPenDelayMs} * 1'000'000;
  const std::int64_t down_command_ns = command_us(kDownUs) * 1000;
  ASSERT_GE(down_command_ns, 0);
  const std::int64_t first_down_move = first_step_after_ns(down_command_ns);
  EXPECT_GE(first_down_move - down_command_ns, delay_ns);
  EXPECT_GE(first_down_move - decoded.pens[0].time_ns, delay_ns - 20'000'000);
  EXPECT_LE(decoded.pens[0].time_ns - down_command_ns, 20'000'000);
  const std::int64_t up_command_ns = command_us(kUpUs) * 1000;
  const std::int64_t first_up_move = first_step_after_ns(up_command_ns);
  EXPECT_GE(first_up_move - up_command_ns, delay_ns);
  EXPECT_GE(first_up_move - decoded.pens[1].time_ns, delay_ns - 20'000'000);
  EXPECT_LE(decoded.pens[1].time_ns - up_command_ns, 20'000'000);
  // The pen went up after the whole first move: every step before the
  // command is a move before the decoded change.
  std::size_t steps_before_up = 0;
  for (const hal::StepDirEvent& e : run.steps) {
    if (e.axis_mask != 0 && static_cast<std::int64_t>(e.time_us) * 1000 < up_command_ns) {
      ++steps_before_up;
    }
  }
  EXPECT_EQ(decoded.pens[1].moves_before, steps_before_up);
  EXPECT_GE(steps_before_up, 400u);  // at least max(|dx|, |dy|) unit moves
}

// Both 0 in the CONFIG: the servo keeps its own (the board's) widths.
TEST(ServoWaveform, ZeroWidthsKeepThePensDefaults) {
  const ServoRun run = RunServoJob(0, 0);
  WaveformHeader header;
  header.pen = PenKind::kServo;
  const std::vector<Pulse> pulses =
      Pulses(TransitionsFromServoEvents(header, run.steps, run.pwm, {}, run.end_us));
  bool saw_down = false;
  for (const Pulse& p : pulses) {
    EXPECT_TRUE(p.width_ns == 1'000'000 || p.width_ns == 2'000'000) << p.width_ns;
    saw_down = saw_down || p.width_ns == 2'000'000;
  }
  EXPECT_TRUE(saw_down);
  EXPECT_EQ(Decode(run, 1000, 2000).pens.size(), 2u);
}

TEST(ServoWaveform, AWidthChangeWaitsForThePeriodAndADisableStopsThePulses) {
  const std::vector<hal::PwmEvent> events = {
      {0, 20000, 1000, true}, {30000, 20000, 2000, true}, {70000, 20000, 2000, false}};
  const std::vector<Pulse> pulses = Pulses(ServoTransitionsFromPwm(events, 200000));
  ASSERT_EQ(pulses.size(), 4u);  // at 0, 20, 40, 60 ms; none after the disable at 70 ms
  EXPECT_EQ(pulses[1].rise_ns, 20'000'000);
  EXPECT_EQ(pulses[1].width_ns, 1'000'000);  // the change at 30 ms shows at 40 ms
  EXPECT_EQ(pulses[2].width_ns, 2'000'000);
  EXPECT_EQ(pulses[3].rise_ns, 60'000'000);
}

}  // namespace
}  // namespace fdsurf::sim
