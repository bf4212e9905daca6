// SPDX-License-Identifier: MIT
#include "fdsurf/host/stream.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>

#include "fdsurf/adaptive.h"
#include "fdsurf/host/constructions.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/protocol/codec.h"

namespace fdsurf::host {
namespace {

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

using Vec = std::array<double, 3>;

// A point of the file in steps, through the job's map.
Vec ToSteps(const Point3& model, const StreamJob& job) {
  Vec out = job.page.map.Apply(model);
  const double step = job.page.quantum.value();
  for (double& c : out) c /= step;
  if (job.page.dims == 2) out[2] = 0;
  return out;
}

Vec InSteps(const Patch& patch, const StreamJob& job, double s, double t) {
  return ToSteps(EvaluateReference(patch, s, t), job);
}

double Distance(const Vec& a, const Vec& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// Where a patch's drawing starts and ends: the device draws s-lines then
// t-lines, every odd-numbered line of a family reversed.
std::array<Vec, 2> Ends(const Patch& patch, const StreamJob& job, int lines_s, int lines_t) {
  const Vec start = InSteps(patch, job, 0, 0);
  if (lines_t >= 2) {
    const bool reversed = ((lines_t - 1) & 1) != 0;
    return {start, InSteps(patch, job, reversed ? 0 : 1, 1)};
  }
  const bool reversed = ((lines_s - 1) & 1) != 0;
  return {start, InSteps(patch, job, 1, reversed ? 0 : 1)};
}

// An edge line a patch draws (s-line at s = 0 or 1, t-line at t = 0 or 1),
// sampled at 9 parameters.
using EdgeSamples = std::array<Vec, 9>;

EdgeSamples SampleEdge(const Patch& patch, const StreamJob& job, int edge) {
  EdgeSamples samples;
  const double fixed = edge % 2 == 0 ? 0.0 : 1.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double u = static_cast<double>(k) / (samples.size() - 1);
    samples[k] = edge < 2 ? InSteps(patch, job, fixed, u) : InSteps(patch, job, u, fixed);
  }
  return samples;
}

// Two patches that share an edge have the same control points along it, so
// the samples agree (up to rounding), forwards or backwards.
bool SameCurve(const EdgeSamples& a, const EdgeSamples& b) {
  constexpr double kSame = 0.1;  // steps
  bool forward = true;
  bool backward = true;
  for (std::size_t k = 0; k < a.size(); ++k) {
    forward = forward && Distance(a[k], b[k]) <= kSame;
    backward = backward && Distance(a[k], b[a.size() - 1 - k]) <= kSame;
  }
  return forward || backward;
}

std::int32_t ToSteps(double length, const Quantum& step, const std::string& what) {
  const double steps = std::floor(length / step.value() + 1e-9);
  if (!(steps >= 1 && steps <= protocol::kMaxTravelSteps)) {
    throw InputError(what + ": " + Number(length) + " is not 1.." +
                     std::to_string(protocol::kMaxTravelSteps) + " steps of " + step.Format(1));
  }
  return static_cast<std::int32_t>(steps);
}

// The file's curves, in file order: CURVE commands with the pen down, and a
// pen-up move only where a curve does not start where the one before ended
// (so a chain is drawn in one stroke).
void AddCurves(const PatchSet& set, const ToolpathOptions& t, const MachineOptions& machine,
               StreamJob* job) {
  bool pen_down = false;
  bool placed = false;
  std::array<std::int32_t, 3> at{};
  const auto pen = [&](bool down) {
    protocol::Command command;
    command.type = protocol::MessageType::kPen;
    command.seq = 0;
    command.body.pen.down = down;
    job->commands.push_back(command);
    job->labels.emplace_back(down ? "pen down" : "pen up");
    pen_down = down;
  };
  for (std::size_t c = 0; c < set.curves.size(); ++c) {
    const Curve& curve = set.curves[c];
    protocol::Command command;
    command.type = protocol::MessageType::kCurve;
    command.seq = 0;
    protocol::CurveCommand& body = command.body.curve;
    body.basis = curve.basis;
    body.dims = static_cast<std::uint8_t>(t.dims);
    body.tolerance_q8 = job->tolerance_q8;
    for (auto& axis : body.geometry) axis = CurveGeometry1{};
    CurveToQuanta(curve, job->page.map, machine.step, t.dims, body.geometry);
    // The device's first and last points of this curve, computed as it will.
    PowerCurve1 power[protocol::kMaxAxes];
    const Status status = CurvePowerCoefficients(body.geometry, curve.basis, power);
    if (status != Status::kOk) {
      throw EngineError(curve.origin + ": " + StatusMessage(status) + "; use a coarser --step");
    }
    std::array<std::int32_t, 3> start{};
    std::array<std::int32_t, 3> end{};
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      const auto& k = power[a].c;
      start[static_cast<std::size_t>(a)] = RoundToQuanta(k[3], kCoefficientFracBits);
      end[static_cast<std::size_t>(a)] =
          RoundToQuanta(k[0] + k[1] + k[2] + k[3], kCoefficientFracBits);
    }
    if (!placed || start != at) {
      if (pen_down) pen(false);
      protocol::Command move;
      move.type = protocol::MessageType::kMove;
      move.seq = 0;
      for (int a = 0; a < protocol::kMaxAxes; ++a) {
        move.body.move.target[a] = start[static_cast<std::size_t>(a)];
      }
      job->commands.push_back(move);
      job->labels.push_back("travel to curve " + std::to_string(c) + " (" + curve.origin + ")");
    }
    if (!pen_down) pen(true);
    job->commands.push_back(command);
    job->labels.push_back("curve " + std::to_string(c) + " (" + curve.origin + ")");
    job->curves.push_back(c);
    at = end;
    placed = true;
  }
  if (pen_down) pen(false);
}

}  // namespace

