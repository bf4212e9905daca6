// SPDX-License-Identifier: MIT
#include "fdsurf/host/plan.h"

#include <algorithm>
#include <cmath>
#include <map>
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
  std::vector<std::array<StrokePoint, 2>> ends;
  ends.reserve(strokes.size());
  for (const Stroke& s : strokes) ends.push_back({s.points.front(), s.points.back()});
  std::vector<Stroke> joined;
  for (const std::vector<Visit>& visits : ChainTouching(ends)) {
    Stroke chain;
    for (const Visit& visit : visits) {
      Stroke& piece = strokes[visit.index];
      if (visit.reversed) Reverse(&piece);
      if (chain.points.empty()) {
        chain = std::move(piece);
      } else {
        Append(&chain, piece);
      }
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

// 3 and 4. Nearest neighbour from `start`, reversing where it helps, then
// 2-opt and Or-opt.
std::vector<Stroke> OrderStrokes(std::vector<Stroke> strokes, const PlanPoint& start) {
  std::vector<std::array<PlanPoint, 2>> ends;
  ends.reserve(strokes.size());
  for (const Stroke& s : strokes)
    ends.push_back({ToPlan(s.points.front()), ToPlan(s.points.back())});
  std::vector<Visit> order = OrderNearestNeighbour(ends, true, PlanMetric::kPlane, start);
  ImproveOrder(ends, PlanMetric::kPlane, start, &order);
  std::vector<Stroke> ordered;
  ordered.reserve(strokes.size());
  for (const Visit& visit : order) {
    if (visit.reversed) Reverse(&strokes[visit.index]);
    ordered.push_back(std::move(strokes[visit.index]));
  }
  return ordered;
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

namespace {

// Reverses a run of visits: drawn in the opposite order, each the other way.
void ReverseVisits(std::vector<Visit>::iterator first, std::vector<Visit>::iterator last) {
  std::reverse(first, last);
  for (auto it = first; it != last; ++it) it->reversed = !it->reversed;
}

// The travel of an order of pieces, and what moving one run of it costs.
class OrderTravel {
 public:
  OrderTravel(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
              const PlanPoint& start)
      : ends_(ends), metric_(metric), start_(start) {}

  [[nodiscard]] PlanPoint Entry(const Visit& v) const { return ends_[v.index][v.reversed ? 1 : 0]; }
  [[nodiscard]] PlanPoint Exit(const Visit& v) const { return ends_[v.index][v.reversed ? 0 : 1]; }
  [[nodiscard]] double Between(const PlanPoint& a, const PlanPoint& b) const {
    return Distance(metric_, a, b);
  }
  // The travel into o[k] from the piece before it (or the start).
  [[nodiscard]] double Into(const std::vector<Visit>& o, std::size_t k) const {
    return Between(k == 0 ? start_ : Exit(o[k - 1]), Entry(o[k]));
  }
  [[nodiscard]] const PlanPoint& start() const { return start_; }

 private:
  const std::vector<std::array<PlanPoint, 2>>& ends_;
  PlanMetric metric_;
  PlanPoint start_;
};

}  // namespace

std::vector<std::vector<Visit>> ChainTouching(
    const std::vector<std::array<std::array<std::int64_t, 3>, 2>>& ends) {
  std::multimap<std::array<std::int64_t, 3>, std::size_t> at;
  for (std::size_t i = 0; i < ends.size(); ++i) {
    at.emplace(ends[i][0], i);
    at.emplace(ends[i][1], i);
  }
  std::vector<bool> used(ends.size(), false);
  const auto unused_at = [&](const std::array<std::int64_t, 3>& point) -> std::ptrdiff_t {
    auto [lo, hi] = at.equal_range(point);
    for (auto it = lo; it != hi; ++it) {
      if (!used[it->second]) return static_cast<std::ptrdiff_t>(it->second);
    }
    return -1;
  };
  const auto exit_of = [&](const Visit& v) { return ends[v.index][v.reversed ? 0 : 1]; };
  std::vector<std::vector<Visit>> chains;
  for (std::size_t i = 0; i < ends.size(); ++i) {
    if (used[i]) continue;
    used[i] = true;
    std::vector<Visit> chain{Visit{i, false}};
    for (int side = 0; side < 2; ++side) {
      for (std::ptrdiff_t next = unused_at(exit_of(chain.back())); next >= 0;
           next = unused_at(exit_of(chain.back()))) {
        const auto k = static_cast<std::size_t>(next);
        used[k] = true;
        chain.push_back(Visit{k, ends[k][0] != exit_of(chain.back())});
      }
      ReverseVisits(chain.begin(), chain.end());  // then extend the other end
    }
    chains.push_back(std::move(chain));
  }
  return chains;
}

void ImproveByTwoOpt(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
                     const PlanPoint& start, std::vector<Visit>* order) {
  const OrderTravel t(ends, metric, start);
  std::vector<Visit>& ordered = *order;
  const std::size_t n = ordered.size();
  const auto entry_of = [&](std::size_t k) { return t.Entry(ordered[k]); };
  const auto exit_of = [&](std::size_t k) { return t.Exit(ordered[k]); };
  const auto distance = [&](const PlanPoint& a, const PlanPoint& b) { return t.Between(a, b); };
  // Reversing the run i..j (and each piece in it) replaces the links
  // exit(i-1)→entry_of(i) and exit_of(j)→entry(j+1) by exit(i-1)→exit_of(j)
  // and entry_of(i)→entry(j+1). A window keeps large drawings fast.
  constexpr std::size_t kWindow = 300;
  constexpr int kPasses = 30;
  for (int pass = 0; pass < kPasses; ++pass) {
    bool improved = false;
    for (std::size_t i = 0; i < n; ++i) {
      const PlanPoint before = i == 0 ? start : exit_of(i - 1);
      for (std::size_t j = i + 1; j < n && j < i + kWindow; ++j) {
        const bool last = j + 1 >= n;
        const double old_links =
            distance(before, entry_of(i)) + (last ? 0 : distance(exit_of(j), entry_of(j + 1)));
        const double new_links =
            distance(before, exit_of(j)) + (last ? 0 : distance(entry_of(i), entry_of(j + 1)));
        if (new_links < old_links - 1e-9) {
          ReverseVisits(ordered.begin() + static_cast<std::ptrdiff_t>(i),
                        ordered.begin() + static_cast<std::ptrdiff_t>(j) + 1);
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
}

namespace {

// One Or-opt move, if any shortens the travel: the run o[i..i+length) taken
// out and put back, either way round, after another piece (or first) within
// the window. Returns whether it moved one.
bool MoveOneRun(const OrderTravel& t, std::size_t length, std::size_t window,
                std::vector<Visit>* order) {
  std::vector<Visit>& o = *order;
  const std::size_t n = o.size();
  for (std::size_t i = 0; i + length <= n; ++i) {
    const std::size_t end = i + length;  // one past the run
    const PlanPoint before = i == 0 ? t.start() : t.Exit(o[i - 1]);
    // What taking the run out saves: its two links, less the one that
    // closes the gap.
    double saved = t.Between(before, t.Entry(o[i]));
    if (end < n) saved += t.Into(o, end) - t.Between(before, t.Entry(o[end]));
    // The order without the run: rest(j).
    const auto rest = [&](std::size_t j) -> const Visit& { return o[j < i ? j : j + length]; };
    const std::size_t rest_size = n - length;
    // Put back before rest(p) (p = rest_size: last), p = i being where it was.
    const std::size_t lo = i > window ? i - window : 0;
    const std::size_t hi = std::min(rest_size, i + window);
    for (std::size_t p = lo; p <= hi; ++p) {
      if (p == i) continue;
      const PlanPoint from = p == 0 ? t.start() : t.Exit(rest(p - 1));
      const bool follows = p < rest_size;
      const double old_link = follows ? t.Between(from, t.Entry(rest(p))) : 0.0;
      for (const bool reversed : {false, true}) {
        const PlanPoint in = reversed ? t.Exit(o[end - 1]) : t.Entry(o[i]);
        const PlanPoint out = reversed ? t.Entry(o[i]) : t.Exit(o[end - 1]);
        const double added =
            t.Between(from, in) + (follows ? t.Between(out, t.Entry(rest(p))) : 0.0) - old_link;
        if (added >= saved - 1e-9) continue;
        std::vector<Visit> run(o.begin() + static_cast<std::ptrdiff_t>(i),
                               o.begin() + static_cast<std::ptrdiff_t>(end));
        if (reversed) ReverseVisits(run.begin(), run.end());
        o.erase(o.begin() + static_cast<std::ptrdiff_t>(i),
                o.begin() + static_cast<std::ptrdiff_t>(end));
        o.insert(o.begin() + static_cast<std::ptrdiff_t>(p), run.begin(), run.end());
        return true;
      }
    }
  }
  return false;
}

}  // namespace

void ImproveByOrOpt(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
                    const PlanPoint& start, std::vector<Visit>* order) {
  const OrderTravel travel(ends, metric, start);
  constexpr std::size_t kWindow = 300;
  constexpr int kMoves = 100000;
  for (int moves = 0; moves < kMoves;) {
    bool moved = false;
    for (std::size_t length = 1; length <= 3; ++length) {
      while (moves < kMoves && MoveOneRun(travel, length, kWindow, order)) {
        ++moves;
        moved = true;
      }
    }
    if (!moved) break;
  }
}

void ImproveOrder(const std::vector<std::array<PlanPoint, 2>>& ends, PlanMetric metric,
                  const PlanPoint& start, std::vector<Visit>* order) {
  // Each can undo what the other could not; a few rounds settle it.
  constexpr int kRounds = 4;
  const OrderTravel travel(ends, metric, start);
  const auto total = [&] {
    double sum = 0;
    for (std::size_t k = 0; k < order->size(); ++k) sum += travel.Into(*order, k);
    return sum;
  };
  double last = total();
  for (int round = 0; round < kRounds; ++round) {
    ImproveByTwoOpt(ends, metric, start, order);
    ImproveByOrOpt(ends, metric, start, order);
    const double now = total();
    if (now >= last - 1e-9) break;
    last = now;
  }
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
