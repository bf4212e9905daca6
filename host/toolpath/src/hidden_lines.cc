// SPDX-License-Identifier: MIT
// Strokes cut into their visible pieces (hidden_lines.h). The occlusion query
// itself is in hidden_lines_query.cc.
//
// Each stroke is sampled at its own points and, between them, wherever two
// samples are further apart than the spacing (bisecting the chord's
// parameter interval). Where two neighbouring samples disagree, the change is
// located by bisection on the line's parameter with exact evaluation, and the
// stroke is cut at the last visible parameter found, so that every point of
// a piece is a point that was classified visible.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/hidden_lines.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

using Vec = std::array<double, 3>;
using StrokePoint = std::array<std::int64_t, 3>;

// Bisections stop here at the latest (2^-48 of a chord's parameter step).
constexpr int kMaxBisections = 48;

double PlaneDistance(const Vec& a, const Vec& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }

double DrawnLength(const Stroke& s, double quantum) {
  double length = 0;
  for (std::size_t k = 1; k < s.points.size(); ++k) {
    length += std::hypot(static_cast<double>(s.points[k][0] - s.points[k - 1][0]),
                         static_cast<double>(s.points[k][1] - s.points[k - 1][1]));
  }
  return length * quantum;
}

// One stroke's exact curve and the visibility of its points.
class StrokeVisibility {
 public:
  StrokeVisibility(const PatchSet& set, const Toolpath& path, const Stroke& stroke,
                   const SurfaceOcclusion& occlusion, HiddenLineReport* report)
      : set_(set), path_(path), stroke_(stroke), occlusion_(occlusion), report_(report) {}

  // The exact point at `param` in output space, with its depth (also in 2-D).
  FDSURF_NODISCARD Vec At(double param) const {
    return ExactStrokePointWithDepth(set_, path_, stroke_, param);
  }

  FDSURF_NODISCARD bool Visible(const Vec& point) const {
    ++report_->queries;
    const SurfaceOcclusion::Answer answer = occlusion_.Query(point);
    if (answer.undecided) ++report_->undecided;
    return !answer.hidden;
  }

  // The exact point rounded to the quantum, as the stroke's own points are.
  FDSURF_NODISCARD StrokePoint Rounded(double param) const {
    const Vec p = At(param);
    StrokePoint out{};
    for (int c = 0; c < path_.dims; ++c) {
      out[c] = std::llround(path_.quantum.ToQuanta(p[c]));
    }
    return out;
  }

  // Between `visible_param` (visible) and `hidden_param` (hidden): the last
  // visible parameter found by bisection once the two bracketing exact
  // points are within `locate` in the drawing plane.
  FDSURF_NODISCARD double Locate(double visible_param, double hidden_param, double locate) const {
    Vec visible = At(visible_param);
    Vec hidden = At(hidden_param);
    for (int k = 0; k < kMaxBisections && PlaneDistance(visible, hidden) > locate; ++k) {
      const double mid = (visible_param + hidden_param) / 2;
      const Vec p = At(mid);
      if (Visible(p)) {
        visible_param = mid;
        visible = p;
      } else {
        hidden_param = mid;
        hidden = p;
      }
    }
    return visible_param;
  }

 private:
  const PatchSet& set_;
  const Toolpath& path_;
  const Stroke& stroke_;
  const SurfaceOcclusion& occlusion_;
  HiddenLineReport* report_;
};

struct Sample {
  double param = 0;
  bool visible = true;
  // Index of the stroke's own point, or -1 for a sample between them.
  std::ptrdiff_t vertex = -1;
};

// Samples of (a, b] (a excluded), none further than `spacing` from the next.
void SampleBetween(const StrokeVisibility& line, double a, const Vec& pa, double b, const Vec& pb,
                   double spacing, int depth, std::vector<Sample>* out) {
  if (PlaneDistance(pa, pb) > spacing && depth < kMaxBisections) {
    const double mid = (a + b) / 2;
    const Vec pm = line.At(mid);
    SampleBetween(line, a, pa, mid, pm, spacing, depth + 1, out);
    SampleBetween(line, mid, pm, b, pb, spacing, depth + 1, out);
    return;
  }
  out->push_back({b, line.Visible(pb), -1});
}

std::vector<Sample> SampleStroke(const StrokeVisibility& line, const Stroke& stroke,
                                 double spacing) {
  std::vector<Sample> samples;
  Vec previous = line.At(stroke.params.front());
  samples.push_back({stroke.params.front(), line.Visible(previous), 0});
  for (std::size_t k = 1; k < stroke.params.size(); ++k) {
    const Vec p = line.At(stroke.params[k]);
    SampleBetween(line, stroke.params[k - 1], previous, stroke.params[k], p, spacing, 0, &samples);
    samples.back().vertex = static_cast<std::ptrdiff_t>(k);
    previous = p;
  }
  return samples;
}

// The Bézier control points of the cubic b restricted to [a, e] (a < e in
// [0, 1]): de Casteljau at e keeps [0, e], then at a/e within it keeps
// [a, e]. Exact up to double rounding.
std::array<std::array<double, 3>, 4> SubCubic(const std::array<std::array<double, 3>, 4>& b,
                                              double a, double e) {
  const auto split = [](const std::array<std::array<double, 3>, 4>& c, double t, bool keep_first) {
    std::array<std::array<double, 3>, 4> first{};
    std::array<std::array<double, 3>, 4> second{};
    std::array<std::array<double, 3>, 4> w = c;
    for (int level = 0; level < 4; ++level) {
      first[static_cast<std::size_t>(level)] = w[0];
      second[static_cast<std::size_t>(3 - level)] = w[static_cast<std::size_t>(3 - level)];
      for (std::size_t i = 0; i + static_cast<std::size_t>(level) < 3; ++i) {
        for (std::size_t k = 0; k < 3; ++k) w[i][k] += t * (w[i + 1][k] - w[i][k]);
      }
    }
    return keep_first ? first : second;
  };
  const std::array<std::array<double, 3>, 4> head = split(b, e, true);
  return e > 0 ? split(head, a / e, false) : head;
}

