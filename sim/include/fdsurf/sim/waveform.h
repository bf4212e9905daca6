// SPDX-License-Identifier: MIT
// The waveform format (text, version 1): every change of a board's
// step/dir/enable/pen pins with its time in nanoseconds. The simulated
// plotter writes it (from its recorded events), the emulator harnesses of
// the reference boards write it (from the emulated pins), and one decoder
// turns either back into unit moves and pen changes, measuring the pulse
// timing on the way (docs/boards.md).
//
//   # fdsurf-waveform 1
//   # board mega2560-ramps
//   # dir_negative_level 1        the DIR level that means "towards negative"
//   # enable_active_level 0       ENABLE level that energises the motors
//   # pen servo 1000 2000         or "# pen line 1": PEN level 1 = down
//   0 X_EN 1
//   1234567 X_STEP 1
//
// Data lines are `<time_ns> <SIGNAL> <level>`, times non-decreasing. The
// first line of a signal is its initial level (not a change); STEP lines
// start low, so a first STEP 1 is a rising edge. Other `# key value` lines
// are kept in WaveformHeader::extra (the simulated plotter writes the job's
// limits there: tick_hz, max_rate, accel, pen_delay_ms, axes).
#pragma once

#include <array>
#include <cstdint>
#include <istream>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/sim.h"

namespace fdsurf::sim {

/// A malformed waveform; the message names the file and the line.
class WaveformError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The recorded pins. STEP/DIR/EN of axis a are 3·a, 3·a + 1, 3·a + 2.
enum class WaveSignal : std::uint8_t {
  kXStep,
  kXDir,
  kXEn,
  kYStep,
  kYDir,
  kYEn,
  kZStep,
  kZDir,
  kZEn,
  kPen,
  kServo,
};

/// "X_STEP", ..., "PEN", "SERVO".
const char* SignalName(WaveSignal signal);

/// The STEP, DIR or EN signal of `axis` (0..2).
WaveSignal StepSignal(int axis);
WaveSignal DirSignal(int axis);
WaveSignal EnableSignal(int axis);

enum class PenKind : std::uint8_t {
  kLine,   ///< a PEN level: pen_down_level means down
  kServo,  ///< hobby-servo pulses on SERVO: about servo_up_us up, servo_down_us down
};

struct WaveformHeader {
  std::string board = "sim";
  int dir_negative_level = 1;
  int enable_active_level = 0;
  PenKind pen = PenKind::kLine;
  int pen_down_level = 1;
  std::uint32_t servo_up_us = 1000;
  std::uint32_t servo_down_us = 2000;
  /// Whether a `# pen` line said what the pen is.
  bool pen_declared = false;
  /// Other `# key value` lines, in order of the keys.
  std::map<std::string, std::string> extra;

