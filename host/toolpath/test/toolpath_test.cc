// SPDX-License-Identifier: MIT
// Toolpaths against the double reference: every emitted point and every chord
// of every isoline within the tolerance of the exact curve (measured densely),
// for the teapot and random patches of every basis, in several views, in 2-D
// and 3-D, in each stepping mode; and path planning that keeps every drawn
// segment while cutting pen-up travel.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {
namespace {

// A view by name or as "AZ,EL" in degrees (the tool's --view, parsed simply).
View ViewNamed(const std::string& text) {
  if (const std::optional<View> named = NamedView(text)) return *named;
  double az = 0;
  double el = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf", &az, &el) != 2) throw InputError(text);
  return ViewFromAngles(text, az, el);
}

using Vec = std::array<double, 3>;

double Distance(const Vec& a, const Vec& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

double DistanceToSegment(const Vec& p, const Vec& a, const Vec& b) {
  double ab2 = 0, dot = 0;
  for (int c = 0; c < 3; ++c) {
    ab2 += (b[c] - a[c]) * (b[c] - a[c]);
    dot += (p[c] - a[c]) * (b[c] - a[c]);
  }
  const double u = ab2 > 0 ? std::clamp(dot / ab2, 0.0, 1.0) : 0.0;
  Vec q{};
  for (int c = 0; c < 3; ++c) q[c] = a[c] + u * (b[c] - a[c]);
  return Distance(p, q);
}

struct Deviation {
  double points = 0;  // largest distance of an emitted point from the curve at its parameter
  double chords = 0;  // largest distance of the curve from its chord, sampled densely
};

Deviation Measure(const PatchSet& set, const Toolpath& path) {
  Deviation worst;
  const double q = path.quantum.value();
  for (const Stroke& s : path.strokes) {
    std::vector<Vec> points;
    for (const auto& p : s.points) points.push_back({p[0] * q, p[1] * q, p[2] * q});
    for (std::size_t k = 0; k < points.size(); ++k) {
      worst.points =
          std::max(worst.points, Distance(points[k], ExactStrokePoint(set, path, s, s.params[k])));
      if (k + 1 == points.size()) break;
      constexpr int kSamples = 16;
      for (int i = 1; i < kSamples; ++i) {
        const double u = s.params[k] + (s.params[k + 1] - s.params[k]) * i / kSamples;
        worst.chords = std::max(worst.chords, DistanceToSegment(ExactStrokePoint(set, path, s, u),
                                                                points[k], points[k + 1]));
      }
    }
  }
  return worst;
}

PatchSet Teapot() { return ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt"); }

PatchSet RandomPatches(std::mt19937_64& rng) {
  PatchSet set;
  set.units = "mm";
  std::uniform_real_distribution<double> dist(-40, 40);
  const Basis bases[] = {Basis::kPower, Basis::kHermite, Basis::kBezier, Basis::kBSpline,
                         Basis::kCatmullRom};
  for (Basis basis : bases) {
    Patch patch;
    patch.basis = basis;
    patch.origin = "random";
    for (auto& row : patch.g) {
      for (auto& p : row) p = {dist(rng), dist(rng), dist(rng)};
    }
    set.patches.push_back(patch);
  }
  return set;
}

ToolpathOptions Options(const std::string& view, double tolerance, int dims, StepMode mode) {
  ToolpathOptions o;
  o.view = ViewNamed(view);
  o.tolerance = tolerance;
  o.dims = dims;
  o.mode = mode;
  o.lines_s = 5;
  o.lines_t = 4;
  o.quantum = Quantum::Parse("0.001");
  return o;
}

TEST(Toolpath, EveryPointAndChordOfTheTeapotIsWithinTolerance) {
  const PatchSet set = Teapot();
  struct Case {
    const char* view;
    double tolerance;
    int dims;
    StepMode mode;
    const char* quantum;
  };
  const Case cases[] = {
      {"iso", 0.05, 2, StepMode::kAdaptive, "0.001"},
      {"top", 0.01, 2, StepMode::kAdaptive, "0.001"},
      {"30,60", 0.2, 3, StepMode::kAdaptive, "0.001"},
      {"front", 0.05, 2, StepMode::kFixed, "0.001"},
      {"side", 0.05, 3, StepMode::kFixed, "0.001"},
      {"iso", 0.04, 2, StepMode::kAdaptive, "0.025"},
      {"iso", 0.02, 2, StepMode::kStepExact, "0.01"},
  };
  for (const Case& c : cases) {
    ToolpathOptions o = Options(c.view, c.tolerance, c.dims, c.mode);
    o.quantum = Quantum::Parse(c.quantum);
    o.fit = std::array<double, 2>{200, 150};
    const Toolpath path = BuildToolpath(set, o, "mm");
    const Deviation d = Measure(set, path);
    EXPECT_LE(d.points, c.tolerance) << c.view << " " << c.tolerance;
    EXPECT_LE(d.chords, c.tolerance) << c.view << " " << c.tolerance;
    // The bound is not slack: the drawing uses a good part of it.
    EXPECT_GE(d.chords, 0.2 * c.tolerance) << c.view << " " << c.tolerance;
  }
}

TEST(Toolpath, CurvesOfTheFileAreDrawnWithinTolerance) {
  // Hermite chains (docs/constructions.md, row 1) next to a patch, in every mode.
  PatchSet set = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/hermite-chain.json");
  ASSERT_EQ(set.patches.size(), 0u);
  ASSERT_EQ(set.curves.size(), 5u);
  for (const StepMode mode : {StepMode::kAdaptive, StepMode::kFixed, StepMode::kStepExact}) {
    ToolpathOptions o = Options("top", 0.02, 2, mode);
    o.quantum = Quantum::Parse("0.005");
    o.fit = std::array<double, 2>{120, 80};
    const Toolpath path = BuildToolpath(set, o, "mm");
    ASSERT_EQ(path.strokes.size(), 5u);
    for (std::size_t k = 0; k < path.strokes.size(); ++k) {
      EXPECT_EQ(path.strokes[k].curve, static_cast<std::ptrdiff_t>(k));
    }
    const Deviation d = Measure(set, path);
    EXPECT_LE(d.points, 0.02);
    EXPECT_LE(d.chords, 0.02);
    // Inside the page.
    for (const Stroke& s : path.strokes) {
      for (const auto& p : s.points) {
        EXPECT_GE(p[0] * 0.005, -1e-9);
        EXPECT_LE(p[0] * 0.005, 120 + 1e-9);
      }
    }
  }
  set.patches = Teapot().patches;  // curves and patches together
  const Toolpath both = BuildToolpath(set, Options("iso", 0.05, 2, StepMode::kAdaptive), "mm");
  const Deviation d = Measure(set, both);
  EXPECT_LE(d.chords, 0.05);
}

TEST(Toolpath, RandomPatchesOfEveryBasisStayWithinTolerance) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 8; ++trial) {
    const PatchSet set = RandomPatches(rng);
    for (StepMode mode : {StepMode::kAdaptive, StepMode::kFixed}) {
      const double tolerance = trial % 2 == 0 ? 0.01 : 0.3;
      const Toolpath path = BuildToolpath(
          set, Options(trial % 3 == 0 ? "iso" : "-20,10", tolerance, 2 + trial % 2, mode), "mm");
      const Deviation d = Measure(set, path);
      EXPECT_LE(d.points, tolerance) << trial;
      EXPECT_LE(d.chords, tolerance) << trial;
    }
  }
}

TEST(Toolpath, StepExactPathsMoveOneQuantumAtATime) {
  const PatchSet set = Teapot();
  ToolpathOptions o = Options("iso", 0.03, 2, StepMode::kStepExact);
  o.quantum = Quantum::Parse("0.01");
  o.fit = std::array<double, 2>{100, 80};
  const Toolpath path = BuildToolpath(set, o, "mm");
  for (const Stroke& s : path.strokes) {
    for (std::size_t k = 1; k < s.points.size(); ++k) {
      ASSERT_LE(std::abs(s.points[k][0] - s.points[k - 1][0]), 1);
      ASSERT_LE(std::abs(s.points[k][1] - s.points[k - 1][1]), 1);
      ASSERT_NE(s.points[k], s.points[k - 1]);
    }
  }
}

TEST(Toolpath, AdaptiveNeedsFewerPointsThanFixedStepsForTheSameTolerance) {
  const PatchSet set = Teapot();
  for (double tolerance : {0.01, 0.05, 0.2}) {
    ToolpathOptions o = Options("iso", tolerance, 2, StepMode::kAdaptive);
    o.fit = std::array<double, 2>{200, 150};
    const auto count = [&](StepMode mode) {
      o.mode = mode;
      std::size_t n = 0;
      for (const Stroke& s : BuildToolpath(set, o, "mm").strokes) n += s.points.size();
      return n;
    };
    EXPECT_LT(count(StepMode::kAdaptive), count(StepMode::kFixed)) << tolerance;
  }
}

TEST(Toolpath, FitPlacesTheDrawingInsideThePage) {
  const PatchSet set = Teapot();
  ToolpathOptions o = Options("iso", 0.05, 2, StepMode::kAdaptive);
  o.fit = std::array<double, 2>{210, 297};
  o.margin = 10;
  const Toolpath path = BuildToolpath(set, o, "mm");
  std::int64_t lo[2] = {INT64_MAX, INT64_MAX}, hi[2] = {INT64_MIN, INT64_MIN};
  for (const Stroke& s : path.strokes) {
    for (const auto& p : s.points) {
      for (int c = 0; c < 2; ++c) {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
      }
    }
  }
  const double q = path.quantum.value();
  EXPECT_GE(lo[0] * q, 10 - q);
  EXPECT_GE(lo[1] * q, 10 - q);
  EXPECT_LE(hi[0] * q, 200 + q);
  EXPECT_LE(hi[1] * q, 287 + q);
  // Uniform scale: the width fills the page exactly (the teapot is wider than tall here).
  // (within the tolerance: the polyline may cut inside an extreme of a curve).
  EXPECT_NEAR((hi[0] - lo[0]) * q, 190, o.tolerance);
}

// One Bézier curve from (10, 10) to (40, 30), monotone in x and y, so its
// extent in the top view is exactly x 10..40, y 10..30 (its end points).
PatchSet CurveFrom10To40() {
  PatchSet set;
  set.units = "mm";
  Curve curve;
  curve.basis = Basis::kBezier;
  curve.g = {Point3{10, 10, 0}, Point3{20, 10, 0}, Point3{30, 20, 0}, Point3{40, 30, 0}};
  curve.origin = "test curve";
  set.curves.push_back(curve);
  return set;
}

// The page under each --origin, against the numbers worked out by hand for
// the curve above (not from the code under test).
TEST(Toolpath, OriginKeepLeavesTheFilesCoordinates) {
  ToolpathOptions o = Options("top", 0.05, 2, StepMode::kAdaptive);
  o.origin = PageOrigin::kKeep;
  o.margin = 5;
  const PatchSet set = CurveFrom10To40();
  const Toolpath path = PlanPage(set, o, "mm");
  EXPECT_EQ(path.map.scale, 1.0);
  EXPECT_EQ(path.map.offset, (std::array<double, 3>{0, 0, 0}));
  // No page: from 0 to the far edge plus the margin.
  EXPECT_DOUBLE_EQ(path.width, 45);
  EXPECT_DOUBLE_EQ(path.height, 35);
  EXPECT_DOUBLE_EQ(path.drawing_lo[0], 10);
  EXPECT_DOUBLE_EQ(path.drawing_hi[1], 30);
  // The file's own page, in output units (a file in inches drawn in mm).
  PatchSet paged = set;
  paged.page = std::array<double, 2>{4, 3};
  o.units_scale = 25.4;
  const Toolpath own = PlanPage(paged, o, "mm");
  EXPECT_DOUBLE_EQ(own.width, 101.6);
  EXPECT_DOUBLE_EQ(own.height, 76.2);
  EXPECT_EQ(own.map.scale, 25.4);
  // A --fit page is taken when the drawing lies inside it as it is...
  o.units_scale = 1;
  o.fit = std::array<double, 2>{40, 30};
  const Toolpath fitted = PlanPage(set, o, "mm");
  EXPECT_EQ(fitted.map.scale, 1.0);
  EXPECT_EQ(fitted.width, 40);
  // ...and refused when it does not (it is never scaled or moved).
  o.fit = std::array<double, 2>{39.9, 30};
  EXPECT_THROW((void)PlanPage(set, o, "mm"), OptionError);
}

TEST(Toolpath, OriginMinAndCenterPlaceTheDrawing) {
  ToolpathOptions o = Options("top", 0.05, 2, StepMode::kAdaptive);
  o.margin = 5;
  o.origin = PageOrigin::kMin;
  const PatchSet set = CurveFrom10To40();
  // Without a page: at the unit scale, lower-left at the margin.
  const Toolpath min = PlanPage(set, o, "mm");
  EXPECT_DOUBLE_EQ(min.drawing_lo[0], 5);
  EXPECT_DOUBLE_EQ(min.drawing_lo[1], 5);
  EXPECT_DOUBLE_EQ(min.width, 40);
  EXPECT_DOUBLE_EQ(min.height, 30);
  // On a 100 x 100 page, margin 5: scale 90/30 = 3 (the width decides),
  // lower-left at (5, 5) for min; centred, the 60-high drawing starts at 20.
  o.fit = std::array<double, 2>{100, 100};
  const Toolpath fitted_min = PlanPage(set, o, "mm");
  EXPECT_DOUBLE_EQ(fitted_min.map.scale, 3);
  EXPECT_NEAR(fitted_min.drawing_lo[1], 5, 1e-12);
  o.origin = PageOrigin::kCenter;
  const Toolpath center = PlanPage(set, o, "mm");
  EXPECT_NEAR(center.drawing_lo[0], 5, 1e-12);
  EXPECT_NEAR(center.drawing_lo[1], 20, 1e-12);
  EXPECT_NEAR(center.drawing_hi[1], 80, 1e-12);
  // The drawn points agree with the planned extent (the start is (10, 10) mapped).
  const Toolpath drawn = BuildToolpath(set, o, "mm");
  ASSERT_FALSE(drawn.strokes.empty());
  const auto& first = drawn.strokes[0].points.front();
  EXPECT_EQ(first[0], 5000);
  EXPECT_EQ(first[1], 20000);
}

TEST(Toolpath, PlanningKeepsEverySegmentAndCutsTravel) {
  const PatchSet set = Teapot();
  ToolpathOptions o = Options("iso", 0.05, 2, StepMode::kAdaptive);
  o.lines_s = o.lines_t = 6;
  Toolpath path = BuildToolpath(set, o, "mm");
  using Point = std::array<std::int64_t, 3>;
  const auto segments = [](const Toolpath& p) {
    std::set<std::pair<Point, Point>> out;
    for (const Stroke& s : p.strokes) {
      for (std::size_t k = 1; k < s.points.size(); ++k) {
        out.insert(std::minmax(s.points[k - 1], s.points[k]));
      }
    }
    return out;
  };
  const auto before = segments(path);
  const PlanReport report = PlanStrokes(set, &path);
  EXPECT_EQ(segments(path), before);
  EXPECT_GT(report.duplicates_removed, 0u);  // the teapot's patches share edges
  EXPECT_LT(report.strokes_after, report.strokes_before);
  EXPECT_LT(report.pen_up_after, report.pen_up_before / 5);
  EXPECT_LT(report.pen_down_after, report.pen_down_before);
}

// De Casteljau on a stroke's cubic: written here again, not the writer's code.
std::array<double, 3> BezierAt(const std::array<std::array<double, 3>, 4>& b, double u) {
  auto p = b;
  for (int level = 3; level > 0; --level) {
    for (int k = 0; k < level; ++k) {
      for (int c = 0; c < 3; ++c) p[k][c] = (1 - u) * p[k][c] + u * p[k + 1][c];
    }
  }
  return p[0];
}

// Every stroke's cubic is its exact curve: isolines of random patches of every
// basis (2-D and 3-D, a rotated view) and the file's curves, against the
// reference evaluation through the same map at 33 parameters.
TEST(Toolpath, StrokeCubicsAreTheExactCurves) {
  std::mt19937_64 rng(5);
  PatchSet set = RandomPatches(rng);
  const PatchSet curves = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/hermite-chain.json");
  set.curves = curves.curves;
  for (int dims : {2, 3}) {
    const Toolpath path =
        BuildToolpath(set, Options("-20,10", 0.05, dims, StepMode::kAdaptive), "mm");
    std::size_t from_curves = 0;
    for (const Stroke& s : path.strokes) {
      ASSERT_EQ(s.cubics.size(), 1u);
      if (s.curve >= 0) ++from_curves;
      for (int k = 0; k <= 32; ++k) {
        const double u = k / 32.0;
        const auto exact = ExactStrokePoint(set, path, s, u);
        EXPECT_LT(Distance(BezierAt(s.cubics[0], u), exact), 1e-9) << s.patch << " " << u;
      }
    }
    EXPECT_EQ(from_curves, set.curves.size());
  }
}

// Planning keeps each layer's strokes together and the layers in order, and
// keeps every stroke's cubics a chain from its first point to its last
// (joined in order, reversed with the stroke).
TEST(Toolpath, PlanningKeepsLayersApartAndCubicsInStep) {
  PatchSet set = Teapot();
  set.layers = {"body", "curves", "again"};
  const PatchSet chains = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/hermite-chain.json");
  for (int layer : {2, 1}) {  // the same curves on two layers, listed last layer first
    for (Curve c : chains.curves) {
      c.layer = layer;
      set.curves.push_back(c);
    }
  }
  ToolpathOptions o = Options("top", 0.05, 2, StepMode::kAdaptive);
  o.fit = std::array<double, 2>{200, 150};
  Toolpath path = BuildToolpath(set, o, "mm");
  PlanStrokes(set, &path);
  std::vector<int> layers;
  for (const Stroke& s : path.strokes) {
    if (layers.empty() || layers.back() != s.layer) layers.push_back(s.layer);
  }
  EXPECT_EQ(layers, (std::vector<int>{0, 1, 2}));  // each once, in order
  std::size_t on_layer[3] = {0, 0, 0};
  for (const Stroke& s : path.strokes) on_layer[s.layer] += s.cubics.size();
  EXPECT_EQ(on_layer[1], chains.curves.size());  // not removed as drawn twice by layer 2
  EXPECT_EQ(on_layer[2], chains.curves.size());
  const double q = path.quantum.value();
  const auto at = [&](const std::array<std::int64_t, 3>& p) {
    return std::array<double, 3>{p[0] * q, p[1] * q, 0};
  };
  for (const Stroke& s : path.strokes) {
    ASSERT_FALSE(s.cubics.empty());
    EXPECT_LE(Distance(s.cubics.front()[0], at(s.points.front())), 0.05);
    EXPECT_LE(Distance(s.cubics.back()[3], at(s.points.back())), 0.05);
    for (std::size_t k = 1; k < s.cubics.size(); ++k) {
      EXPECT_LE(Distance(s.cubics[k - 1][3], s.cubics[k][0]), 1e-6);
    }
  }
}

TEST(Toolpath, ViewsAreRotations) {
  const auto top = ViewNamed("top");
  EXPECT_EQ(top.right, (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(top.up, (std::array<double, 3>{0, 1, 0}));
  EXPECT_EQ(top.depth, (std::array<double, 3>{0, 0, 1}));
  for (const char* name : {"iso", "30,45", "-120,-10", "0,90", "front", "side"}) {
    const View v = ViewNamed(name);
    const std::array<double, 3>* rows[3] = {&v.right, &v.up, &v.depth};
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        double dot = 0;
        for (int c = 0; c < 3; ++c) dot += (*rows[a])[c] * (*rows[b])[c];
        EXPECT_NEAR(dot, a == b ? 1 : 0, 1e-12) << name;
      }
    }
  }
  // front: x to the right, z up; side: y to the right, z up.
  EXPECT_EQ(ViewNamed("front").up, (std::array<double, 3>{0, 0, 1}));
  EXPECT_EQ(ViewNamed("side").right, (std::array<double, 3>{0, 1, 0}));
  EXPECT_FALSE(NamedView("diagonal"));
  EXPECT_THROW(ViewFromAngles("10,95", 10, 95), OptionError);
  EXPECT_THROW(ViewFromAngles("10,nan", 10, std::nan("")), OptionError);
}

TEST(Toolpath, RefusesWhatItCannotDraw) {
  const PatchSet set = Teapot();
  ToolpathOptions o = Options("iso", 0.0005, 2, StepMode::kAdaptive);
  EXPECT_THROW(BuildToolpath(set, o, "mm"), InputError);  // below √2·0.5 quanta
  o.tolerance = 0.05;
  o.lines_s = o.lines_t = 0;
  EXPECT_THROW(BuildToolpath(set, o, "mm"), InputError);
  o.lines_s = 3;
  o.fit = std::array<double, 2>{10, 10};
  o.margin = 6;
  EXPECT_THROW(BuildToolpath(set, o, "mm"), InputError);
}

}  // namespace
}  // namespace fdsurf::host
