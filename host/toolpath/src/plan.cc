// SPDX-License-Identifier: MIT
#include "fdsurf/host/plan.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {
namespace {

// Two samples closer than this (in units) are the same point of one curve.
constexpr double kSameCurve = 0.1;

double SpaceDistance(const PlanPoint& a, const PlanPoint& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

double PlaneDistance(const PlanPoint& a, const PlanPoint& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1]);
}

double Distance(PlanMetric metric, const PlanPoint& a, const PlanPoint& b) {
  return metric == PlanMetric::kPlane ? PlaneDistance(a, b) : SpaceDistance(a, b);
}

PlanPoint InUnits(const Point3& model, const OutputMap& map, double unit, int dims) {
  PlanPoint out = map.Apply(model);
  for (double& c : out) c /= unit;
  if (dims == 2) out[2] = 0;
  return out;
}

template <typename At>
SampledCurve Sample(const At& at) {
  SampledCurve samples;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    samples[k] = at(static_cast<double>(k) / (samples.size() - 1));
  }
  return samples;
}

bool SameCurve(const SampledCurve& a, const SampledCurve& b) {
  bool forward = true;
  bool backward = true;
  for (std::size_t k = 0; k < a.size(); ++k) {
    forward = forward && SpaceDistance(a[k], b[k]) <= kSameCurve;
    backward = backward && SpaceDistance(a[k], b[a.size() - 1 - k]) <= kSameCurve;
  }
  return forward || backward;
}

// ---- The stages of PlanStrokes ------------------------------------------------

using StrokePoint = std::array<std::int64_t, 3>;

