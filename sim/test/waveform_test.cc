// SPDX-License-Identifier: MIT
#include "fdsurf/sim/waveform.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <sstream>

#include "fdsurf/hal/sim.h"
#include "fdsurf/sim/checks.h"

namespace fdsurf::sim {
namespace {

// A run recorded by the in-memory HAL as the Device drives it: per 25 µs
// tick at most one unit move (enable first, then directions, then the
// step) or one pen change, with rests around the pen changes.
struct Recorded {
  std::vector<hal::StepDirEvent> steps;
  std::vector<hal::PenEvent> pens;
};

Recorded RandomRun(int axes, unsigned seed, int ticks = 4000) {
  hal::SimClock clock;
  hal::SimStepDir steppers(clock, static_cast<std::uint8_t>(axes));
  hal::SimPen pen(clock);
  std::mt19937 random(seed);
  const std::uint8_t all = static_cast<std::uint8_t>((1u << axes) - 1);
  std::uint8_t negative = 0;
  for (int tick = 0; tick < ticks; ++tick) {
    clock.Set(100 + static_cast<std::uint64_t>(tick) * 25);
    const unsigned roll = random() % 100;
    if (roll < 2) {
      (void)pen.SetPen(!pen.down());
      tick += 40;  // the pen delay
      continue;
    }
    if (roll < 40) continue;  // idle tick
    if (!steppers.enabled()) (void)steppers.SetEnabled(true);
    const std::uint8_t mask = static_cast<std::uint8_t>(1 + random() % all);
    if (random() % 8 == 0) negative = static_cast<std::uint8_t>(random() & all);
    const std::uint8_t dirs =
        static_cast<std::uint8_t>((steppers.negative_mask() & ~mask) | (negative & mask));
    if (dirs != steppers.negative_mask()) (void)steppers.SetDirections(dirs);
    (void)steppers.Step(mask);
  }
  clock.Advance(1000);
  (void)steppers.SetEnabled(false);
  return {steppers.events(), pen.events()};
}

WaveformHeader SimHeader() {
  WaveformHeader header;
  header.extra["tick_hz"] = "40000";
  return header;
}

Waveform RoundTrip(const WaveformHeader& header, const std::vector<Transition>& transitions) {
  std::stringstream text;
  WriteWaveform(text, header, transitions);
  return ReadWaveform(text, "round-trip");
}

// "" if equal, else the first difference, readable.
std::string FirstDifference(const std::vector<hal::StepDirEvent>& got,
                            const std::vector<hal::StepDirEvent>& want) {
  const auto show = [](const hal::StepDirEvent& e) {
    return "{" + std::to_string(e.time_us) + " us, axes " + std::to_string(e.axis_mask) +
           ", negative " + std::to_string(e.negative_mask) + ", enabled " +
           std::to_string(e.enabled) + "}";
  };
  for (std::size_t i = 0; i < std::min(got.size(), want.size()); ++i) {
    if (!(got[i] == want[i])) {
      return "event " + std::to_string(i) + ": got " + show(got[i]) + ", want " + show(want[i]);
    }
  }
  if (got.size() != want.size()) {
    return std::to_string(got.size()) + " events, want " + std::to_string(want.size());
  }
  return "";
}

std::size_t StepCount(const std::vector<hal::StepDirEvent>& events) {
  std::size_t n = 0;
  for (const auto& e : events) n += e.axis_mask != 0;
  return n;
}

TEST(Waveform, RoundTripGivesTheSimulatorsEventsBack) {
  for (int axes : {2, 3}) {
    for (int polarity : {0, 1}) {
      const Recorded run = RandomRun(axes, 7u + axes + polarity);
      WaveformHeader header = SimHeader();
      header.dir_negative_level = polarity;
      header.enable_active_level = 1 - polarity;
      header.pen_down_level = polarity;
      WaveformWriteOptions write;
      write.axes = axes;
      Waveform back = RoundTrip(header, TransitionsFromEvents(header, run.steps, run.pens, write));
      EXPECT_EQ(back.header.dir_negative_level, polarity);
      EXPECT_EQ(back.header.extra.at("tick_hz"), "40000");
      for (bool snapped : {true, false}) {  // to the header's ticks, and µs as written
        if (!snapped) back.header.extra.erase("tick_hz");
        const DecodedWaveform decoded = DecodeWaveform(back);
        EXPECT_EQ(FirstDifference(decoded.step_events, run.steps), "")
            << "axes " << axes << " snapped " << snapped;
        EXPECT_EQ(decoded.pen_events, run.pens);
        EXPECT_EQ(decoded.moves.size(), StepCount(run.steps));
        EXPECT_EQ(decoded.timing.min_pulse_ns, 2000);
        EXPECT_EQ(decoded.timing.min_dir_setup_ns, 800);
        EXPECT_EQ(decoded.timing.problems(), 0u) << decoded.timing.first_problem;
      }
    }
  }
}

TEST(Waveform, DecodedEventsFeedTheMotionCheckAndTheReplay) {
  const Recorded run = RandomRun(2, 3);
  const WaveformHeader header = SimHeader();
  const DecodedWaveform decoded =
      DecodeWaveform(RoundTrip(header, TransitionsFromEvents(header, run.steps, run.pens, {})));
  MotionLimitsSi limits;
  limits.max_rate = 40000;
  limits.accel = 1e9;
  const MotionReport direct = CheckMotion(run.steps, run.pens, limits);
  const MotionReport via = CheckMotion(decoded.step_events, decoded.pen_events, limits);
  EXPECT_EQ(via.moves, direct.moves);
  EXPECT_DOUBLE_EQ(via.path_length, direct.path_length);
  EXPECT_DOUBLE_EQ(via.duration_s, direct.duration_s);
  const auto paths = ReplayEvents(decoded.step_events, decoded.pen_events);
  const auto expected = ReplayEvents(run.steps, run.pens);
  ASSERT_EQ(paths.size(), expected.size());
  ASSERT_FALSE(paths.empty());
  for (std::size_t i = 0; i < paths.size(); ++i) EXPECT_EQ(paths[i].points, expected[i].points);
}

// The perturbations a broken board would show, each caught.
class Perturbed : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = RandomRun(2, 11);
    header_ = SimHeader();
    transitions_ = TransitionsFromEvents(header_, run_.steps, run_.pens, {});
  }
  // The index of the n-th rising edge of `signal`.
  std::size_t Rise(WaveSignal signal, int n) const {
    for (std::size_t i = 0; i < transitions_.size(); ++i) {
      if (transitions_[i].signal == signal && transitions_[i].level == 1 && n-- == 0) return i;
    }
    ADD_FAILURE() << "no such edge";
    return 0;
  }
  DecodedWaveform Decode() const { return DecodeWaveform(RoundTrip(header_, transitions_)); }

