// SPDX-License-Identifier: MIT
// The waveform decoder: pins back into unit moves, pen changes and the
// simulator's events, with the pulse timing measured on the way.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>

#include "fdsurf/sim/waveform.h"

namespace fdsurf::sim {
namespace {

constexpr std::int64_t kDefaultGroupWindowNs = 5000;
// Servo pulses further apart than this are a pause of the PWM, not its period.
constexpr std::int64_t kMaxServoPeriodNs = 60'000'000;

int Index(WaveSignal signal) { return static_cast<int>(signal); }

// STEP and SERVO start low (their first line may be an edge); the others'
// first line is their initial level.
bool IsEdgeSignal(int s) { return s == Index(WaveSignal::kServo) || (s < 9 && s % 3 == 0); }

// Converts pin times (ns) to the simulator's µs, snapped to the board's tick
// grid when its rate is known.
//
// A board writes its pins at different points of its tick interrupt (a pen
// change early, a step after the motion's arithmetic) and the interrupt
// itself may start late, so the nearest grid tick of an edge can be a tick
// off. A device does at most one unit move or one pen change per tick, so
// each of those gets a tick after the previous one's (OwnTickMicros); DIR
// and EN changes happen in the tick of the step they prepare and never
// before the last move or pen change (StateMicros). The order of the
// recording is kept; only times move, by less than a tick.
//
// The grid is counted from the last unit move or pen change (the first STEP
// edge before any): an event is the nearest whole number of ticks after it.
// A grid fixed at the first edge fails when the recording's clock and the
// board's timer differ a little (QEMU's instruction count against its
// virtual clock: ~50 µs a second): the grid slides through the ticks, and
// a 2-tick interval of a late edge then an early one rounded to 1 tick.
class TimeBase {
 public:
  TimeBase(std::uint32_t tick_hz, std::int64_t phase_ns)
      : tick_hz_(tick_hz), phase_ns_(phase_ns), anchor_ns_(phase_ns) {}

  std::uint64_t OwnTickMicros(std::int64_t ns) {
    if (tick_hz_ == 0) return static_cast<std::uint64_t>(ns / 1000);
    std::int64_t index = Index(ns);
    if (has_own_ && index < anchor_index_ + 1) index = anchor_index_ + 1;
    anchor_ns_ = ns;
    anchor_index_ = index;
    has_own_ = true;
    return MicrosOf(index);
  }
  FDSURF_NODISCARD std::uint64_t StateMicros(std::int64_t ns) const {
    if (tick_hz_ == 0) return static_cast<std::uint64_t>(ns / 1000);
    const std::int64_t index = Index(ns);
    return MicrosOf(has_own_ && index < anchor_index_ ? anchor_index_ : index);
  }

 private:
  FDSURF_NODISCARD double TickNs() const { return 1e9 / tick_hz_; }
  // Grid ticks after the phase: the anchor's, plus the nearest whole number
  // of ticks from the anchor's time.
  FDSURF_NODISCARD std::int64_t Index(std::int64_t ns) const {
    return anchor_index_ +
           static_cast<std::int64_t>(std::round(static_cast<double>(ns - anchor_ns_) / TickNs()));
  }
  FDSURF_NODISCARD std::uint64_t MicrosOf(std::int64_t index) const {
    const double grid_ns = static_cast<double>(phase_ns_) + static_cast<double>(index) * TickNs();
    return grid_ns <= 0 ? 0 : static_cast<std::uint64_t>(std::floor(grid_ns * 1e-3 + 1e-6));
  }

  std::uint32_t tick_hz_;
  std::int64_t phase_ns_;
  std::int64_t anchor_ns_;
  std::int64_t anchor_index_ = 0;
  bool has_own_ = false;
};

class Decoder {
 public:
  Decoder(const WaveformHeader& header, const DecodeOptions& options,
          const std::vector<Transition>& transitions);
  DecodedWaveform Run(const std::vector<Transition>& transitions);