PlanPoint ToPlan(const StrokePoint& p) {
  return {static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
}

double StrokeLength(const Stroke& s) {
  double length = 0;
  for (std::size_t k = 1; k < s.points.size(); ++k) {
    length += PlaneDistance(ToPlan(s.points[k - 1]), ToPlan(s.points[k]));
  }
  return length;
}

// Pen-down and pen-up lengths in quanta, pen starting at the origin.
std::pair<double, double> PenLengths(const std::vector<Stroke>& strokes) {
  StrokePoint pen{0, 0, 0};
  double down = 0;
  double up = 0;
  for (const Stroke& s : strokes) {
    down += StrokeLength(s);
    up += PlaneDistance(ToPlan(pen), ToPlan(s.points.front()));
    pen = s.points.back();
  }
  return {down, up};
}

void Reverse(Stroke* s) {
  std::reverse(s->points.begin(), s->points.end());
  std::reverse(s->params.begin(), s->params.end());
  std::reverse(s->cubics.begin(), s->cubics.end());
  for (auto& cubic : s->cubics) std::reverse(cubic.begin(), cubic.end());
}

// Appends `other` (which starts where `chain` ends) to `chain`; the cubics
// stay a complete description only when both have them.
void Append(Stroke* chain, const Stroke& other) {
  chain->points.insert(chain->points.end(), other.points.begin() + 1, other.points.end());
  if (chain->cubics.empty() || other.cubics.empty()) {
    chain->cubics.clear();
  } else {
    chain->cubics.insert(chain->cubics.end(), other.cubics.begin(), other.cubics.end());
  }
}

// The exact curve a stroke of BuildToolpath draws.
SampledCurve SampleStroke(const PatchSet& set, const Toolpath& path, const Stroke& stroke) {
  const double unit = path.quantum.value();
  // A piece of a line (hidden-line removal cuts lines) is sampled over its
  // own parameters, so that two pieces of one line are not one curve.
  const double from = stroke.params.empty() ? 0.0 : stroke.params.front();
  const double to = stroke.params.empty() ? 1.0 : stroke.params.back();
  if (std::min(from, to) > 0 || std::max(from, to) < 1) {
    return Sample([&](double u) {
      PlanPoint p = ExactStrokePoint(set, path, stroke, from + (to - from) * u);
      for (double& c : p) c /= unit;
      return p;
    });
  }
  if (stroke.curve >= 0) {
    return SampleCurve(set.curves[static_cast<std::size_t>(stroke.curve)], path.map, unit,
                       path.dims);
  }
  return SampleIsoline(set.patches[stroke.patch], path.map, unit, path.dims, stroke.family,
                       stroke.line_param);
}

// 1. Strokes that draw a curve drawn already: patches that share an edge
// both draw it.
std::vector<Stroke> RemoveDrawnTwice(const PatchSet& set, const Toolpath& path,
                                     std::vector<Stroke> strokes, std::size_t* removed) {
  DrawnCurves drawn;
  std::vector<Stroke> unique;
  for (Stroke& s : strokes) {
    const bool from_set = s.curve >= 0 ? static_cast<std::size_t>(s.curve) < set.curves.size()
                                       : s.patch < set.patches.size();
    if (from_set && drawn.CheckAndAdd(SampleStroke(set, path, s))) {
      ++*removed;
      continue;
    }
    unique.push_back(std::move(s));
  }
  return unique;
}

// 2. Strokes that meet end to end become one pen-down stroke.
std::vector<Stroke> JoinTouching(std::vector<Stroke> strokes) {
  std::multimap<StrokePoint, std::size_t> ends;
  for (std::size_t i = 0; i < strokes.size(); ++i) {
    ends.emplace(strokes[i].points.front(), i);
    ends.emplace(strokes[i].points.back(), i);
  }
  std::vector<bool> used(strokes.size(), false);
  const auto unused_at = [&](const StrokePoint& point) -> std::ptrdiff_t {
    auto [lo, hi] = ends.equal_range(point);
    for (auto it = lo; it != hi; ++it) {
      if (!used[it->second]) return static_cast<std::ptrdiff_t>(it->second);
    }
    return -1;
  };
  std::vector<Stroke> joined;
  for (std::size_t i = 0; i < strokes.size(); ++i) {
    if (used[i]) continue;
    used[i] = true;
    Stroke chain = std::move(strokes[i]);
    for (int side = 0; side < 2; ++side) {
      for (std::ptrdiff_t next = unused_at(chain.points.back()); next >= 0;
           next = unused_at(chain.points.back())) {
        used[static_cast<std::size_t>(next)] = true;
        Stroke& other = strokes[static_cast<std::size_t>(next)];
        if (other.points.front() != chain.points.back()) Reverse(&other);
        Append(&chain, other);
      }
      Reverse(&chain);  // then extend the other end
    }
    chain.params.clear();  // a joined stroke spans several curves
    joined.push_back(std::move(chain));
  }
  return joined;
}

// For a set whose order is the user's (PatchSet::keep_order, a G-code
// program): only strokes that already meet one after the other are joined;
// nothing is reordered, reversed or left out.
std::vector<Stroke> JoinInSequence(std::vector<Stroke> strokes) {
  std::vector<Stroke> joined;
  for (Stroke& stroke : strokes) {
    if (!joined.empty() && joined.back().points.back() == stroke.points.front()) {
      Append(&joined.back(), stroke);
      joined.back().params.clear();  // a joined stroke spans several curves
    } else {
      joined.push_back(std::move(stroke));
    }
  }
  return joined;
}

// 3. Nearest neighbour from `start`, reversing where it helps.
std::vector<Stroke> OrderStrokes(std::vector<Stroke> strokes, const PlanPoint& start) {
  std::vector<std::array<PlanPoint, 2>> ends;
  ends.reserve(strokes.size());
  for (const Stroke& s : strokes)
    ends.push_back({ToPlan(s.points.front()), ToPlan(s.points.back())});
  std::vector<Stroke> ordered;
  ordered.reserve(strokes.size());
  for (const Visit& visit : OrderNearestNeighbour(ends, true, PlanMetric::kPlane, start)) {
    if (visit.reversed) Reverse(&strokes[visit.index]);
    ordered.push_back(std::move(strokes[visit.index]));
  }
  return ordered;
}

// 4. 2-opt: reversing the run i..j (and each stroke in it) replaces the
// links exit(i-1)→entry_of(i) and exit_of(j)→entry(j+1) by exit(i-1)→exit_of(j) and
// entry_of(i)→entry(j+1). A window keeps large drawings fast.
void ImproveByTwoOpt(std::vector<Stroke>* strokes, const PlanPoint& start) {
  std::vector<Stroke>& ordered = *strokes;
  const std::size_t n = ordered.size();
  const auto entry_of = [&](std::size_t k) { return ToPlan(ordered[k].points.front()); };
  const auto exit_of = [&](std::size_t k) { return ToPlan(ordered[k].points.back()); };
  const auto exit_before = [&](std::size_t k) { return k == 0 ? start : exit_of(k - 1); };
  constexpr std::size_t kWindow = 300;
  constexpr int kPasses = 30;
  for (int pass = 0; pass < kPasses; ++pass) {
    bool improved = false;
    for (std::size_t i = 0; i < n; ++i) {
      const PlanPoint before = exit_before(i);
      for (std::size_t j = i + 1; j < n && j < i + kWindow; ++j) {
        const bool last = j + 1 >= n;
        const double old_links = PlaneDistance(before, entry_of(i)) +
                                 (last ? 0 : PlaneDistance(exit_of(j), entry_of(j + 1)));
        const double new_links = PlaneDistance(before, exit_of(j)) +
                                 (last ? 0 : PlaneDistance(entry_of(i), entry_of(j + 1)));
        if (new_links < old_links - 1e-9) {
          std::reverse(ordered.begin() + static_cast<std::ptrdiff_t>(i),
                       ordered.begin() + static_cast<std::ptrdiff_t>(j) + 1);
          for (std::size_t k = i; k <= j; ++k) Reverse(&ordered[k]);
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
}

// The strokes of each layer, layers in order (a stroke's layer below 0 counts as 0).
std::vector<std::vector<Stroke>> SplitByLayer(std::vector<Stroke> strokes) {
  std::vector<std::vector<Stroke>> layers;
  for (Stroke& s : strokes) {
    const auto layer = static_cast<std::size_t>(std::max(0, s.layer));
    if (layer >= layers.size()) layers.resize(layer + 1);
    layers[layer].push_back(std::move(s));
  }
  return layers;
}

}  // namespace

SampledCurve SampleIsoline(const Patch& patch, const OutputMap& map, double unit, int dims,
                           IsolineFamily family, double at) {
  return Sample([&](double u) {
    const Point3 p = family == IsolineFamily::kSLines ? EvaluateReference(patch, at, u)
                                                      : EvaluateReference(patch, u, at);
    return InUnits(p, map, unit, dims);
  });
}

SampledCurve SampleCurve(const Curve& curve, const OutputMap& map, double unit, int dims) {
  return Sample([&](double u) { return InUnits(EvaluateCurve(curve, u), map, unit, dims); });
}

bool IsPoint(const SampledCurve& samples) {
  return SpaceDistance(samples.front(), samples.back()) < 1e-9 &&
         SpaceDistance(samples.front(), samples[samples.size() / 2]) < 1e-9;
}

bool DrawnCurves::CheckAndAdd(const SampledCurve& samples) {
  std::array<std::int64_t, 3> a{};
  std::array<std::int64_t, 3> b{};
  for (std::size_t c = 0; c < 3; ++c) {
    a[c] = std::llround(samples.front()[c]);
    b[c] = std::llround(samples.back()[c]);
  }
  if (b < a) std::swap(a, b);
  const std::array<std::int64_t, 6> key{a[0], a[1], a[2], b[0], b[1], b[2]};
  for (auto [it, end] = by_ends_.equal_range(key); it != end; ++it) {
    if (SameCurve(it->second, samples)) return true;
  }
  by_ends_.emplace(key, samples);
  return false;
}

std::vector<Visit> OrderNearestNeighbour(const std::vector<std::array<PlanPoint, 2>>& ends,
                                         bool may_reverse, PlanMetric metric,
                                         const PlanPoint& start) {
  std::vector<Visit> order;
  order.reserve(ends.size());
  std::vector<bool> placed(ends.size(), false);
  PlanPoint pen = start;
  for (std::size_t n = 0; n < ends.size(); ++n) {
    double best = HUGE_VAL;
    Visit next;
    for (std::size_t i = 0; i < ends.size(); ++i) {
      if (placed[i]) continue;
      for (const bool reversed : {false, true}) {
        if (reversed && !may_reverse) break;
        const double d = Distance(metric, pen, ends[i][reversed ? 1 : 0]);
        if (d < best) {
          best = d;
          next = Visit{i, reversed};
        }
      }
    }
    placed[next.index] = true;
    pen = ends[next.index][next.reversed ? 0 : 1];
    order.push_back(next);
  }
  return order;
}

PlanReport PlanStrokes(const PatchSet& set, Toolpath* path) {
  PlanReport report;
  const double q = path->quantum.value();
  report.strokes_before = path->strokes.size();
  const auto [down_before, up_before] = PenLengths(path->strokes);
  report.pen_down_before = down_before * q;
  report.pen_up_before = up_before * q;

  // Each layer is planned on its own (a pen change lies between layers), in
  // layer order, starting where the layer before it left the pen; nothing is
  // joined, removed as a duplicate or reordered across layers. A program's
  // order (keep_order) is kept: its strokes are only joined in sequence.
  std::vector<Stroke> planned;
  PlanPoint pen{0, 0, 0};
  for (std::vector<Stroke>& layer : SplitByLayer(std::move(path->strokes))) {
    std::vector<Stroke> strokes;
    if (set.keep_order) {
      strokes = JoinInSequence(std::move(layer));
    } else {
      strokes = RemoveDrawnTwice(set, *path, std::move(layer), &report.duplicates_removed);
      strokes = OrderStrokes(JoinTouching(std::move(strokes)), pen);
      ImproveByTwoOpt(&strokes, pen);
    }
    if (!strokes.empty()) pen = ToPlan(strokes.back().points.back());
    for (Stroke& s : strokes) planned.push_back(std::move(s));
  }
  path->strokes = std::move(planned);

  report.strokes_after = path->strokes.size();
  const auto [down_after, up_after] = PenLengths(path->strokes);
  report.pen_down_after = down_after * q;
  report.pen_up_after = up_after * q;
  return report;
}

}  // namespace fdsurf::host
