// SPDX-License-Identifier: MIT
// The machine time of WriteGcode's program on a G-code machine: the moves
// the program makes, at the feeds it gives, planned as Grbl's planner plans
// them (trapezoidal speed per move, a junction speed between moves from the
// junction deviation, a stop at every dwell, pen switch and pause).
// docs/toolpaths.md, "Time estimate", derives it.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "fdsurf/host/toolpath.h"
#include "fdsurf/host/writers.h"

namespace fdsurf::host {

/// What the program does, measured in output units and seconds.
struct GcodeEstimate {
  /// Machine time from the first command to M2, seconds: motion, dwells;
  /// the pauses between layers (M0) take none.
  double seconds = 0;
  /// Length of the drawing moves (G1 with the pen down; in 3-D with Z).
  double pen_down_length = 0;
  /// Length of the G0 moves in the XY plane (origin → strokes → origin).
  double travel_length = 0;
  /// Pen lifts after a stroke: one per stroke.
  std::size_t pen_lifts = 0;
  /// The toolpath's dims: 3 gives the extent a z range.
  int dims = 2;
  /// Whether any point is drawn; then lo/hi bound the drawn points (x, y,
  /// and z in 3-D), output units.
  bool drew = false;
  std::array<double, 3> lo{};
  std::array<double, 3> hi{};
};

/// The estimate of WriteGcode(path, options)'s program. With
/// options.accel == 0 every move takes length / rate (acceleration
/// ignored). Throws OptionError ("pen") for a pen that is not z, m3 or
/// servo, as the writer does.
GcodeEstimate EstimateGcode(const Toolpath& path, const GcodeOptions& options);

/// The time of one move of length `length` that enters at speed
/// `entry_speed`, leaves at `exit_speed` and may go no faster than
/// `rate`, with acceleration `accel` (units, units/s, units/s²): a
/// trapezoid, or a triangle when the move is too short to reach `rate`.
/// The speeds must be reachable: |exit² − entry²| ≤ 2·accel·length.
double TrapezoidSeconds(double length, double entry_speed, double exit_speed, double rate,
                        double accel);

/// The largest speed at which Grbl's planner passes the join of two moves
/// along unit vectors `from` and `to`: sqrt(a·δ·s / (1 − s)), s = sin(θ/2),
/// θ the angle between the moves, δ the junction deviation; unlimited for a
/// straight continuation, 0 for a reversal. Returns the speed squared
/// (units²/s²), or a huge value for "unlimited".
double JunctionSpeedSquared(const std::array<double, 3>& from, const std::array<double, 3>& to,
                            double accel, double junction_deviation);

/// The estimate as G-code header comment lines (ASCII, each at most 80
/// characters, no parentheses or semicolons): machine time, pen-down and
/// travel distance, pen lifts, extent, and the settings it assumed.
std::vector<std::string> DescribeGcodeEstimate(const GcodeEstimate& estimate,
                                               const GcodeOptions& options,
                                               const std::string& units);

}  // namespace fdsurf::host
