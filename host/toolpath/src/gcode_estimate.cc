// SPDX-License-Identifier: MIT
#include "fdsurf/host/gcode_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

using Vector = std::array<double, 3>;

// A join speed² that no feed reaches: "no limit at this junction".
constexpr double kUnlimited = std::numeric_limits<double>::max();

// One straight move of the program: its length, direction and top speed.
struct Block {
  double length = 0;  // output units
  Vector unit{};      // direction, length 1
  double rate = 0;    // output units per second
  double accel = 0;   // output units per second², the axes' limits applied
};

Vector Minus(const Vector& a, const Vector& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

// The acceleration a move in direction `unit` (length 1) may have: the
// path's, and no axis beyond its own limit (0: none). Grbl's planner
// (limit_acceleration_by_axis_maximum) limits each block so.
double AccelAlong(const Vector& unit, double accel, const Vector& axis_accel) {
  double limit = accel;
  for (int c = 0; c < 3; ++c) {
    const double share = std::fabs(unit[c]);
    if (axis_accel[c] > 0 && share > 1e-12) limit = std::min(limit, axis_accel[c] / share);
  }
  return limit;
}

// The moves between two stops (a dwell, a pen switch, M0, the start and
// the end), planned as one run: Grbl plans every block in its buffer and
// comes to rest only where the program makes it (an M3/M5, G4, M0 or the
// end of the program empties the planner).
class MotionPlan {
 public:
  MotionPlan(double accel, const Vector& axis_accel, double junction_deviation)
      : accel_(accel), axis_accel_(axis_accel), junction_deviation_(junction_deviation) {}

  // A straight move by `delta` at `rate_per_minute`; zero-length moves are
  // dropped, as Grbl drops them.
  void Move(const Vector& delta, double rate_per_minute) {
    const double length = std::hypot(delta[0], delta[1], delta[2]);
    if (length == 0) return;
    Block block;
    block.length = length;
    for (int c = 0; c < 3; ++c) block.unit[c] = delta[c] / length;
    block.rate = rate_per_minute / 60;
    block.accel = AccelAlong(block.unit, accel_, axis_accel_);
    run_.push_back(block);
  }

  // The machine comes to rest here, then waits `dwell_s`.
  void Stop(double dwell_s) {
    seconds_ += RunSeconds() + dwell_s;
    run_.clear();
  }

  [[nodiscard]] double seconds() const { return seconds_; }

 private:
  // The time of the run: Grbl's planner in one go. Speeds are kept squared:
  // v² grows by 2·a·L along a move at acceleration a.
  FDSURF_NODISCARD double RunSeconds() const {
    if (accel_ <= 0) {
      double t = 0;
      for (const Block& b : run_) t += b.length / b.rate;
      return t;
    }
    const std::size_t n = run_.size();
    std::vector<double> entry(n + 1, 0.0);  // entry[i]: speed² entering block i; entry[n] = 0
    for (std::size_t i = 1; i < n; ++i) {
      const double top = std::min(run_[i - 1].rate, run_[i].rate);
      entry[i] = std::min(top * top, JunctionSpeedSquared(run_[i - 1].unit, run_[i].unit,
                                                          JunctionAccel(i), junction_deviation_));
    }
    for (std::size_t i = n; i-- > 0;) {  // backward: able to slow down for what follows
      entry[i] = std::min(entry[i], entry[i + 1] + 2 * run_[i].accel * run_[i].length);
    }
    for (std::size_t i = 0; i < n; ++i) {  // forward: able to speed up to it
      entry[i + 1] = std::min(entry[i + 1], entry[i] + 2 * run_[i].accel * run_[i].length);
    }
    double t = 0;
    for (std::size_t i = 0; i < n; ++i) {
      t += TrapezoidSeconds(run_[i].length, std::sqrt(entry[i]), std::sqrt(entry[i + 1]),
                            run_[i].rate, run_[i].accel);
    }
    return t;
  }

  // The acceleration of the turn from block i - 1 into block i: the axes'
  // limits along the change of direction, as Grbl's junction_unit_vec.
  FDSURF_NODISCARD double JunctionAccel(std::size_t i) const {
    Vector turn = Minus(run_[i].unit, run_[i - 1].unit);
    const double size = std::hypot(turn[0], turn[1], turn[2]);
    if (size == 0) return accel_;
    for (double& c : turn) c /= size;
    return AccelAlong(turn, accel_, axis_accel_);
  }

  double accel_;
  Vector axis_accel_;
  double junction_deviation_;
  std::vector<Block> run_;
  double seconds_ = 0;
};

void Grow(const Vector& p, int dims, GcodeEstimate* e) {
  for (int c = 0; c < dims; ++c) {
    e->lo[c] = e->drew ? std::min(e->lo[c], p[c]) : p[c];
    e->hi[c] = e->drew ? std::max(e->hi[c], p[c]) : p[c];
  }
  e->drew = true;
}

// The program's moves, in the order WriteGcode writes them, fed to `plan`.
class ProgramWalk {
 public:
  ProgramWalk(const Toolpath& path, const GcodeOptions& options)
      : path_(path),
        options_(options),
        three_d_(path.dims == 3),
        pen_(three_d_ ? "z" : options.pen),
        plan_(options.accel, options.axis_accel, options.junction_deviation),
        at_{0, 0, options.pen_up_z} {
    if (pen_ != "z" && pen_ != "m3" && pen_ != "servo") {
      throw OptionError("pen", options.pen, "is not one of z, m3, servo");
    }
  }

  GcodeEstimate Walk() {
    if (pen_ != "z") plan_.Stop(options_.dwell);  // the first pen-up: M5 or M280, a dwell
    int layer = -1;
    for (const Stroke& s : path_.strokes) {
      if (!path_.layers.empty() && s.layer != layer) {
        if (layer >= 0) plan_.Stop(0);  // M0: at rest, the pause takes no machine time
        layer = s.layer;
      }
      DrawStroke(s);
    }
    Travel({0, 0, at_[2]});  // G0 X0 Y0
    plan_.Stop(0);           // M2
    estimate_.seconds = plan_.seconds();
    estimate_.dims = path_.dims;
    return estimate_;
  }

 private:
  FDSURF_NODISCARD Vector Point(const std::array<std::int64_t, 3>& p) const {
    const double q = path_.quantum.value();
    return {static_cast<double>(p[0]) * q, static_cast<double>(p[1]) * q,
            three_d_ ? static_cast<double>(p[2]) * q : options_.pen_down_z};
  }

  void Travel(const Vector& to) {
    const Vector delta = Minus(to, at_);
    estimate_.travel_length += std::hypot(delta[0], delta[1]);
    plan_.Move(delta, options_.travel_rate);
    at_ = to;
  }

  void DrawStroke(const Stroke& s) {
    const Vector first = Point(s.points.front());
    Travel({first[0], first[1], at_[2]});
    if (pen_ == "z") {  // G1 Z at the plunge feed
      plan_.Move(Minus(first, at_), options_.plunge_feed);
      at_ = first;
    } else {  // M3 or M280 and a dwell
      plan_.Stop(options_.dwell);
      at_ = first;
    }
    Grow(first, path_.dims, &estimate_);
    for (std::size_t k = 1; k < s.points.size(); ++k) {
      const Vector p = Point(s.points[k]);
      const Vector delta = Minus(p, at_);
      estimate_.pen_down_length += std::hypot(delta[0], delta[1], three_d_ ? delta[2] : 0.0);
      plan_.Move(delta, options_.feed);
      Grow(p, path_.dims, &estimate_);
      at_ = p;
    }
    if (pen_ == "z") {  // G0 Z up
      const Vector up{at_[0], at_[1], options_.pen_up_z};
      plan_.Move(Minus(up, at_), options_.travel_rate);
      at_ = up;
    } else {
      plan_.Stop(options_.dwell);
    }
    ++estimate_.pen_lifts;
  }

  const Toolpath& path_;
  const GcodeOptions& options_;
  bool three_d_;
  std::string pen_;
  MotionPlan plan_;
  Vector at_;  // where the tool is; x, y in the plane, z the Z axis (pen z or 3-D)
  GcodeEstimate estimate_;
};

std::string Fixed(double v, int decimals) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

// ", X 500, Y 400 units/s^2 per axis" for the axes with a limit, else ""
// (no parentheses: the line is a parenthesis comment in some flavours).
std::string AxisAccelNote(const Vector& axis_accel, const std::string& units) {
  std::string note;
  for (int c = 0; c < 3; ++c) {
    if (axis_accel[c] <= 0) continue;
    note += std::string(", ") + "XYZ"[c] + " " + FormatNumber(axis_accel[c]);
  }
  return note.empty() ? note : note + " " + units + "/s^2 per axis";
}

std::string Clock(double seconds) {
  const auto whole = static_cast<long long>(std::llround(std::max(0.0, seconds)));
  char text[48];
  std::snprintf(text, sizeof text, "%lld:%02lld:%02lld", whole / 3600, whole / 60 % 60, whole % 60);
  return text;
}

}  // namespace

