// SPDX-License-Identifier: MIT
#include "fdsurf/sim/checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "fdsurf/config/nodiscard.h"

namespace fdsurf::sim {
namespace {

using Vec = std::array<double, 3>;

struct Segment {
  Vec a;
  Vec b;
};

double DistanceToSegment(const Vec& p, const Segment& s) {
  Vec ab{};
  Vec ap{};
  double ab2 = 0;
  double dot = 0;
  for (int c = 0; c < 3; ++c) {
    ab[c] = s.b[c] - s.a[c];
    ap[c] = p[c] - s.a[c];
    ab2 += ab[c] * ab[c];
    dot += ab[c] * ap[c];
  }
  const double u = ab2 > 0 ? std::clamp(dot / ab2, 0.0, 1.0) : 0.0;
  double d2 = 0;
  for (int c = 0; c < 3; ++c) {
    const double e = ap[c] - u * ab[c];
    d2 += e * e;
  }
  return std::sqrt(d2);
}

// Segments bucketed by cells of `radius`; each segment goes into every cell
// its box, grown by the radius, touches, so a query looks in one cell only.
class SegmentGrid {
 public:
  SegmentGrid(double radius, int dims) : radius_(radius), dims_(dims) {}

  void Add(const Segment& s) {
    const std::size_t index = segments_.size();
    segments_.push_back(s);
    std::array<std::int64_t, 3> lo{};
    std::array<std::int64_t, 3> hi{};
    for (int c = 0; c < 3; ++c) {
      lo[c] = Cell(std::min(s.a[c], s.b[c]) - radius_);
      hi[c] = Cell(std::max(s.a[c], s.b[c]) + radius_);
      if (c >= dims_) lo[c] = hi[c] = 0;
    }
    for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) cells_[Key(x, y, z)].push_back(index);
      }
    }
  }

  double Nearest(const Vec& p) const {
    const auto it = cells_.find(Key(Cell(p[0]), Cell(p[1]), dims_ == 3 ? Cell(p[2]) : 0));
    double best = radius_;
    if (it == cells_.end()) return best;
    for (const std::size_t index : it->second) {
      best = std::min(best, DistanceToSegment(p, segments_[index]));
    }
    return best;
  }

 private:
  std::int64_t Cell(double v) const { return static_cast<std::int64_t>(std::floor(v / radius_)); }
  static std::uint64_t Key(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto part = [](std::int64_t v) {
      return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1FFFFF;
    };
    return part(x) | part(y) << 21 | part(z) << 42;
  }

  double radius_;
  int dims_;
  std::vector<Segment> segments_;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;
};

Vec ToVec(const std::array<std::int64_t, 3>& p, int dims) {
  return {static_cast<double>(p[0]), static_cast<double>(p[1]),
          dims == 3 ? static_cast<double>(p[2]) : 0.0};
}

}  // namespace