  Recorded run_;
  WaveformHeader header_;
  std::vector<Transition> transitions_;
};

TEST_F(Perturbed, ADroppedStepChangesTheMoves) {
  const std::size_t rise = Rise(WaveSignal::kYStep, 100);
  transitions_.erase(transitions_.begin() + static_cast<std::ptrdiff_t>(rise));
  const DecodedWaveform decoded = Decode();
  EXPECT_NE(decoded.step_events, run_.steps);
  std::size_t y_steps = 0, expected = 0;
  for (const auto& m : decoded.moves) y_steps += m.axis_mask >> 1 & 1;
  for (const auto& e : run_.steps) expected += e.axis_mask >> 1 & 1;
  EXPECT_EQ(y_steps + 1, expected);
}

TEST_F(Perturbed, AFlippedDirectionChangesTheMoves) {
  // X's DIR toggled around its 200th step (the step goes the other way).
  const std::size_t rise = Rise(WaveSignal::kXStep, 200);
  const std::int64_t t = transitions_[rise].time_ns;
  int level = 0;
  for (std::size_t i = 0; i < rise; ++i) {
    if (transitions_[i].signal == WaveSignal::kXDir) level = transitions_[i].level;
  }
  const auto at = transitions_.begin() + static_cast<std::ptrdiff_t>(rise);
  transitions_.insert(at + 2, {t + 2000, WaveSignal::kXDir, static_cast<std::uint8_t>(level)});
  transitions_.insert(transitions_.begin() + static_cast<std::ptrdiff_t>(rise),
                      {t - 500, WaveSignal::kXDir, static_cast<std::uint8_t>(1 - level)});
  const DecodedWaveform decoded = Decode();
  ASSERT_EQ(decoded.moves.size(), StepCount(run_.steps));
  std::size_t differing = 0;
  std::size_t k = 0;
  for (const auto& e : run_.steps) {
    if (e.axis_mask == 0) continue;
    differing += decoded.moves[k++].negative_mask != e.negative_mask;
  }
  EXPECT_EQ(differing, 1u);
  EXPECT_EQ(decoded.timing.problems(), 0u) << decoded.timing.first_problem;  // 500 ns set-up
}