StreamJob BuildStreamJob(const PatchSet& set, const ToolpathOptions& options,
                         const MachineOptions& machine, const std::string& units) {
  ToolpathOptions t = options;
  t.quantum = machine.step;
  StreamJob job;
  job.page = PlanPage(set, t, units);
  const double step = machine.step.value();
  if (t.dims == 3) {
    // The device's axes run from 0: put the bottom of the surface at Z = 0.
    job.page.map.offset[2] += job.page.depth;
  }

  // The machine.
  protocol::MachineConfig& config = job.config;
  config.axes = static_cast<std::uint8_t>(t.dims);
  const double page[3] = {job.page.width, job.page.height, job.page.depth};
  const char* const names[3] = {"--travel X", "--travel Y", "--travel Z"};
  for (int c = 0; c < 3; ++c) {
    config.steps_per_meter[c] = 0;
    config.travel_steps[c] = 0;
    if (c >= t.dims) continue;
    const double travel = machine.travel[c] > 0 ? machine.travel[c] : std::max(page[c], step);
    if (travel < page[c] - 1e-9) {
      std::string message = names[c];
      message += " " + Number(travel) + " " + units;
      message += " is smaller than the page (" + Number(page[c]) + " " + units + ")";
      throw InputError(message);
    }
    config.travel_steps[c] = ToSteps(travel, machine.step, names[c]);
    const double meters = step * (units == "in" ? 0.0254 : 0.001);
    config.steps_per_meter[c] = static_cast<std::uint32_t>(std::lround(1 / meters));
  }
  const double max_rate = std::floor(machine.speed / step);
  const double accel = std::floor(machine.accel / step);
  if (!(max_rate >= 1 && max_rate < 4e9)) {
    throw InputError("--speed " + Number(machine.speed) + " " + units +
                     "/s is not 1 step/s or more");
  }
  if (!(accel >= 1 && accel < 4e9)) {
    throw InputError("--accel " + Number(machine.accel) + " " + units +
                     "/s² is not 1 step/s² or more");
  }
  if (machine.pen_delay_ms < 0 || machine.pen_delay_ms > 65535) {
    throw InputError("--pen-delay " + std::to_string(machine.pen_delay_ms) +
                     " ms is outside 0..65535");
  }
  config.max_rate = static_cast<std::uint32_t>(max_rate);
  config.accel = static_cast<std::uint32_t>(accel);
  config.pen_delay_ms = static_cast<std::uint16_t>(machine.pen_delay_ms);

  job.tolerance_steps = t.tolerance / step;
  job.tolerance_q8 =
      static_cast<std::uint32_t>(std::min(std::floor(job.tolerance_steps * 256), 4294967295.0));

  protocol::Command configure;
  configure.type = protocol::MessageType::kConfig;
  configure.seq = 0;
  configure.body.config = config;
  job.commands.push_back(configure);
  job.labels.emplace_back("the machine configuration");

  // The patches, nearest neighbour first from the origin.
  const std::size_t n = set.patches.size();
  std::vector<std::array<Vec, 2>> ends(n);
  for (std::size_t p = 0; p < n; ++p) ends[p] = Ends(set.patches[p], job, t.lines_s, t.lines_t);
  std::vector<bool> done(n, false);
  // Edges drawn so far, found by their rounded end points.
  std::multimap<std::array<std::int64_t, 6>, EdgeSamples> drawn_edges;
  const auto edge_key = [](const EdgeSamples& e) {
    std::array<std::int64_t, 3> a{};
    std::array<std::int64_t, 3> b{};
    for (int c = 0; c < 3; ++c) {
      a[c] = std::llround(e.front()[static_cast<std::size_t>(c)]);
      b[c] = std::llround(e.back()[static_cast<std::size_t>(c)]);
    }
    if (b < a) std::swap(a, b);
    return std::array<std::int64_t, 6>{a[0], a[1], a[2], b[0], b[1], b[2]};
  };
  Vec pen{0, 0, 0};
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t best = 0;
    double best_distance = HUGE_VAL;
    for (std::size_t p = 0; p < n; ++p) {
      if (done[p]) continue;
      const double d = Distance(pen, ends[p][0]);
      if (d < best_distance) {
        best_distance = d;
        best = p;
      }
    }
    done[best] = true;
    pen = ends[best][1];

    const Patch& patch = set.patches[best];
    protocol::Command command;
    command.type = protocol::MessageType::kPatch;
    command.seq = 0;
    protocol::PatchCommand& body = command.body.patch;
    body.basis = patch.basis;
    body.dims = static_cast<std::uint8_t>(t.dims);
    body.lines_s = static_cast<std::uint16_t>(t.lines_s);
    body.lines_t = static_cast<std::uint16_t>(t.lines_t);
    body.tolerance_q8 = job.tolerance_q8;
    for (auto& axis : body.geometry) axis = PatchGeometry1{};
    PatchToQuanta(patch, job.page.map, machine.step, t.dims, body.geometry);
    body.skip_lines = 0;
    const std::uint8_t bits[4] = {protocol::kSkipFirstSLine, protocol::kSkipLastSLine,
                                  protocol::kSkipFirstTLine, protocol::kSkipLastTLine};
    for (int edge = 0; edge < 4; ++edge) {
      if ((edge < 2 ? t.lines_s : t.lines_t) < 2) continue;
      const EdgeSamples samples = SampleEdge(patch, job, edge);
      if (Distance(samples.front(), samples.back()) < 1e-9 &&
          Distance(samples.front(), samples[samples.size() / 2]) < 1e-9) {
        continue;  // a pole: the device leaves it out anyway
      }
      const auto key = edge_key(samples);
      bool shared = false;
      for (auto [it, end] = drawn_edges.equal_range(key); it != end && !shared; ++it) {
        shared = SameCurve(it->second, samples);
      }
      if (shared) {
        body.skip_lines = static_cast<std::uint8_t>(body.skip_lines | bits[edge]);
        ++job.shared_edges_skipped;
      } else {
        drawn_edges.emplace(key, samples);
      }
    }
    job.commands.push_back(command);
    job.labels.push_back("patch " + std::to_string(best) + " (" + patch.origin + ")");
    job.patches.push_back(StreamedPatch{best, t.lines_s, t.lines_t});
  }
  AddCurves(set, t, machine, &job);
  return job;
}