DrawingComparison CompareDrawing(const std::vector<DrawnPath>& drawn,
                                 const std::vector<ReferenceLine>& reference, int dims,
                                 double search_radius) {
  DrawingComparison result;
  SegmentGrid exact(search_radius, dims);
  for (const ReferenceLine& line : reference) {
    for (std::size_t k = 0; k + 1 < line.points.size(); ++k) {
      Segment s{line.points[k], line.points[k + 1]};
      if (dims == 2) s.a[2] = s.b[2] = 0;
      exact.Add(s);
    }
    if (line.points.size() == 1) exact.Add(Segment{line.points[0], line.points[0]});
  }
  SegmentGrid machine(search_radius, dims);
  for (const DrawnPath& path : drawn) {
    for (std::size_t k = 0; k < path.points.size(); ++k) {
      const Vec p = ToVec(path.points[k], dims);
      ++result.drawn_points;
      double d = exact.Nearest(p);
      if (k + 1 < path.points.size()) {
        const Vec q = ToVec(path.points[k + 1], dims);
        machine.Add(Segment{p, q});
        const Vec mid{(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
        d = std::max(d, exact.Nearest(mid));
      }
      if (d > result.max_deviation) {
        result.max_deviation = d;
        result.worst_drawn_point = path.points[k];
      }
    }
  }
  for (const ReferenceLine& line : reference) {
    for (Vec p : line.points) {
      if (dims == 2) p[2] = 0;
      ++result.reference_points;
      const double d = machine.Nearest(p);
      if (d > result.max_gap) {
        result.max_gap = d;
        result.worst_reference_point = p;
      }
    }
  }
  return result;
}

namespace {

std::string Describe(const char* format, double x, double y, double z, double w = 0) {
  char text[200];
  std::snprintf(text, sizeof text, format, x, y, z, w);
  return std::string(text);
}

// The working state of CheckMotion: the report it fills, and the moves'
// completion times with the cumulative path length (steps) and each axis's
// position (signed steps from the start; 32 bits hold any plannable travel,
// 2²⁶) after each.
struct MotionCheck {
  const MotionLimitsSi& limits;
  double tick_s;
  double a;
  MotionReport report;
  std::vector<double> time;
  std::vector<double> distance;
  std::vector<std::array<std::int32_t, 3>> position;
  /// Per move: the pen events before it (its run between rests) and
  /// whether the pen was down.
  std::vector<std::size_t> run;
  std::vector<bool> pen_down;

  FDSURF_NODISCARD double RateFor(bool down) const {
    return down || limits.travel_rate <= 0 ? limits.max_rate : limits.travel_rate;
  }

  void Violation(const std::string& what) {
    if (report.violations++ == 0) report.first_violation = what;
  }
};

// Records the moves, checking each axis's interval between steps (against
// the speed limit of the pen's state at the later step).
void TraceMoves(const std::vector<hal::StepDirEvent>& steps, const std::vector<hal::PenEvent>& pens,
                MotionCheck& c) {
  MotionReport& report = c.report;
  double total = 0;
  std::array<double, 3> last_step{-1, -1, -1};
  std::array<std::int32_t, 3> position{};
  report.min_axis_interval_us = HUGE_VAL;
  const auto min_interval_s = [&c](bool down) {
    return std::floor(static_cast<double>(c.limits.tick_hz) / c.RateFor(down)) * c.tick_s;
  };
  std::size_t pens_before = 0;
  for (const hal::StepDirEvent& e : steps) {
    if (e.axis_mask == 0) continue;
    while (pens_before < pens.size() && pens[pens_before].time_us <= e.time_us) ++pens_before;
    const bool down = pens_before > 0 && pens[pens_before - 1].down;
    const double t = e.time_us * 1e-6;
    int axes = 0;
    for (int axis = 0; axis < 3; ++axis) {
      if ((e.axis_mask >> axis & 1) == 0) continue;
      ++axes;
      if (last_step[axis] >= 0) {
        const double interval = t - last_step[axis];
        report.min_axis_interval_us = std::min(report.min_axis_interval_us, interval * 1e6);
        if (interval < min_interval_s(down) - 1e-9) {
          c.Violation(
              Describe("axis %.0f stepped %.1f µs after its previous step (at least %.1f µs)", axis,
                       interval * 1e6, min_interval_s(down) * 1e6));
        }
      }
      last_step[axis] = t;
      position[axis] += (e.negative_mask >> axis & 1) != 0 ? -1 : 1;
    }
    total += std::sqrt(static_cast<double>(axes));
    c.time.push_back(t);
    c.distance.push_back(total);
    c.position.push_back(position);
    c.run.push_back(pens_before);
    c.pen_down.push_back(down);
  }
  report.moves = c.time.size();
  report.path_length = total;
  report.duration_s = c.time.empty() ? 0 : c.time.back();
}

// Pen changes happen at rest and are followed by the pen delay.
void CheckPenDelays(const std::vector<hal::PenEvent>& pens, MotionCheck& c) {
  for (const hal::PenEvent& pen : pens) {
    const double t = pen.time_us * 1e-6;
    const auto after = std::lower_bound(c.time.begin(), c.time.end(), t - 1e-9);
    if (after != c.time.end() && *after < t + c.limits.pen_delay_s - 1e-9) {
      c.Violation(Describe("a step %.1f µs after the pen change at %.6f s (pen delay %.0f ms)",
                           (*after - t) * 1e6, t, c.limits.pen_delay_s * 1e3));
    }
  }
}

// Between two rests (the start, pen changes) the machine starts from rest
// and comes to rest: x ≤ a·(t − t0 + 1.5·tick)²/2 after the start, and the
// distance left ≤ a·(t1 − t + 1.5·tick)²/2 before the stop. The 1.5 ticks
// allow for speed changing in whole ticks: k ticks of a speed that grows
// by a·tick each cover a·tick²·k(k+1)/2 ≤ a·((k + 1/2)·tick)²/2.
void CheckRests(const std::vector<hal::PenEvent>& pens, MotionCheck& c) {
  const std::vector<double>& time = c.time;
  const std::vector<double>& distance = c.distance;
  const double a = c.a;
  std::vector<double> rests{0.0};
  for (const hal::PenEvent& pen : pens) rests.push_back(pen.time_us * 1e-6);
  std::size_t k = 0;
  for (std::size_t r = 0; r < rests.size(); ++r) {
    const double start = r == 0 ? 0.0 : rests[r] + c.limits.pen_delay_s;
    const bool stops = r + 1 < rests.size();
    const double stop = stops ? rests[r + 1] : HUGE_VAL;
    const std::size_t first = k;
    while (k < time.size() && time[k] < stop) ++k;
    if (first == k) continue;
    const double base = first == 0 ? 0.0 : distance[first - 1];
    const double end = distance[k - 1];
    for (std::size_t i = first; i < k; ++i) {
      const double from_start = distance[i] - base;
      const double span = time[i] - start + 1.5 * c.tick_s;
      if (from_start > 0.5 * a * span * span + 1e-9) {
        c.Violation(
            Describe("%.2f steps covered %.6f s after a start from rest (accel limit allows %.2f)",
                     from_start, span, 0.5 * a * span * span));
      }
      if (stops) {
        const double left = end - distance[i];
        const double until = stop - time[i] + 1.5 * c.tick_s;
        if (left > 0.5 * a * until * until + 1e-9) {
          c.Violation(
              Describe("%.2f steps left %.6f s before a stop at rest (accel limit allows %.2f)",
                       left, until, 0.5 * a * until * until));
        }
      }
    }
  }
}

// Speed over windows of at least window_s: x_j − x_i ≤ v·(t_j − t_i) + 1
// (the phase carried into and out of the window is below one step). v is
// the limit of the pen's state (max_rate down, travel_rate up) for a window
// within one run between pen changes, the larger of the two for a window
// over a pen change (the machine rests there, so that is generous).
void CheckWindowSpeed(double window_s, MotionCheck& c) {
  std::size_t i = 0;
  for (std::size_t j = 0; j < c.time.size(); ++j) {
    while (i + 1 < j && c.time[j] - c.time[i + 1] >= window_s) ++i;
    const double span = c.time[j] - c.time[i];
    if (span < window_s) continue;
    const double covered = c.distance[j] - c.distance[i];
    const double speed = covered / span;
    c.report.max_speed = std::max(c.report.max_speed, speed);
    const bool one_run = c.run[i] == c.run[j];
    if (one_run) {
      double& largest = c.pen_down[j] ? c.report.max_draw_speed : c.report.max_travel_speed;
      largest = std::max(largest, speed);
    }
    const double limit =
        one_run ? c.RateFor(c.pen_down[j]) : std::max(c.RateFor(true), c.RateFor(false));
    if (covered > limit * span + 1.0 + 1e-9) {
      c.Violation(Describe("%.1f steps in %.6f s: faster than %.0f steps/s", covered, span, limit) +
                  (c.pen_down[j] ? " (pen down)" : " (pen up)"));
    }
  }
}

// Windows of window_s tiled from t = 0 over the run, for a quantity known
// after each move (value(k) just after move k, 0 before the first): calls
// on_change(t, change) with the change of its average rate from the window
// before t to the window [t, t + W). The first window is compared with rest.
template <typename Value, typename OnChange>
void ForEachWindowChange(const std::vector<double>& time, double window_s, const Value& value,
                         const OnChange& on_change) {
  const auto value_at = [&](double t) {
    const auto it = std::upper_bound(time.begin(), time.end(), t);
    return it == time.begin() ? 0.0 : value(static_cast<std::size_t>(it - time.begin()) - 1);
  };
  double previous = 0;
  for (double t = 0; t < time.back(); t += window_s) {
    const double rate = (value_at(t + window_s) - value_at(t)) / window_s;
    on_change(t, rate - previous);
    previous = rate;
  }
}

// Windowed acceleration: average speeds of neighbouring windows differ by
// at most a·W; each estimate errs by under 2·√3/W (a move in progress at
// each end), so the test allows a·W + 4·√3/W.
void CheckWindowAccel(double window_s, MotionCheck& c) {
  const double allowance = c.a * window_s + 4 * std::sqrt(3.0) / window_s;
  ForEachWindowChange(
      c.time, window_s, [&](std::size_t k) { return c.distance[k]; },
      [&](double /*t*/, double signed_change) {
        const double change = std::fabs(signed_change);
        c.report.max_accel = std::max(c.report.max_accel, change / window_s);
        if (change > allowance + 1e-9) {
          c.Violation(Describe("the speed changed by %.1f steps/s within %.3f s (allowed %.1f)",
                               change, window_s, allowance));
        }
      });
}

// The same per axis, on its signed position: the average velocities of
// neighbouring windows differ by at most axis_accel·W; the position counted
// from steps is within one step of the axis's continuous position (a step in
// progress, either way), so each change errs by under 4/W and the test
// allows axis_accel·W + 4/W (docs/motion.md).
void CheckWindowAxisAccel(double window_s, MotionCheck& c) {
  for (int axis = 0; axis < 3; ++axis) {
    const double own = c.limits.axis_accel_each[static_cast<std::size_t>(axis)];
    const double limit = own > 0 ? own : c.limits.axis_accel;
    const double allowance = limit * window_s + 4 / window_s;
    double& largest = c.report.max_axis_accel[axis];
    ForEachWindowChange(
        c.time, window_s, [&](std::size_t k) { return static_cast<double>(c.position[k][axis]); },
        [&](double t, double signed_change) {
          const double change = std::fabs(signed_change);
          largest = std::max(largest, change / window_s);
          if (limit > 0 && change > allowance + 1e-9) {
            c.Violation(std::string("axis ") + "XYZ"[axis] +
                        Describe(": its velocity changed by %.1f steps/s in the %.3f s window at "
                                 "%.6f s (axis accel limit allows %.1f)",
                                 change, window_s, t, allowance));
          }
        });
  }
}

}  // namespace

MotionReport CheckMotion(const std::vector<hal::StepDirEvent>& steps,
                         const std::vector<hal::PenEvent>& pens, const MotionLimitsSi& limits,
                         double window_s) {
  MotionCheck check{limits, 1.0 / limits.tick_hz, limits.accel, {}, {}, {}, {}, {}, {}};
  TraceMoves(steps, pens, check);
  if (check.time.empty()) return check.report;
  CheckPenDelays(pens, check);
  CheckRests(pens, check);
  CheckWindowSpeed(window_s, check);
  CheckWindowAccel(window_s, check);
  CheckWindowAxisAccel(window_s, check);
  return check.report;
}

}  // namespace fdsurf::sim