TEST_F(Perturbed, ATooShortPulseIsCounted) {
  const std::size_t rise = Rise(WaveSignal::kXStep, 50);
  for (std::size_t i = rise + 1; i < transitions_.size(); ++i) {
    if (transitions_[i].signal == WaveSignal::kXStep) {
      transitions_[i].time_ns = transitions_[rise].time_ns + 400;
      break;
    }
  }
  const DecodedWaveform decoded = Decode();
  EXPECT_EQ(decoded.timing.short_pulses, 1u);
  EXPECT_EQ(decoded.timing.min_pulse_ns, 400);
  EXPECT_NE(decoded.timing.first_problem.find("X_STEP high for only 400 ns"), std::string::npos)
      << decoded.timing.first_problem;
}

TEST_F(Perturbed, AStepWhileDisabledIsCounted) {
  // A Y pulse before the motors were first enabled.
  std::size_t enable = 0;
  while (!(transitions_[enable].signal == WaveSignal::kXEn && transitions_[enable].time_ns > 0)) {
    ++enable;
  }
  const std::int64_t t = transitions_[enable].time_ns - 10000;
  const auto at = transitions_.begin() + static_cast<std::ptrdiff_t>(enable);
  transitions_.insert(at, {{t, WaveSignal::kYStep, 1}, {t + 2000, WaveSignal::kYStep, 0}});
  const DecodedWaveform decoded = Decode();
  EXPECT_EQ(decoded.timing.steps_while_disabled, 1u);
  EXPECT_NE(decoded.timing.first_problem.find("disabled"), std::string::npos);
}

TEST_F(Perturbed, AShortDirectionSetUpIsCounted) {
  std::size_t dir = 0;
  while (!(transitions_[dir].signal == WaveSignal::kYDir && transitions_[dir].time_ns > 0)) ++dir;
  std::size_t rise = dir;
  while (!(transitions_[rise].signal == WaveSignal::kYStep && transitions_[rise].level == 1)) {
    ++rise;
  }
  Transition moved = transitions_[dir];
  moved.time_ns = transitions_[rise].time_ns - 150;
  transitions_.erase(transitions_.begin() + static_cast<std::ptrdiff_t>(dir));
  const auto at = std::upper_bound(
      transitions_.begin(), transitions_.end(), moved,
      [](const Transition& a, const Transition& b) { return a.time_ns < b.time_ns; });
  transitions_.insert(at, moved);
  const DecodedWaveform decoded = Decode();
  EXPECT_EQ(decoded.timing.short_dir_setups, 1u);
  EXPECT_EQ(decoded.timing.min_dir_setup_ns, 150);
}

TEST(WaveformDecode, GroupsAxesWithinTheWindowIntoOneMove) {
  Waveform w;
  w.header.extra["tick_hz"] = "40000";  // window: 12.5 µs
  w.transitions = {{0, WaveSignal::kXStep, 1},     {2000, WaveSignal::kXStep, 0},
                   {3000, WaveSignal::kYStep, 1},  {5000, WaveSignal::kYStep, 0},
                   {25000, WaveSignal::kXStep, 1}, {27000, WaveSignal::kXStep, 0},
                   {28000, WaveSignal::kXStep, 1}, {30000, WaveSignal::kXStep, 0},
                   {50000, WaveSignal::kYStep, 1}, {52000, WaveSignal::kYStep, 0}};
  const DecodedWaveform d = DecodeWaveform(w);
  ASSERT_EQ(d.moves.size(), 4u);
  EXPECT_EQ(d.moves[0].axis_mask, 3);
  EXPECT_EQ(d.moves[1].axis_mask, 1);  // X twice: two moves
  EXPECT_EQ(d.moves[2].axis_mask, 1);
  EXPECT_EQ(d.moves[3].axis_mask, 2);
  // X twice 3 µs apart cannot be one tick each: counted, and the second is
  // given the next tick (the times keep one move per tick, in order).
  EXPECT_EQ(d.timing.crowded_ticks, 1u);
  EXPECT_EQ(d.timing.min_event_interval_ns, 3000);
  EXPECT_EQ(d.step_events[2].time_us, 50u);
  EXPECT_EQ(d.step_events[3].time_us, 75u);
}

