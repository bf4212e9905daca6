// SPDX-License-Identifier: MIT
#include "fdsurf/sim/waveform.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace fdsurf::sim {
namespace {

constexpr const char* kMagic = "# fdsurf-waveform 1";
constexpr int kSignals = 11;
constexpr const char* kSignalNames[kSignals] = {"X_STEP", "X_DIR", "X_EN",   "Y_STEP",
                                                "Y_DIR",  "Y_EN",  "Z_STEP", "Z_DIR",
                                                "Z_EN",   "PEN",   "SERVO"};

int Index(WaveSignal signal) { return static_cast<int>(signal); }

std::string Trim(const std::string& text) {
  const std::size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  const std::size_t end = text.find_last_not_of(" \t\r");
  return text.substr(begin, end - begin + 1);
}

// A 0 or 1 header value; WaveformError naming the key otherwise.
int HeaderLevel(const std::string& value, const std::string& key, const std::string& where) {
  if (value != "0" && value != "1") {
    throw WaveformError(where + ": " + key + " must be 0 or 1, not '" + value + "'");
  }
  return value == "1" ? 1 : 0;
}

std::uint32_t HeaderMicros(const std::string& value, const std::string& where) {
  char* end = nullptr;
  errno = 0;
  const unsigned long us = std::strtoul(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || errno != 0 || us == 0 || us > 100000) {
    throw WaveformError(where + ": servo pulse '" + value + "' is not a width in µs (1..100000)");
  }
  return static_cast<std::uint32_t>(us);
}

void ParsePen(const std::string& value, WaveformHeader* header, const std::string& where) {
  std::istringstream words(value);
  std::string kind, a, b, rest;
  words >> kind >> a >> b >> rest;
  if (kind == "line" && !a.empty() && b.empty()) {
    header->pen = PenKind::kLine;
    header->pen_down_level = HeaderLevel(a, "pen line", where);
    return;
  }
  if (kind == "servo" && !b.empty() && rest.empty()) {
    header->pen = PenKind::kServo;
    header->servo_up_us = HeaderMicros(a, where);
    header->servo_down_us = HeaderMicros(b, where);
    if (header->servo_up_us == header->servo_down_us) {
      throw WaveformError(where + ": the servo's up and down pulses are both " + a + " µs");
    }
    return;
  }
  throw WaveformError(where + ": pen must be 'line LEVEL' or 'servo UP_US DOWN_US', not '" + value +
                      "'");
}

void ParseHeaderLine(const std::string& line, WaveformHeader* header, const std::string& where) {
  const std::string body = Trim(line.substr(1));
  if (body.empty()) return;
  const std::size_t space = body.find_first_of(" \t");
  const std::string key = body.substr(0, space);
  const std::string value = space == std::string::npos ? "" : Trim(body.substr(space));
  if (key == "board") {
    header->board = value;
  } else if (key == "dir_negative_level") {
    header->dir_negative_level = HeaderLevel(value, key, where);
  } else if (key == "enable_active_level") {
    header->enable_active_level = HeaderLevel(value, key, where);
  } else if (key == "pen") {
    ParsePen(value, header, where);
    header->pen_declared = true;
  } else {
    header->extra[key] = value;
  }
}

Transition ParseDataLine(const std::string& line, const std::string& where) {
  std::istringstream words(line);
  std::string time, name, level, rest;
  words >> time >> name >> level >> rest;
  if (level.empty() || !rest.empty()) {
    throw WaveformError(where + ": expected '<time_ns> <SIGNAL> <level>', got '" + line + "'");
  }
  Transition t;
  char* end = nullptr;
  errno = 0;
  t.time_ns = std::strtoll(time.c_str(), &end, 10);
  if (*end != '\0' || errno != 0 || t.time_ns < 0) {
    throw WaveformError(where + ": time '" + time + "' is not a whole number of ns ≥ 0");
  }
  const auto* found = std::find(std::begin(kSignalNames), std::end(kSignalNames), name);
  if (found == std::end(kSignalNames)) {
    throw WaveformError(where + ": unknown signal '" + name + "'");
  }
  t.signal = static_cast<WaveSignal>(found - std::begin(kSignalNames));
  if (level != "0" && level != "1") {
    throw WaveformError(where + ": level of " + name + " must be 0 or 1, not '" + level + "'");
  }
  t.level = level == "1" ? 1 : 0;
  return t;
}

std::string Ns(std::int64_t ns) { return std::to_string(ns) + " ns"; }

}  // namespace