 private:
  struct Group {
    std::int64_t time_ns;
    std::uint8_t axis_mask;
    std::uint8_t negative_mask;
    bool enabled;
  };
  struct AxisState {
    int step_level = 0;
    std::int64_t rise_ns = -1;
    std::int64_t dir_change_ns = -1;  // a change not yet followed by a step
  };

  void Apply(const Transition& t);
  void StepEdge(int axis, const Transition& t);
  void DirChange(int axis, const Transition& t);
  void EnableChange(const Transition& t);
  void PenLevel(const Transition& t);
  void ServoEdge(const Transition& t);
  void PenTo(bool down, std::int64_t time_ns);
  void CloseGroup();
  void StateEvent(std::int64_t time_ns, bool dir_change);
  void FlushState();
  FDSURF_NODISCARD bool AxisEnabled(int axis) const {
    return !seen_[Index(EnableSignal(axis))] ||
           level_[Index(EnableSignal(axis))] == header_.enable_active_level;
  }
  FDSURF_NODISCARD bool Enabled() const;
  void Problem(const std::string& what);
  // A unit move or pen change at `time_ns`: the interval since the last one.
  void OwnTick(std::int64_t time_ns);

  const WaveformHeader& header_;
  DecodeOptions options_;
  TimeBase time_;
  std::int64_t last_own_ns_ = -1;
  std::uint32_t tick_hz_;
  std::int64_t window_ns_;
  std::array<bool, 11> seen_{};
  std::array<int, 11> level_{};
  std::array<AxisState, 3> axes_{};
  std::uint8_t stepping_axes_ = 0;  // axes that step anywhere in the waveform
  std::uint8_t negative_ = 0;
  bool enabled_ = false;
  bool pen_down_ = false;
  std::int64_t servo_rise_ns_ = -1;
  std::optional<Group> group_;
  std::optional<hal::StepDirEvent> pending_state_;
  bool pending_is_dir_ = false;
  std::vector<hal::StepDirEvent> held_;  // state events while a group is open
  DecodedWaveform out_;
};

std::int64_t FirstStepRise(const std::vector<Transition>& transitions) {
  for (const Transition& t : transitions) {
    if (IsEdgeSignal(Index(t.signal)) && t.signal != WaveSignal::kServo && t.level == 1) {
      return t.time_ns;
    }
  }
  return 0;
}

std::uint32_t TickHz(const WaveformHeader& header, const DecodeOptions& options) {
  if (options.tick_hz != 0) return options.tick_hz;
  return static_cast<std::uint32_t>(header.Number("tick_hz", 0));
}

Decoder::Decoder(const WaveformHeader& header, const DecodeOptions& options,
                 const std::vector<Transition>& transitions)
    : header_(header),
      options_(options),
      time_(TickHz(header, options), FirstStepRise(transitions)),
      window_ns_(options.group_window_ns),
      tick_hz_(TickHz(header, options)) {
  const std::uint32_t tick_hz = tick_hz_;
  if (window_ns_ <= 0) window_ns_ = tick_hz != 0 ? 500'000'000 / tick_hz : kDefaultGroupWindowNs;
  for (const Transition& t : transitions) {
    if (IsEdgeSignal(Index(t.signal)) && t.signal != WaveSignal::kServo && t.level == 1) {
      stepping_axes_ |= static_cast<std::uint8_t>(1u << (Index(t.signal) / 3));
    }
  }
  stepping_axes_ |= 3;  // X and Y always count (a plotter)
}

bool Decoder::Enabled() const {
  for (int axis = 0; axis < 3; ++axis) {
    if ((stepping_axes_ >> axis & 1) != 0 && !AxisEnabled(axis)) return false;
  }
  return true;
}

void Decoder::OwnTick(std::int64_t time_ns) {
  if (last_own_ns_ >= 0) {
    const std::int64_t interval = time_ns - last_own_ns_;
    WaveformTiming& t = out_.timing;
    if (t.min_event_interval_ns < 0 || interval < t.min_event_interval_ns) {
      t.min_event_interval_ns = interval;
    }
    if (tick_hz_ != 0 && interval * 2 * tick_hz_ < 1'000'000'000) {
      ++t.crowded_ticks;
      Problem("at " + std::to_string(time_ns) + " ns: a move or pen change only " +
              std::to_string(interval) + " ns after the previous one (under half a tick)");
    }
  }
  last_own_ns_ = time_ns;
}

void Decoder::Problem(const std::string& what) {
  if (out_.timing.first_problem.empty()) out_.timing.first_problem = what;
}

DecodedWaveform Decoder::Run(const std::vector<Transition>& transitions) {
  for (const Transition& t : transitions) {
    const int s = Index(t.signal);
    if (!seen_[s] && !IsEdgeSignal(s)) {
      // The first line of a level signal is its initial level.
      seen_[s] = true;
      level_[s] = t.level;
      if (t.signal == WaveSignal::kPen) pen_down_ = t.level == header_.pen_down_level;
      if (s < 9 && s % 3 == 1 && t.level == header_.dir_negative_level) {
        negative_ |= static_cast<std::uint8_t>(1u << (s / 3));
      }
      continue;
    }
    seen_[s] = true;
    if (level_[s] == t.level) continue;
    Apply(t);
    level_[s] = t.level;
  }
  CloseGroup();
  FlushState();
  if (!transitions.empty()) out_.timing.duration_ns = transitions.back().time_ns;
  return std::move(out_);
}

void Decoder::Apply(const Transition& t) {
  const int s = Index(t.signal);
  if (s < 9) {
    const int axis = s / 3;
    if (s % 3 == 0) StepEdge(axis, t);
    if (s % 3 == 1) DirChange(axis, t);
    if (s % 3 == 2) EnableChange(t);
    return;
  }
  if (t.signal == WaveSignal::kPen) PenLevel(t);
  if (t.signal == WaveSignal::kServo) ServoEdge(t);
}

void Decoder::StepEdge(int axis, const Transition& t) {
  AxisState& a = axes_[axis];
  if (t.level == 0) {
    if (a.rise_ns < 0) return;
    const std::int64_t width = t.time_ns - a.rise_ns;
    WaveformTiming& timing = out_.timing;
    if (timing.min_pulse_ns < 0 || width < timing.min_pulse_ns) timing.min_pulse_ns = width;
    if (width < options_.min_pulse_ns) {
      ++timing.short_pulses;
      Problem("at " + std::to_string(a.rise_ns) + " ns: " + SignalName(t.signal) +
              " high for only " + std::to_string(width) + " ns");
    }
    return;
  }
  FlushState();
  a.rise_ns = t.time_ns;
  const char* name = SignalName(t.signal);
  if (!AxisEnabled(axis)) {
    ++out_.timing.steps_while_disabled;
    Problem("at " + std::to_string(t.time_ns) + " ns: " + name + " while the motors are disabled");
  }
  if (a.dir_change_ns >= 0) {
    const std::int64_t setup = t.time_ns - a.dir_change_ns;
    WaveformTiming& timing = out_.timing;
    if (timing.min_dir_setup_ns < 0 || setup < timing.min_dir_setup_ns) {
      timing.min_dir_setup_ns = setup;
    }
    if (setup < options_.min_dir_setup_ns) {
      ++timing.short_dir_setups;
      Problem("at " + std::to_string(t.time_ns) + " ns: " + name + " only " +
              std::to_string(setup) + " ns after its DIR changed");
    }
    a.dir_change_ns = -1;
  }
  const std::uint8_t bit = static_cast<std::uint8_t>(1u << axis);
  if (group_ && (t.time_ns - group_->time_ns >= window_ns_ || (group_->axis_mask & bit) != 0)) {
    CloseGroup();
  }
  if (!group_) group_ = Group{t.time_ns, 0, negative_, enabled_};
  group_->axis_mask |= bit;
  group_->negative_mask =
      static_cast<std::uint8_t>((group_->negative_mask & ~bit) | (negative_ & bit));
}

void Decoder::DirChange(int axis, const Transition& t) {
  const std::uint8_t bit = static_cast<std::uint8_t>(1u << axis);
  negative_ = static_cast<std::uint8_t>(t.level == header_.dir_negative_level ? negative_ | bit
                                                                              : negative_ & ~bit);
  axes_[axis].dir_change_ns = t.time_ns;
  StateEvent(t.time_ns, true);
}

void Decoder::EnableChange(const Transition& t) {
  level_[Index(t.signal)] = t.level;
  if (Enabled() == enabled_) return;
  enabled_ = Enabled();
  StateEvent(t.time_ns, false);
}

// A DIR or EN change as an axis_mask 0 event. DIR changes at the same time
// are one event (one SetDirections()).
void Decoder::StateEvent(std::int64_t time_ns, bool dir_change) {
  const std::uint64_t us = time_.StateMicros(time_ns);
  if (pending_state_ && dir_change && pending_is_dir_ && pending_state_->time_us == us) {
    pending_state_->negative_mask = negative_;
    return;
  }
  FlushState();
  pending_state_ = hal::StepDirEvent{us, 0, negative_, enabled_};
  pending_is_dir_ = dir_change;
}

void Decoder::FlushState() {
  if (!pending_state_) return;
  if (group_) {
    held_.push_back(*pending_state_);
  } else {
    out_.step_events.push_back(*pending_state_);
  }
  pending_state_.reset();
}

void Decoder::CloseGroup() {
  if (!group_) return;
  const Group g = *group_;
  group_.reset();
  out_.moves.push_back(UnitMove{g.time_ns, g.axis_mask, g.negative_mask});
  OwnTick(g.time_ns);
  const std::uint64_t us = time_.OwnTickMicros(g.time_ns);
  out_.step_events.push_back(hal::StepDirEvent{us, g.axis_mask, g.negative_mask, g.enabled});
  // Changes held while the group was open came after its first edge.
  for (hal::StepDirEvent e : held_) {
    e.time_us = std::max(e.time_us, us);
    out_.step_events.push_back(e);
  }
  held_.clear();
}

void Decoder::PenTo(bool down, std::int64_t time_ns) {
  if (down == pen_down_) return;
  CloseGroup();
  FlushState();
  pen_down_ = down;
  out_.pens.push_back(PenChange{time_ns, down, out_.moves.size()});
  OwnTick(time_ns);
  out_.pen_events.push_back(hal::PenEvent{time_.OwnTickMicros(time_ns), down});
}

void Decoder::PenLevel(const Transition& t) {
  if (header_.pen != PenKind::kLine) return;
  PenTo(t.level == header_.pen_down_level, t.time_ns);
}

// A servo pulse's width says where the servo goes: nearer the down width is
// down. The change takes effect at the pulse's rising edge.
void Decoder::ServoEdge(const Transition& t) {
  if (header_.pen != PenKind::kServo) {
    throw WaveformError("waveform of board '" + header_.board + "': SERVO pulses at " +
                        std::to_string(t.time_ns) +
                        " ns, but the header has no '# pen servo UP_US DOWN_US' line");
  }
  if (t.level == 1) {
    if (servo_rise_ns_ >= 0) {
      const std::int64_t period = t.time_ns - servo_rise_ns_;
      if (period <= kMaxServoPeriodNs) {
        out_.timing.servo_period_ns = std::max(out_.timing.servo_period_ns, period);
      }
    }
    servo_rise_ns_ = t.time_ns;
    return;
  }
  if (servo_rise_ns_ < 0) return;
  const double width_us = static_cast<double>(t.time_ns - servo_rise_ns_) * 1e-3;
  const bool down =
      std::fabs(width_us - header_.servo_down_us) < std::fabs(width_us - header_.servo_up_us);
  PenTo(down, servo_rise_ns_);
}

}  // namespace

DecodedWaveform DecodeWaveform(const Waveform& waveform, const DecodeOptions& options) {
  Decoder decoder(waveform.header, options, waveform.transitions);
  return decoder.Run(waveform.transitions);
}

}  // namespace fdsurf::sim
