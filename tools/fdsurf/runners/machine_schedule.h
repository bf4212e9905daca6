// SPDX-License-Identifier: MIT
// A job's schedule in machine time: when each command had finished executing
// on the simulated plotter (a dry run in virtual time, sim_runner.cc), so that
// a real run's progress line can say how much machine time has passed and how
// much is left from the device's executed count alone.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace fdsurf::host {

struct MachineSchedule {
  /// executed_s[k]: the machine time, in seconds from the start of the job,
  /// by which k + 1 commands had been executed (non-decreasing; the pauses
  /// between layers take no machine time).
  std::vector<double> executed_s;
  /// The machine tick rate the schedule was computed with, Hz.
  std::uint32_t tick_hz = 0;

  /// When the last command had been executed: the job's machine time.
  [[nodiscard]] double total_s() const { return executed_s.empty() ? 0 : executed_s.back(); }
};

/// Machine time done and left, seconds.
struct TimeLeft {
  double elapsed_s = 0;
  double left_s = 0;
};

/// The machine time by which `executed` commands were done in the schedule,
/// plus `running_s` into the next command (at most its scheduled length:
/// the time the device has spent on it so far, for a smooth reading when a
/// command runs for seconds), and what the schedule has after that. A count
/// beyond the schedule (a job refitted to the device, FitJobToDevice) counts
/// as the end.
inline TimeLeft TimeLeftAt(const MachineSchedule& schedule, std::uint64_t executed,
                           double running_s = 0) {
  const auto done_by = [&schedule](std::uint64_t count) {
    if (count == 0 || schedule.executed_s.empty()) return 0.0;
    const std::uint64_t last = std::min<std::uint64_t>(count, schedule.executed_s.size());
    return schedule.executed_s[static_cast<std::size_t>(last) - 1];
  };
  TimeLeft t;
  const double next = done_by(executed + 1);
  t.elapsed_s = std::min(next, done_by(executed) + std::max(0.0, running_s));
  t.left_s = std::max(0.0, schedule.total_s() - t.elapsed_s);
  return t;
}

/// Seconds as a clock reading, rounded to the second: "0:07", "4:56",
/// "1:02:03".
inline std::string FormatClock(double seconds) {
  const auto whole = static_cast<long long>(std::llround(std::max(0.0, seconds)));
  char text[32];
  if (whole >= 3600) {
    std::snprintf(text, sizeof text, "%lld:%02lld:%02lld", whole / 3600, whole / 60 % 60,
                  whole % 60);
  } else {
    std::snprintf(text, sizeof text, "%lld:%02lld", whole / 60, whole % 60);
  }
  return text;
}

/// "elapsed 1:23, about 4:56 left" (machine time) for the progress line.
inline std::string DescribeTimeLeft(const MachineSchedule& schedule, std::uint64_t executed,
                                    double running_s = 0) {
  const TimeLeft t = TimeLeftAt(schedule, executed, running_s);
  return "elapsed " + FormatClock(t.elapsed_s) + ", about " + FormatClock(t.left_s) + " left";
}

}  // namespace fdsurf::host