const char* SignalName(WaveSignal signal) { return kSignalNames[Index(signal)]; }
WaveSignal StepSignal(int axis) { return static_cast<WaveSignal>(3 * axis); }
WaveSignal DirSignal(int axis) { return static_cast<WaveSignal>(3 * axis + 1); }
WaveSignal EnableSignal(int axis) { return static_cast<WaveSignal>(3 * axis + 2); }

double WaveformHeader::Number(const std::string& key, double fallback) const {
  const auto it = extra.find(key);
  if (it == extra.end()) return fallback;
  char* end = nullptr;
  const double value = std::strtod(it->second.c_str(), &end);
  if (it->second.empty() || *end != '\0' || !std::isfinite(value)) {
    throw WaveformError("waveform header: " + key + " '" + it->second + "' is not a number");
  }
  return value;
}

// --- Writing ------------------------------------------------------------------

namespace {

// The STEP/DIR/EN pins of the recorded step events, appended to `out`.
void AppendStepDir(const WaveformHeader& header, const std::vector<hal::StepDirEvent>& steps,
                   const WaveformWriteOptions& options, std::vector<Transition>* transitions) {
  std::vector<Transition>& out = *transitions;
  const auto dir_level = [&](bool negative) {
    return static_cast<std::uint8_t>(negative ? header.dir_negative_level
                                              : 1 - header.dir_negative_level);
  };
  const auto enable_level = [&](bool on) {
    return static_cast<std::uint8_t>(on ? header.enable_active_level
                                        : 1 - header.enable_active_level);
  };
  for (int axis = 0; axis < options.axes; ++axis) {
    out.push_back({0, StepSignal(axis), 0});
    out.push_back({0, DirSignal(axis), dir_level(false)});
    out.push_back({0, EnableSignal(axis), enable_level(false)});
  }
  std::uint8_t negative = 0;
  bool enabled = false;
  for (const hal::StepDirEvent& e : steps) {
    const std::int64_t t = static_cast<std::int64_t>(e.time_us) * 1000;
    for (int axis = 0; axis < options.axes && e.enabled != enabled; ++axis) {
      out.push_back({t, EnableSignal(axis), enable_level(e.enabled)});
    }
    enabled = e.enabled;
    for (int axis = 0; axis < options.axes; ++axis) {
      const bool now = (e.negative_mask >> axis & 1) != 0;
      if (now != ((negative >> axis & 1) != 0)) out.push_back({t, DirSignal(axis), dir_level(now)});
    }
    negative = e.negative_mask;
    const std::int64_t rise = t + options.step_delay_ns;
    for (int axis = 0; axis < options.axes; ++axis) {
      if ((e.axis_mask >> axis & 1) == 0) continue;
      out.push_back({rise, StepSignal(axis), 1});
      out.push_back({rise + options.pulse_ns, StepSignal(axis), 0});
    }
  }
}

void SortByTime(std::vector<Transition>* out) {
  std::stable_sort(out->begin(), out->end(),
                   [](const Transition& a, const Transition& b) { return a.time_ns < b.time_ns; });
}

// The settings in force at `t_us`: the last event at or before it.
const hal::PwmEvent* PwmAt(const std::vector<hal::PwmEvent>& events, std::uint64_t t_us) {
  const hal::PwmEvent* in_force = nullptr;
  for (const hal::PwmEvent& e : events) {
    if (e.time_us > t_us) break;
    in_force = &e;
  }
  return in_force;
}

}  // namespace

std::vector<Transition> TransitionsFromEvents(const WaveformHeader& header,
                                              const std::vector<hal::StepDirEvent>& steps,
                                              const std::vector<hal::PenEvent>& pens,
                                              const WaveformWriteOptions& options) {
  if (header.pen != PenKind::kLine) {
    throw std::invalid_argument("the simulated plotter's waveform has a PEN line, not a servo");
  }
  std::vector<Transition> out;
  AppendStepDir(header, steps, options, &out);
  out.push_back({0, WaveSignal::kPen, static_cast<std::uint8_t>(1 - header.pen_down_level)});
  for (const hal::PenEvent& p : pens) {
    const std::int64_t t = static_cast<std::int64_t>(p.time_us) * 1000;
    out.push_back(
        {t, WaveSignal::kPen,
         static_cast<std::uint8_t>(p.down ? header.pen_down_level : 1 - header.pen_down_level)});
  }
  SortByTime(&out);
  return out;
}

