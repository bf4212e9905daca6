// SPDX-License-Identifier: MIT
// fdsurf_waveform_check: compares the pins a board recorded under its
// emulator (REC) with what the simulated plotter did for the same job (REF,
// `fdsurf stream --device sim --waveform`): the same unit moves and pen
// changes in the same order, the same drawing, the drivers' pulse timing, and
// the job's speed and acceleration limits (sim::CheckMotion, limits from
// REF's header) kept on REC.
//
//   fdsurf_waveform_check --reference REF --recorded REC [--prefix]
//                         [--min-pulse-ns N] [--min-dir-setup-ns N]
//
// --prefix: REC was cut by a STOP: its moves must be a proper prefix of
// REF's, after which the pen is up and the motion has come to rest within
// the acceleration limit. Exit 0: all kept; 1: the first difference or
// violation is printed; 2: bad input (a file that is not a waveform).
//
// A test instrument, not a user command: it lives with the end-to-end tests
// (tests/boards/) and links only the simulator box.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "fdsurf/sim/checks.h"
#include "fdsurf/sim/plotter.h"
#include "fdsurf/sim/waveform.h"

namespace fdsurf::sim {
namespace {

struct Options {
  std::string reference;
  std::string recorded;
  bool prefix = false;
  std::int64_t min_pulse_ns = 1000;
  std::int64_t min_dir_setup_ns = 200;
  /// The longest a servo pen's change waits for the pulse that carries it;
  /// 0: one PWM period (the recording's longest).
  std::int64_t servo_wait_ns = 0;
};

std::string Axes(const UnitMove& m) {
  std::string text;
  for (int axis = 0; axis < 3; ++axis) {
    if ((m.axis_mask >> axis & 1) == 0) continue;
    if (!text.empty()) text += " ";
    text += static_cast<char>('X' + axis);
    text += (m.negative_mask >> axis & 1) != 0 ? '-' : '+';
  }
  return text;
}

bool SameMove(const UnitMove& a, const UnitMove& b) {
  return a.axis_mask == b.axis_mask &&
         (a.negative_mask & a.axis_mask) == (b.negative_mask & b.axis_mask);
}

// The first difference of the unit moves, or nothing.
std::optional<std::string> CompareMoves(const DecodedWaveform& ref, const DecodedWaveform& rec,
                                        bool prefix) {
  const std::size_t n = std::min(ref.moves.size(), rec.moves.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!SameMove(ref.moves[i], rec.moves[i])) {
      return "move " + std::to_string(i) + " (recorded at " + std::to_string(rec.moves[i].time_ns) +
             " ns): expected " + Axes(ref.moves[i]) + ", got " + Axes(rec.moves[i]);
    }
  }
  if (rec.moves.size() > ref.moves.size()) {
    return "move " + std::to_string(n) + " (recorded at " + std::to_string(rec.moves[n].time_ns) +
           " ns): expected none (the reference has " + std::to_string(n) + " moves), got " +
           Axes(rec.moves[n]);
  }
  if (rec.moves.size() < ref.moves.size() && !prefix) {
    return "move " + std::to_string(n) + ": expected " + Axes(ref.moves[n]) +
           ", got none (the recording ends after " + std::to_string(n) + " of " +
           std::to_string(ref.moves.size()) + " moves)";
  }
  if (prefix && rec.moves.size() == ref.moves.size()) {
    return "--prefix: the recording has all " + std::to_string(n) +
           " moves of the reference: the STOP cut nothing";
  }
  return std::nullopt;
}

std::string Pen(const PenChange& p) {
  return std::string(p.down ? "down" : "up") + " after move " + std::to_string(p.moves_before);
}

// The first difference of the pen changes (and where they fall among the
// moves), or nothing. With `prefix`, REC may end with one extra lift.
std::optional<std::string> ComparePens(const DecodedWaveform& ref, const DecodedWaveform& rec,
                                       bool prefix) {
  std::size_t rec_pens = rec.pens.size();
  if (prefix && rec_pens > 0) {
    const PenChange& last = rec.pens.back();
    const bool extra_lift = !last.down && last.moves_before == rec.moves.size() &&
                            (rec_pens > ref.pens.size() || ref.pens[rec_pens - 1].down ||
                             ref.pens[rec_pens - 1].moves_before != last.moves_before);
    if (extra_lift) --rec_pens;
  }
  const std::size_t n = std::min(ref.pens.size(), rec_pens);
  for (std::size_t i = 0; i < n; ++i) {
    const PenChange& a = ref.pens[i];
    const PenChange& b = rec.pens[i];
    if (a.down != b.down || a.moves_before != b.moves_before) {
      return "pen change " + std::to_string(i) + " (recorded at " + std::to_string(b.time_ns) +
             " ns): expected " + Pen(a) + ", got " + Pen(b);
    }
  }
  if (rec_pens > n) {
    return "pen change " + std::to_string(n) + " (recorded at " +
           std::to_string(rec.pens[n].time_ns) + " ns): expected none, got " + Pen(rec.pens[n]);
  }
  if (!prefix && ref.pens.size() > n) {
    return "pen change " + std::to_string(n) + ": expected " + Pen(ref.pens[n]) + ", got none";
  }
  if (prefix && !rec.pens.empty() && rec.pens.back().down) {
    return "--prefix: the pen is still down after the STOP (since " +
           std::to_string(rec.pens.back().time_ns) + " ns)";
  }
  return std::nullopt;
}

// The drawings: REC's strokes must be REF's (with --prefix: REF's first
// strokes, the last one possibly cut short).
std::optional<std::string> CompareDrawings(const DecodedWaveform& ref, const DecodedWaveform& rec,
                                           bool prefix) {
  const auto a = ReplayEvents(ref.step_events, ref.pen_events);
  const auto b = ReplayEvents(rec.step_events, rec.pen_events);
  if (b.size() > a.size() || (!prefix && b.size() != a.size())) {
    return "the drawing has " + std::to_string(b.size()) + " strokes, the reference " +
           std::to_string(a.size());
  }
  for (std::size_t i = 0; i < b.size(); ++i) {
    const bool last = i + 1 == b.size();
    const auto& p = a[i].points;
    const auto& q = b[i].points;
    const bool same =
        prefix && last ? q.size() <= p.size() && std::equal(q.begin(), q.end(), p.begin()) : p == q;
    if (!same) return "stroke " + std::to_string(i) + " differs from the reference's";
  }
  return std::nullopt;
}

MotionLimitsSi LimitsFrom(const WaveformHeader& ref, const std::string& name) {
  MotionLimitsSi limits;
  limits.tick_hz = static_cast<std::uint32_t>(ref.Number("tick_hz", 0));
  limits.max_rate = ref.Number("max_rate", 0);
  limits.travel_rate = ref.Number("travel_rate", 0);  // absent: max_rate, pen up too
  limits.accel = ref.Number("accel", 0);
  limits.pen_delay_s = ref.Number("pen_delay_ms", 0) * 1e-3;
  if (limits.tick_hz == 0 || !(limits.max_rate > 0) || !(limits.accel > 0)) {
    throw WaveformError(name +
                        ": the reference's header lacks the job's limits (tick_hz, max_rate, "
                        "accel): write it with `fdsurf stream --device sim --waveform`");
  }
  return limits;
}

// CheckMotion on REC, the end of the recording counted as a rest (the motion
// must have come to rest within the acceleration limit, after a STOP too).
MotionReport CheckRecordedMotion(const DecodedWaveform& rec, MotionLimitsSi limits,
                                 std::int64_t servo_wait_ns) {
  // A servo pen takes effect at its next pulse: up to one PWM period later,
  // or as long as the board says a change can wait for its pulse (the
  // recording times the change at that pulse, the device's pen delay ran
  // from the change itself).
  if (rec.timing.servo_period_ns > 0) {
    const std::int64_t wait = std::max(servo_wait_ns, rec.timing.servo_period_ns);
    limits.pen_delay_s = std::max(0.0, limits.pen_delay_s - static_cast<double>(wait) * 1e-9);
  }
  std::vector<hal::PenEvent> pens = rec.pen_events;
  std::uint64_t last_step_us = 0;
  std::uint64_t previous_step_us = 0;
  for (const hal::StepDirEvent& e : rec.step_events) {
    if (e.axis_mask == 0) continue;
    previous_step_us = last_step_us;
    last_step_us = e.time_us;
  }
  // Where the motion came to rest: after its last step a correct stop still
  // decelerates over less than one step, which at the acceleration limit a
  // takes at most sqrt(2 / a) (x = a t^2 / 2 <= 1 step), and no longer than
  // v / a from the speed v it had (about one step per the last interval),
  // plus a tick of quantisation. Taking the last step itself as the rest
  // would hold a correct deceleration to a law it cannot meet; the bound
  // still catches a stop that is too abrupt (at speed, v / a is far longer
  // than sqrt(2 / a)).
  std::uint64_t settle_us = 1'000'000 / limits.tick_hz;
  if (limits.accel > 0) {
    double settle_s = std::sqrt(2.0 / limits.accel);
    if (previous_step_us != 0 && last_step_us > previous_step_us) {
      const double speed = 1e6 / static_cast<double>(last_step_us - previous_step_us);
      settle_s = std::min(settle_s, speed / limits.accel);
    }
    settle_us += static_cast<std::uint64_t>(settle_s * 1e6);
  }
  const std::uint64_t end_us = last_step_us + settle_us;
  if (pens.empty() || pens.back().time_us < end_us) {
    pens.push_back(hal::PenEvent{end_us, pens.empty() ? false : pens.back().down});
  }
  return CheckMotion(rec.step_events, pens, limits);
}

void PrintTiming(const WaveformTiming& t, const Options& o) {
  std::printf(
      "timing: shortest STEP pulse %lld ns (at least %lld), shortest DIR set-up %lld ns (at least "
      "%lld), %zu steps while disabled, shortest time between two moves or pen changes %lld ns "
      "(%zu under half a tick)\n",
      static_cast<long long>(t.min_pulse_ns), static_cast<long long>(o.min_pulse_ns),
      static_cast<long long>(t.min_dir_setup_ns), static_cast<long long>(o.min_dir_setup_ns),
      t.steps_while_disabled, static_cast<long long>(t.min_event_interval_ns), t.crowded_ticks);
}

int Check(const Options& o) {
  const Waveform ref_wave = ReadWaveformFile(o.reference);
  const Waveform rec_wave = ReadWaveformFile(o.recorded);
  const MotionLimitsSi limits = LimitsFrom(ref_wave.header, o.reference);
  DecodeOptions decode;
  decode.tick_hz = limits.tick_hz;
  decode.min_pulse_ns = o.min_pulse_ns;
  decode.min_dir_setup_ns = o.min_dir_setup_ns;
  const DecodedWaveform ref = DecodeWaveform(ref_wave, decode);
  const DecodedWaveform rec = DecodeWaveform(rec_wave, decode);
  std::printf("reference %s: %zu moves, %zu pen changes, %.3f s\n", o.reference.c_str(),
              ref.moves.size(), ref.pens.size(), ref.timing.duration_ns * 1e-9);
  std::printf("recorded %s (board %s): %zu moves, %zu pen changes, %.3f s\n", o.recorded.c_str(),
              rec_wave.header.board.c_str(), rec.moves.size(), rec.pens.size(),
              rec.timing.duration_ns * 1e-9);
  std::vector<std::string> failures;
  for (const auto& difference : {CompareMoves(ref, rec, o.prefix), ComparePens(ref, rec, o.prefix),
                                 CompareDrawings(ref, rec, o.prefix)}) {
    if (difference) failures.push_back(*difference);
  }
  if (failures.empty()) {
    std::printf("moves and pen changes: the same, in the same order%s\n",
                o.prefix
                    ? (" (a prefix: cut by the STOP after " + std::to_string(rec.moves.size()) +
                       " of " + std::to_string(ref.moves.size()) + " moves)")
                          .c_str()
                    : "");
  }
  PrintTiming(rec.timing, o);
  if (rec.timing.problems() > 0) failures.push_back(rec.timing.first_problem);
  const MotionReport motion = CheckRecordedMotion(rec, limits, o.servo_wait_ns);
  std::printf(
      "motion: top speed %.0f steps/s (limit %.0f), largest acceleration %.0f steps/s² (limit "
      "%.0f, windowed), %zu violations\n",
      motion.max_speed, limits.max_rate, motion.max_accel, limits.accel, motion.violations);
  if (motion.violations > 0) failures.push_back("motion limits: " + motion.first_violation);
  if (failures.empty()) {
    std::printf("OK\n");
    return 0;
  }
  std::printf("FAIL: %s\n", failures.front().c_str());
  for (std::size_t i = 1; i < failures.size(); ++i) std::printf("also: %s\n", failures[i].c_str());
  return 1;
}

}  // namespace
}  // namespace fdsurf::sim

int main(int argc, char** argv) {
  fdsurf::sim::Options o;
  CLI::App app("Compares a board's recorded pins with the simulated plotter's for the same job");
  app.add_option("--reference", o.reference, "the simulated plotter's waveform")->required();
  app.add_option("--recorded", o.recorded, "the board's waveform")->required();
  app.add_flag("--prefix", o.prefix, "the recording was cut by a STOP");
  app.add_option("--min-pulse-ns", o.min_pulse_ns, "shortest STEP high time the drivers take")
      ->capture_default_str();
  app.add_option("--min-dir-setup-ns", o.min_dir_setup_ns,
                 "shortest DIR change to STEP edge the drivers take")
      ->capture_default_str();
  app.add_option("--servo-wait-ns", o.servo_wait_ns,
                 "longest a servo pen's change waits for its pulse (default: one PWM period)")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    return fdsurf::sim::Check(o);
  } catch (const fdsurf::sim::WaveformError& e) {
    std::fprintf(stderr, "fdsurf_waveform_check: error: %s\n", e.what());
    return 2;
  }
}