// A board writes a pen change early in its tick interrupt and a step late,
// so a pen change can come less than a tick after the step before it (here
// 0.8 tick, as the micro:bit does); its nearest grid tick is then the
// step's. It still gets a tick of its own, after the step, so the replay
// keeps the pen change after the step and the motion check sees no step
// at the pen change.
TEST(WaveformDecode, APenChangeEarlyInItsTickStaysAfterTheStepBeforeIt) {
  Waveform w;
  w.header.extra["tick_hz"] = "20000";  // 50 µs
  w.header.pen = PenKind::kLine;
  w.header.pen_down_level = 1;
  w.transitions = {{0, WaveSignal::kPen, 0},       {40000, WaveSignal::kXStep, 1},
                   {42000, WaveSignal::kXStep, 0}, {90000, WaveSignal::kXStep, 1},
                   {92000, WaveSignal::kXStep, 0}, {130000, WaveSignal::kPen, 1}};
  const DecodedWaveform d = DecodeWaveform(w);
  ASSERT_EQ(d.moves.size(), 2u);
  ASSERT_EQ(d.pen_events.size(), 1u);
  EXPECT_GT(d.pen_events[0].time_us, d.step_events.back().time_us);
  EXPECT_EQ(d.timing.crowded_ticks, 0u);
  EXPECT_EQ(d.timing.min_event_interval_ns, 40000);
}

TEST(WaveformDecode, AServoPenIsReadFromThePulseWidths) {
  std::stringstream text;
  text << "# fdsurf-waveform 1\n# board test\n# pen servo 1000 2000\n";
  std::int64_t t = 0;
  for (int i = 0; i < 10; ++i, t += 20'000'000) {
    const int width_us = i >= 3 && i < 7 ? 2000 : 1000;  // down for pulses 3..6
    text << t << " SERVO 1\n" << t + width_us * 1000 << " SERVO 0\n";
    if (i == 5) text << t + 5'000'000 << " X_STEP 1\n" << t + 5'002'000 << " X_STEP 0\n";
  }
  const DecodedWaveform d = DecodeWaveform(ReadWaveform(text, "servo"));
  ASSERT_EQ(d.pens.size(), 2u);
  EXPECT_TRUE(d.pens[0].down);
  EXPECT_EQ(d.pens[0].time_ns, 60'000'000);
  EXPECT_EQ(d.pens[0].moves_before, 0u);
  EXPECT_FALSE(d.pens[1].down);
  EXPECT_EQ(d.pens[1].time_ns, 140'000'000);
  EXPECT_EQ(d.pens[1].moves_before, 1u);
  EXPECT_EQ(d.timing.servo_period_ns, 20'000'000);
}

TEST(WaveformDecode, ServoPulsesWithoutAServoHeaderAreAnError) {
  std::stringstream text;
  text << "# fdsurf-waveform 1\n# board test\n0 SERVO 1\n1000000 SERVO 0\n";
  const Waveform w = ReadWaveform(text, "servo");
  EXPECT_THROW((void)DecodeWaveform(w), WaveformError);
}

void ExpectError(const std::string& text, const std::string& message) {
  std::stringstream in(text);
  try {
    (void)ReadWaveform(in, "bad.wave");
    ADD_FAILURE() << "no error for: " << text;
  } catch (const WaveformError& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(WaveformRead, BadInputIsNamedWithItsLine) {
  ExpectError("0 X_STEP 1\n", "bad.wave:1: not a waveform");
  ExpectError("# fdsurf-waveform 1\n0 W_STEP 1\n", "bad.wave:2: unknown signal 'W_STEP'");
  ExpectError("# fdsurf-waveform 1\n5 X_STEP 1\n4 X_STEP 0\n", "bad.wave:3: time 4 ns is before");
  ExpectError("# fdsurf-waveform 1\n5 X_STEP 2\n", "bad.wave:2: level of X_STEP must be 0 or 1");
  ExpectError("# fdsurf-waveform 1\n5 X_STEP\n", "bad.wave:2: expected");
  ExpectError("# fdsurf-waveform 1\n# pen servo 1000\n", "bad.wave:2: pen must be");
  ExpectError("# fdsurf-waveform 1\n# dir_negative_level 2\n", "dir_negative_level must be 0 or 1");
}

}  // namespace
}  // namespace fdsurf::sim
