// SPDX-License-Identifier: MIT
// CheckMotion's per-axis acceleration on synthetic step trains whose motion
// is known analytically: a constant-acceleration ramp on X and a circle at
// constant speed (centripetal v²/r on each axis). The reference is the
// analytic motion over the same windows, never the checker.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "fdsurf/sim/checks.h"

namespace fdsurf::sim {
namespace {

constexpr std::uint32_t kTickHz = 40000;
constexpr double kWindow = 0.02;
constexpr double kPi = 3.14159265358979323846;

using Motion = std::function<std::array<double, 3>(double)>;

// The steps of `motion` (steps as a function of seconds) sampled at every
// tick: an axis steps when its rounded position changes, so the counted
// position is always within half a step of the motion.
std::vector<hal::StepDirEvent> StepsOf(const Motion& motion, double duration_s) {
  std::vector<hal::StepDirEvent> steps;
  std::array<long long, 3> at{};
  for (int axis = 0; axis < 3; ++axis) at[axis] = std::llround(motion(0)[axis]);
  const auto ticks = static_cast<std::uint64_t>(duration_s * kTickHz);
  for (std::uint64_t k = 1; k <= ticks; ++k) {
    const std::array<double, 3> p = motion(static_cast<double>(k) / kTickHz);
    hal::StepDirEvent e{k * 1'000'000 / kTickHz, 0, 0, true};
    for (int axis = 0; axis < 3; ++axis) {
      const long long target = std::llround(p[axis]);
      if (target == at[axis]) continue;
      EXPECT_EQ(std::llabs(target - at[axis]), 1) << "more than a step a tick at tick " << k;
      e.axis_mask |= static_cast<std::uint8_t>(1 << axis);
      if (target < at[axis]) e.negative_mask |= static_cast<std::uint8_t>(1 << axis);
      at[axis] = target;
    }
    if (e.axis_mask != 0) steps.push_back(e);
  }
  return steps;
}

// The largest change of the motion's exact average velocity between
// neighbouring windows, divided by the window, over the windows CheckMotion
// tiles (from t = 0, the first compared with rest, up to the last step). The
// motions here are at rest after their last step.
double ExactWindowedAccel(const Motion& motion, int axis, double last_step_s) {
  const std::array<double, 3> origin = motion(0);
  const auto x = [&](double t) { return motion(t)[axis] - origin[axis]; };
  double largest = 0;
  double previous = 0;
  for (double t = 0; t < last_step_s; t += kWindow) {
    const double velocity = (x(t + kWindow) - x(t)) / kWindow;
    largest = std::max(largest, std::fabs(velocity - previous) / kWindow);
    previous = velocity;
  }
  return largest;
}

// Path limits far beyond these motions, so that only the axis check counts.
MotionLimitsSi GenerousLimits(double axis_accel) {
  MotionLimitsSi limits;
  limits.tick_hz = kTickHz;
  limits.max_rate = kTickHz;
  limits.accel = 1e9;
  limits.axis_accel = axis_accel;
  return limits;
}

// docs/motion.md: a counted position is within a step of the axis's
// continuous one, so each windowed change errs by under 4/W: 4/W² in accel.
constexpr double kQuantisation = 4 / (kWindow * kWindow);

TEST(CheckMotionAxisAccel, MeasuresAConstantAccelerationRampOnX) {
  // 0.1 s at +a then 0.1 s at −a: 10 000 steps/s at the top, 1000 steps.
  constexpr double a = 100000;
  constexpr double ramp = 0.1;
  const Motion motion = [](double t) -> std::array<double, 3> {
    if (t <= ramp) return {0.5 * a * t * t, 0, 0};
    const double u = std::min(t, 2 * ramp) - ramp;
    return {0.5 * a * ramp * ramp + a * ramp * u - 0.5 * a * u * u, 0, 0};
  };
  const std::vector<hal::StepDirEvent> steps = StepsOf(motion, 2 * ramp + 0.05);
  const double last_step_s = static_cast<double>(steps.back().time_us) * 1e-6;
  const MotionReport report = CheckMotion(steps, {}, GenerousLimits(0), kWindow);
  const double exact = ExactWindowedAccel(motion, 0, last_step_s);
  EXPECT_NEAR(exact, a, 1e-6 * a);  // whole windows inside a ramp see exactly a
  EXPECT_NEAR(report.max_axis_accel[0], exact, kQuantisation);
  EXPECT_EQ(report.max_axis_accel[1], 0);
  EXPECT_EQ(report.max_axis_accel[2], 0);
  EXPECT_EQ(report.violations, 0u) << report.first_violation;  // 0: not checked
  // Held to its own acceleration it passes; to 80 % of it, X is named.
  EXPECT_EQ(CheckMotion(steps, {}, GenerousLimits(a), kWindow).violations, 0u);
  const MotionReport tight = CheckMotion(steps, {}, GenerousLimits(0.8 * a), kWindow);
  EXPECT_GT(tight.violations, 0u);
  EXPECT_EQ(tight.first_violation.rfind("axis X: ", 0), 0u) << tight.first_violation;
}

TEST(CheckMotionAxisAccel, TheAllowanceCoversCountingInWholeSteps) {
  // A gentle trapezoid (1000 steps/s² to 1010.5 steps/s): windows of the
  // cruise hold 20 or 21 steps, so the counted velocity jumps by 1/W =
  // 50 steps/s where the motion's does not change, more than a·W = 20.
  constexpr double a = 1000;
  constexpr double ramp = 1.0105;
  constexpr double cruise = 0.5;
  const Motion motion = [&](double t) -> std::array<double, 3> {
    const double up = std::min(t, ramp);
    const double level = std::clamp(t - ramp, 0.0, cruise);
    const double down = std::clamp(t - ramp - cruise, 0.0, ramp);
    return {0.5 * a * up * up + a * ramp * (level + down) - 0.5 * a * down * down, 0, 0};
  };
  const std::vector<hal::StepDirEvent> steps = StepsOf(motion, 2 * ramp + cruise + 0.05);
  const MotionReport report = CheckMotion(steps, {}, GenerousLimits(a), kWindow);
  EXPECT_GT(report.max_axis_accel[0], 2 * a);  // the counting, not the motion
  EXPECT_LE(report.max_axis_accel[0], a + kQuantisation);
  EXPECT_EQ(report.violations, 0u) << report.first_violation;
}

TEST(CheckMotionAxisAccel, CountsAReversalAtSpeedWithItsDirection) {
  // X at 5000 steps/s turns back at once at 0.1 s (a window boundary): its
  // velocity changes by 2·5000 steps/s between two windows. Counted without
  // the direction, the speed would not change at all there.
  constexpr double v = 5000;
  constexpr double turn = 0.1;
  const Motion motion = [](double t) -> std::array<double, 3> {
    return {t <= turn ? v * t : std::max(0.0, v * (2 * turn - t)), 0, 0};
  };
  const std::vector<hal::StepDirEvent> steps = StepsOf(motion, 2 * turn + 0.05);
  const double last_step_s = static_cast<double>(steps.back().time_us) * 1e-6;
  const MotionReport report = CheckMotion(steps, {}, GenerousLimits(0), kWindow);
  const double exact = ExactWindowedAccel(motion, 0, last_step_s);
  EXPECT_NEAR(exact, 2 * v / kWindow, 1e-6 * v / kWindow);
  EXPECT_NEAR(report.max_axis_accel[0], exact, kQuantisation);
}

TEST(CheckMotionAxisAccel, MeasuresTheCentripetalAccelerationOfACircle) {
  // r = 4000 steps at 20 000 steps/s (ω = 5 rad/s): v²/r = 100 000 steps/s²
  // on each axis. The angle ramps up over 1 s and down over 1 s around three
  // laps at full speed (tangential r·α = 20 000 steps/s² while ramping).
  constexpr double r = 4000;
  constexpr double omega = 5;
  constexpr double ramp = 1;
  constexpr double cruise = 3 * 2 * kPi / omega;
  const auto angle = [&](double t) {
    const double alpha = omega / ramp;
    if (t <= ramp) return 0.5 * alpha * t * t;
    const double at_cruise = 0.5 * alpha * ramp * ramp;
    if (t <= ramp + cruise) return at_cruise + omega * (t - ramp);
    const double u = std::min(t - ramp - cruise, ramp);
    return at_cruise + omega * cruise + omega * u - 0.5 * alpha * u * u;
  };
  const Motion motion = [&](double t) -> std::array<double, 3> {
    return {5000 + r * std::cos(angle(t)), 5000 + r * std::sin(angle(t)), 0};
  };
  const std::vector<hal::StepDirEvent> steps = StepsOf(motion, 2 * ramp + cruise + 0.05);
  const double last_step_s = static_cast<double>(steps.back().time_us) * 1e-6;
  const MotionReport report = CheckMotion(steps, {}, GenerousLimits(0), kWindow);
  const double centripetal = r * omega * omega;
  for (int axis = 0; axis < 2; ++axis) {
    const double exact = ExactWindowedAccel(motion, axis, last_step_s);
    // Windows of W see r·ω²·sinc²(ωW/2) at their best phase, within ωW/2 of
    // the peak; the ramps' tangential part adds at most √(1 + (α/ω²)²).
    const double half = omega * kWindow / 2;
    const double smoothing = std::pow(std::sin(half) / half, 2) * std::cos(half);
    EXPECT_GE(exact, centripetal * smoothing) << axis;
    EXPECT_LE(exact, centripetal * std::hypot(1.0, 1.0 / (ramp * omega))) << axis;
    EXPECT_NEAR(report.max_axis_accel[axis], exact, kQuantisation) << axis;
  }
  EXPECT_EQ(report.max_axis_accel[2], 0);
}

}  // namespace
}  // namespace fdsurf::sim