double TrapezoidSeconds(double length, double entry_speed, double exit_speed, double rate,
                        double accel) {
  // Peak speed of the triangle: accelerating from v0 and decelerating to v1
  // over the whole length, vp² = (2aL + v0² + v1²) / 2.
  const double v0 = entry_speed;
  const double v1 = exit_speed;
  const double peak_squared = (2 * accel * length + v0 * v0 + v1 * v1) / 2;
  if (peak_squared <= rate * rate) {
    const double peak = std::sqrt(peak_squared);
    return (2 * peak - v0 - v1) / accel;
  }
  const double ramps = (2 * rate * rate - v0 * v0 - v1 * v1) / (2 * accel);
  return (2 * rate - v0 - v1) / accel + (length - ramps) / rate;
}

double JunctionSpeedSquared(const Vector& from, const Vector& to, double accel,
                            double junction_deviation) {
  // Grbl's planner (planner.c, plan_buffer_line): cos θ of the angle
  // between the reversed previous direction and the next one.
  const double cos_theta = -(from[0] * to[0] + from[1] * to[1] + from[2] * to[2]);
  if (cos_theta > 0.999999) return 0;            // a reversal
  if (cos_theta < -0.999999) return kUnlimited;  // straight on
  const double sin_half = std::sqrt(0.5 * (1 - cos_theta));
  return accel * junction_deviation * sin_half / (1 - sin_half);
}