// The visible pieces of one stroke, in order. Each keeps its line's layer
// and, when the line has its exact cubic (G5 output), the cubic of the piece.
class PieceBuilder {
 public:
  PieceBuilder(const Stroke& stroke, std::vector<Stroke>* out) : stroke_(stroke), out_(out) {}

  void Add(const StrokePoint& point, double param) {
    if (!open_) {
      piece_ = Stroke{};
      piece_.patch = stroke_.patch;
      piece_.family = stroke_.family;
      piece_.curve = stroke_.curve;
      piece_.line_param = stroke_.line_param;
      piece_.layer = stroke_.layer;
      open_ = true;
    }
    // A cut that rounds onto its neighbour adds no point.
    if (!piece_.points.empty() && piece_.points.back() == point) return;
    piece_.points.push_back(point);
    piece_.params.push_back(param);
  }

  void Close() {
    if (open_ && piece_.points.size() >= 2) {
      if (stroke_.cubics.size() == 1 && piece_.params.front() < piece_.params.back()) {
        piece_.cubics = {SubCubic(stroke_.cubics[0], piece_.params.front(), piece_.params.back())};
      }
      out_->push_back(std::move(piece_));
    }
    open_ = false;
  }

 private:
  const Stroke& stroke_;
  std::vector<Stroke>* out_;
  Stroke piece_;
  bool open_ = false;
};

void CutStroke(const StrokeVisibility& line, const Stroke& stroke, const HiddenLineOptions& options,
               std::vector<Stroke>* out) {
  const std::vector<Sample> samples = SampleStroke(line, stroke, options.spacing);
  PieceBuilder pieces(stroke, out);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Sample& here = samples[k];
    if (k > 0 && here.visible != samples[k - 1].visible) {
      const Sample& before = samples[k - 1];
      if (before.visible) {
        const double cut = line.Locate(before.param, here.param, options.locate);
        pieces.Add(line.Rounded(cut), cut);
        pieces.Close();
      } else {
        const double cut = line.Locate(here.param, before.param, options.locate);
        pieces.Add(line.Rounded(cut), cut);
      }
    }
    if (here.visible && here.vertex >= 0) {
      const auto v = static_cast<std::size_t>(here.vertex);
      pieces.Add(stroke.points[v], stroke.params[v]);
    }
  }
  pieces.Close();
}

void CheckOptions(const HiddenLineOptions& options) {
  const auto positive = [](double v, const char* field) {
    if (!(v > 0) || !std::isfinite(v)) throw OptionError(field, FormatNumber(v), "must be above 0");
  };
  positive(options.eps, "hidden eps");
  positive(options.locate, "hidden locate");
  positive(options.spacing, "hidden spacing");
  if (options.spacing < options.locate) {
    throw OptionError(
        "hidden spacing", FormatNumber(options.spacing),
        "must not be below the transition's location (" + FormatNumber(options.locate) + ")");
  }
}

}  // namespace

HiddenLineOptions HiddenLineDefaults(double tolerance) {
  HiddenLineOptions options;
  options.eps = tolerance;
  options.locate = tolerance;
  options.spacing = 10 * tolerance;
  return options;
}

HiddenLineReport RemoveHiddenLines(const PatchSet& set, const HiddenLineOptions& options,
                                   Toolpath* path) {
  CheckOptions(options);
  const auto start = std::chrono::steady_clock::now();
  HiddenLineReport report;
  const SurfaceOcclusion occlusion(set, path->map, options.eps);
  const double quantum = path->quantum.value();
  std::vector<Stroke> visible;
  for (const Stroke& stroke : path->strokes) {
    report.length_before += DrawnLength(stroke, quantum);
    if (stroke.points.size() < 2 || stroke.params.size() != stroke.points.size()) {
      throw InputError("hidden lines: a stroke without its parameters (planned already?)");
    }
    const StrokeVisibility line(set, *path, stroke, occlusion, &report);
    CutStroke(line, stroke, options, &visible);
  }
  report.strokes_before = path->strokes.size();
  report.strokes_after = visible.size();
  for (const Stroke& s : visible) report.length_after += DrawnLength(s, quantum);
  path->strokes = std::move(visible);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

std::string DescribeHiddenLines(const HiddenLineReport& report, const HiddenLineOptions& options,
                                const std::string& units) {
  const char* u = units.c_str();
  char line[512];
  std::snprintf(line, sizeof line,
                "hidden: %zu strokes -> %zu visible pieces; drawn %.1f -> %.1f %s; %zu points "
                "tested in %.2f s (depth margin %s %s, cuts located within %s %s, samples at "
                "most %s %s apart)",
                report.strokes_before, report.strokes_after, report.length_before,
                report.length_after, u, report.queries, report.seconds,
                FormatNumber(options.eps).c_str(), u, FormatNumber(options.locate).c_str(), u,
                FormatNumber(options.spacing).c_str(), u);
  return line;
}

}  // namespace fdsurf::host