std::vector<Transition> ServoTransitionsFromPwm(const std::vector<hal::PwmEvent>& pwm,
                                                std::uint64_t end_us) {
  std::vector<Transition> out;
  out.push_back({0, WaveSignal::kServo, 0});
  // Periods start when the channel is enabled and follow each other while it
  // stays enabled; each pulses the width in force at its start.
  std::uint64_t start_us = 0;
  bool running = false;
  for (std::size_t i = 0; i < pwm.size(); ++i) {
    const hal::PwmEvent& e = pwm[i];
    if (!e.enabled) {
      running = false;
      continue;
    }
    if (!running) {
      running = true;
      start_us = e.time_us;
    }
    const std::uint64_t until_us = i + 1 < pwm.size() ? pwm[i + 1].time_us : end_us;
    while (start_us <= until_us && start_us < end_us) {
      const hal::PwmEvent* now = PwmAt(pwm, start_us);
      if (now == nullptr || !now->enabled || now->period_us == 0) break;
      if (now->pulse_us > 0) {
        const auto rise = static_cast<std::int64_t>(start_us) * 1000;
        out.push_back({rise, WaveSignal::kServo, 1});
        out.push_back({rise + std::int64_t{now->pulse_us} * 1000, WaveSignal::kServo, 0});
      }
      start_us += now->period_us;
    }
  }
  return out;
}

std::vector<Transition> TransitionsFromServoEvents(const WaveformHeader& header,
                                                   const std::vector<hal::StepDirEvent>& steps,
                                                   const std::vector<hal::PwmEvent>& pwm,
                                                   const WaveformWriteOptions& options,
                                                   std::uint64_t end_us) {
  if (header.pen != PenKind::kServo) {
    throw std::invalid_argument("a servo pen's waveform needs a '# pen servo' header");
  }
  std::vector<Transition> out;
  AppendStepDir(header, steps, options, &out);
  const std::vector<Transition> servo = ServoTransitionsFromPwm(pwm, end_us);
  out.insert(out.end(), servo.begin(), servo.end());
  SortByTime(&out);
  return out;
}

void WriteWaveform(std::ostream& out, const WaveformHeader& header,
                   const std::vector<Transition>& transitions) {
  out << kMagic << "\n# board " << header.board << "\n# dir_negative_level "
      << header.dir_negative_level << "\n# enable_active_level " << header.enable_active_level
      << "\n";
  if (header.pen == PenKind::kLine) {
    out << "# pen line " << header.pen_down_level << "\n";
  } else {
    out << "# pen servo " << header.servo_up_us << " " << header.servo_down_us << "\n";
  }
  for (const auto& [key, value] : header.extra) out << "# " << key << " " << value << "\n";
  char line[64];
  for (const Transition& t : transitions) {
    const int n =
        std::snprintf(line, sizeof line, "%lld %s %u\n", static_cast<long long>(t.time_ns),
                      SignalName(t.signal), static_cast<unsigned>(t.level));
    out.write(line, n);
  }
}

// --- Reading ------------------------------------------------------------------

Waveform ReadWaveform(std::istream& in, const std::string& name) {
  Waveform waveform;
  std::string line;
  std::size_t number = 0;
  if (!std::getline(in, line) || Trim(line) != kMagic) {
    throw WaveformError(name + ":1: not a waveform (the first line must be '" +
                        std::string(kMagic) + "')");
  }
  ++number;
  std::int64_t last = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = name + ":" + std::to_string(number);
    const std::string text = Trim(line);
    if (text.empty()) continue;
    if (text[0] == '#') {
      ParseHeaderLine(text, &waveform.header, where);
      continue;
    }
    const Transition t = ParseDataLine(text, where);
    if (t.time_ns < last) {
      throw WaveformError(where + ": time " + Ns(t.time_ns) + " is before the previous line's " +
                          Ns(last));
    }
    last = t.time_ns;
    waveform.transitions.push_back(t);
  }
  return waveform;
}

Waveform ReadWaveformFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw WaveformError(path + ": cannot open the waveform file");
  return ReadWaveform(in, path);
}

}  // namespace fdsurf::sim