GcodeEstimate EstimateGcode(const Toolpath& path, const GcodeOptions& options) {
  return ProgramWalk(path, options).Walk();
}

std::vector<std::string> DescribeGcodeEstimate(const GcodeEstimate& e, const GcodeOptions& o,
                                               const std::string& units) {
  std::vector<std::string> lines;
  lines.push_back("estimated time " + Clock(e.seconds) + " = " + Fixed(e.seconds, 2) +
                  " s of machine time, docs/toolpaths.md");
  lines.push_back("estimate: pen down " + Fixed(e.pen_down_length, 1) + " " + units + ", travel " +
                  Fixed(e.travel_length, 1) + " " + units + ", " + std::to_string(e.pen_lifts) +
                  " pen lift" + (e.pen_lifts == 1 ? "" : "s"));
  if (e.drew) {
    std::string extent = "estimate: extent x " + FormatNumber(e.lo[0]) + ".." +
                         FormatNumber(e.hi[0]) + ", y " + FormatNumber(e.lo[1]) + ".." +
                         FormatNumber(e.hi[1]);
    if (e.dims == 3) {
      extent += ", z " + FormatNumber(e.lo[2]) + ".." + FormatNumber(e.hi[2]);
    }
    lines.push_back(extent + " " + units);
  } else {
    lines.emplace_back("estimate: extent: nothing drawn");
  }
  lines.push_back("estimate assumes: feed " + FormatNumber(o.feed) + ", plunge " +
                  FormatNumber(o.plunge_feed) + ", G0 " + FormatNumber(o.travel_rate) + " " +
                  units + "/min");
  lines.push_back(
      "estimate assumes: accel " +
      (o.accel > 0 ? FormatNumber(o.accel) + " " + units + "/s^2" : std::string("none")) +
      AxisAccelNote(o.axis_accel, units) + ", junction deviation " +
      FormatNumber(o.junction_deviation) + " " + units + ", dwell " + FormatNumber(o.dwell) + " s");
  return lines;
}

}  // namespace fdsurf::host