  /// extra[key] as a number; `fallback` if absent. WaveformError naming the
  /// key if it is not a number.
  FDSURF_NODISCARD double Number(const std::string& key, double fallback) const;
};

/// One line of data: `signal` took `level` at `time_ns`.
struct Transition {
  std::int64_t time_ns = 0;
  WaveSignal signal = WaveSignal::kXStep;
  std::uint8_t level = 0;
  bool operator==(const Transition&) const = default;
};

struct Waveform {
  WaveformHeader header;
  std::vector<Transition> transitions;
};

// --- Writing (the simulated plotter) ----------------------------------------

/// How the simulated plotter's instantaneous Step() is drawn as pins: the
/// STEP lines rise `step_delay_ns` after the tick (after any DIR/EN change
/// of that tick: the direction set-up time) and stay high `pulse_ns`.
struct WaveformWriteOptions {
  int axes = 2;
  std::uint32_t step_delay_ns = 800;
  std::uint32_t pulse_ns = 2000;
};

/// The pins of a run recorded by hal::SimStepDir / hal::SimPen (which start
/// disabled, directions positive, pen up), initial levels at time 0 and then
/// every change, sorted by time, under the header's polarities. The pen must
/// be a PEN line (header.pen == kLine), else std::invalid_argument.
std::vector<Transition> TransitionsFromEvents(const WaveformHeader& header,
                                              const std::vector<hal::StepDirEvent>& steps,
                                              const std::vector<hal::PenEvent>& pens,
                                              const WaveformWriteOptions& options);

/// The SERVO pin of a hal::SimPwm (a hal::ServoPen's channel) from its
/// recorded events, up to `end_us`: the initial level 0, then a pulse at the
/// start of every period while enabled. Periods start at the enable and
/// follow each other; each pulses the width in force at its start, so a new
/// width shows from the next period on, as a timer's buffered compare does.
std::vector<Transition> ServoTransitionsFromPwm(const std::vector<hal::PwmEvent>& pwm,
                                                std::uint64_t end_us);

/// As TransitionsFromEvents, for a servo pen on a hal::SimPwm: the SERVO pin
/// (ServoTransitionsFromPwm) in place of a PEN line. header.pen must be
/// kServo, else std::invalid_argument.
std::vector<Transition> TransitionsFromServoEvents(const WaveformHeader& header,
                                                   const std::vector<hal::StepDirEvent>& steps,
                                                   const std::vector<hal::PwmEvent>& pwm,
                                                   const WaveformWriteOptions& options,
                                                   std::uint64_t end_us);

/// Writes the header and the transitions in the format above.
void WriteWaveform(std::ostream& out, const WaveformHeader& header,
                   const std::vector<Transition>& transitions);

// --- Reading ------------------------------------------------------------------

/// Parses a waveform; `name` (the file) is used in errors. Throws
/// WaveformError for a missing or wrong magic line, a bad header line, an
/// unknown signal, a level other than 0/1, or a time going backwards.
Waveform ReadWaveform(std::istream& in, const std::string& name);

/// Reads the file at `path`; WaveformError naming it if it cannot be opened.
Waveform ReadWaveformFile(const std::string& path);

// --- Decoding -----------------------------------------------------------------

struct DecodeOptions {
  /// STEP rising edges of different axes less than this after the first of
  /// a group form one unit move. 0: half a tick of `tick_hz` (if known,
  /// else of the header's tick_hz, else 5 µs).
  std::int64_t group_window_ns = 0;
  /// The board's step timer (0: the header's tick_hz, if any). When known,
  /// the µs times of the decoded events are snapped to its tick grid (phase
  /// from the first STEP edge), so interrupt latency of a few cycles does
  /// not read as a shorter step interval.
  std::uint32_t tick_hz = 0;
  /// Timing requirements of the stepper drivers (A4988: 1 µs, 200 ns).
  std::int64_t min_pulse_ns = 1000;
  std::int64_t min_dir_setup_ns = 200;
};

/// One unit move: the axes stepped together, the directions of every axis
/// in force (bit set: towards negative), the time of its first STEP edge.
struct UnitMove {
  std::int64_t time_ns = 0;
  std::uint8_t axis_mask = 0;
  std::uint8_t negative_mask = 0;
};

struct PenChange {
  std::int64_t time_ns = 0;
  bool down = false;
  /// Unit moves before it.
  std::size_t moves_before = 0;
};

/// What the decoder measured on the pins. -1: nothing to measure.
struct WaveformTiming {
  std::int64_t min_pulse_ns = -1;      ///< shortest STEP high time
  std::int64_t min_dir_setup_ns = -1;  ///< shortest DIR change to that axis's next STEP edge
  std::size_t short_pulses = 0;        ///< below DecodeOptions::min_pulse_ns
  std::size_t short_dir_setups = 0;    ///< below DecodeOptions::min_dir_setup_ns
  std::size_t steps_while_disabled = 0;
  /// The shortest time between two consecutive unit moves or pen changes
  /// (-1: fewer than two). A device makes at most one of them per tick, so
  /// with the tick rate known, an interval under half a tick is counted in
  /// crowded_ticks: two moves in one tick (a late interrupt followed by an
  /// on-time one stays above half a tick on the boards).
  std::int64_t min_event_interval_ns = -1;
  std::size_t crowded_ticks = 0;
  /// Servo pen: the longest interval between pulses (the PWM period).
  std::int64_t servo_period_ns = 0;
  std::int64_t duration_ns = 0;  ///< time of the last transition
  /// The first of the problems counted above, with its time ("" if none).
  std::string first_problem;
  FDSURF_NODISCARD std::size_t problems() const {
    return short_pulses + short_dir_setups + steps_while_disabled + crowded_ticks;
  }
};

struct DecodedWaveform {
  std::vector<UnitMove> moves;
  std::vector<PenChange> pens;
  /// The same as the simulator's events (µs): a step event per unit move,
  /// an axis_mask 0 event per DIR or EN change, for sim::CheckMotion and
  /// sim::ReplayEvents.
  std::vector<hal::StepDirEvent> step_events;
  std::vector<hal::PenEvent> pen_events;
  WaveformTiming timing;
};

/// Decodes the pins into unit moves and pen changes, with the timing report.
/// Throws WaveformError if SERVO pulses appear but the header does not
/// declare a servo pen (its widths are needed to read them).
DecodedWaveform DecodeWaveform(const Waveform& waveform, const DecodeOptions& options = {});

}  // namespace fdsurf::sim
