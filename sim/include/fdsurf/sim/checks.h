// SPDX-License-Identifier: MIT
// What the simulated plotter checks about a run, from the recorded pin events
// alone: how far the drawing is from the exact (double-precision) curves, and
// whether the motion kept the machine's limits.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fdsurf/hal/sim.h"
#include "fdsurf/sim/plotter.h"

namespace fdsurf::sim {

/// A reference curve as a dense polyline in steps (double precision).
struct ReferenceLine {
  std::vector<std::array<double, 3>> points;
};

struct DrawingComparison {
  /// Largest distance from a drawn point or drawn segment midpoint to the
  /// nearest reference curve, in steps (the deviation of the drawing).
  double max_deviation = 0;
  std::array<std::int64_t, 3> worst_drawn_point{};
  /// Largest distance from a reference point to the nearest drawn segment,
  /// in steps: a curve the machine left out shows up here.
  double max_gap = 0;
  std::array<double, 3> worst_reference_point{};
  std::size_t drawn_points = 0;
  std::size_t reference_points = 0;
};

/// Compares the drawn paths with the reference curves (both in steps; z is
/// used when `dims` is 3). Distances beyond `search_radius` steps are
/// reported as search_radius (they fail any sensible bound anyway).
DrawingComparison CompareDrawing(const std::vector<DrawnPath>& drawn,
                                 const std::vector<ReferenceLine>& reference, int dims,
                                 double search_radius = 16);

/// The limits a run must keep, in steps and seconds.
struct MotionLimitsSi {
  std::uint32_t tick_hz = 40000;
  double max_rate = 0;  ///< path speed with the pen down, steps/s
  /// Path speed with the pen up (travel), steps/s; 0: the same as max_rate.
  double travel_rate = 0;
  double accel = 0;  ///< path acceleration, steps/s²
  /// Acceleration of each axis on its own (the centripetal part on curves
  /// included), steps/s²; 0: measured but not checked.
  double axis_accel = 0;
  /// The same for one axis (x, y, z), over `axis_accel`; 0: `axis_accel`.
  std::array<double, 3> axis_accel_each{0, 0, 0};
  double pen_delay_s = 0;
};

struct MotionReport {
  /// Shortest time between two steps of one axis, µs.
  double min_axis_interval_us = 0;
  /// Fastest path speed over any window of `window_s`, steps/s.
  double max_speed = 0;
  /// The same over windows wholly within one pen-down run, and within one
  /// pen-up run (between two rests at pen changes), steps/s.
  double max_draw_speed = 0;
  double max_travel_speed = 0;
  /// Largest change of the windowed speed between neighbouring windows,
  /// divided by the window: steps/s².
  double max_accel = 0;
  /// Per axis (x, y, z), the largest change of the axis's windowed velocity
  /// (signed steps, so a reversal counts) between neighbouring windows,
  /// divided by the window: steps/s².
  std::array<double, 3> max_axis_accel{};
  /// Violations of: the per-axis step interval, the speed limit (max_rate
  /// with the pen down, travel_rate with it up), the
  /// start-from-rest and stop-at-rest acceleration laws, the pen delay, the
  /// windowed acceleration of the path and (when `axis_accel` is set) of
  /// each axis (each with the quantisation allowance in docs/motion.md).
  std::size_t violations = 0;
  std::string first_violation;
  std::size_t moves = 0;
  double path_length = 0;  ///< steps, pen up and down
  double duration_s = 0;
};

/// Checks the recorded motion against `limits`.
MotionReport CheckMotion(const std::vector<hal::StepDirEvent>& steps,
                         const std::vector<hal::PenEvent>& pens, const MotionLimitsSi& limits,
                         double window_s = 0.02);

}  // namespace fdsurf::sim