std::vector<std::vector<std::array<double, 3>>> ReferenceLines(const PatchSet& set,
                                                               const StreamJob& job,
                                                               double chord_steps) {
  std::vector<std::vector<Vec>> lines;
  for (const StreamedPatch& streamed : job.patches) {
    const Patch& patch = set.patches[streamed.patch];
    const auto add_family = [&](int count, bool s_lines) {
      for (int i = 0; i < count; ++i) {
        const double fixed = static_cast<double>(i) / (count - 1);
        const auto at = [&](double u) {
          return s_lines ? InSteps(patch, job, fixed, u) : InSteps(patch, job, u, fixed);
        };
        std::vector<Vec> points{at(0)};
        // Subdivide until the chord is within chord_steps of the curve at the
        // midpoint and the quarter points (a cubic piece this short has no
        // room for an undetected bulge).
        std::function<void(double, const Vec&, double, const Vec&, int)> refine =
            [&](double u0, const Vec& p0, double u1, const Vec& p1, int depth) {
              const Vec mid = at((u0 + u1) / 2);
              double worst = 0;
              for (const double f : {0.25, 0.5, 0.75}) {
                const Vec q = f == 0.5 ? mid : at(u0 + f * (u1 - u0));
                Vec chord{};
                for (int c = 0; c < 3; ++c) chord[c] = p0[c] + f * (p1[c] - p0[c]);
                worst = std::max(worst, Distance(q, chord));
              }
              if (depth < 24 && (worst > chord_steps || Distance(p0, p1) > 8)) {
                refine(u0, p0, (u0 + u1) / 2, mid, depth + 1);
                refine((u0 + u1) / 2, mid, u1, p1, depth + 1);
              } else {
                points.push_back(p1);
              }
            };
        refine(0, points[0], 1, at(1), 0);
        double length = 0;
        for (std::size_t k = 1; k < points.size(); ++k)
          length += Distance(points[k - 1], points[k]);
        if (length > 1e-9) lines.push_back(std::move(points));
      }
    };
    add_family(streamed.lines_s, true);
    add_family(streamed.lines_t, false);
  }
  for (const std::size_t c : job.curves) {
    std::vector<Vec> points;
    constexpr int kSamples = 20000;
    for (int k = 0; k <= kSamples; ++k) {
      points.push_back(
          ToSteps(EvaluateCurve(set.curves[c], static_cast<double>(k) / kSamples), job));
    }
    lines.push_back(std::move(points));
  }
  return lines;
}

}  // namespace fdsurf::host
