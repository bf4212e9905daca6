// SPDX-License-Identifier: MIT
// Hidden-line removal against an independent reference: a dense triangle mesh
// of every patch (the double reference evaluation on a grid) and a ray test
// per point, with a margin above the mesh's measured error; points within the
// margin are not judged. Also a sphere made here of eight Bézier patches (only
// its front half may be drawn, and all of it is), a plane in front of a
// plane, and a patch seen edge-on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "fdsurf/host/hidden_lines.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {
namespace {

using Vec = std::array<double, 3>;

double PlaneDistance(const Vec& a, const Vec& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }

// ---- The reference: a triangle mesh and a ray test ---------------------------

struct Triangle {
  Vec a, b, c;
};

class MeshReference {
 public:
  MeshReference(const PatchSet& set, const OutputMap& map, int grid) {
    for (const Patch& patch : set.patches) AddPatch(patch, map, grid);
    // The margin: four times the largest distance, measured at each
    // triangle's centre, between the mesh and the exact surface.
    margin_ = 4 * mesh_error_ + 1e-9;
    Bin();
  }

  double margin() const { return margin_; }

  enum class Verdict { kVisible, kHidden, kNotJudged };

  // Hidden when a triangle lies more than eps + margin in front over the
  // point and over the four points `margin` beside it; visible when none lies
  // more than eps − margin in front over any of the five.
  Verdict Judge(const Vec& p, double eps) const {
    bool all_hidden = true;
    bool all_visible = true;
    const double offsets[5][2] = {{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    for (const auto& o : offsets) {
      const double depth = FrontDepth(p[0] + o[0] * margin_, p[1] + o[1] * margin_);
      all_hidden = all_hidden && depth > p[2] + eps + margin_;
      all_visible = all_visible && depth <= p[2] + eps - margin_;
    }
    if (all_hidden) return Verdict::kHidden;
    if (all_visible) return Verdict::kVisible;
    return Verdict::kNotJudged;
  }

 private:
  void AddPatch(const Patch& patch, const OutputMap& map, int grid) {
    std::vector<Vec> points;
    for (int i = 0; i <= grid; ++i) {
      for (int j = 0; j <= grid; ++j) {
        points.push_back(map.Apply(EvaluateReference(patch, double(i) / grid, double(j) / grid)));
      }
    }
    const auto at = [&](int i, int j) {
      return points[static_cast<std::size_t>(i * (grid + 1) + j)];
    };
    for (int i = 0; i < grid; ++i) {
      for (int j = 0; j < grid; ++j) {
        triangles_.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        triangles_.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        const Vec exact = map.Apply(EvaluateReference(patch, (i + 0.5) / grid, (j + 0.5) / grid));
        const Vec a = at(i, j);
        const Vec c = at(i + 1, j + 1);
        const Vec mid{(a[0] + c[0]) / 2, (a[1] + c[1]) / 2, (a[2] + c[2]) / 2};
        mesh_error_ = std::max(mesh_error_, std::sqrt((mid[0] - exact[0]) * (mid[0] - exact[0]) +
                                                      (mid[1] - exact[1]) * (mid[1] - exact[1]) +
                                                      (mid[2] - exact[2]) * (mid[2] - exact[2])));
      }
    }
  }

  void Bin() {
    lo_ = {1e300, 1e300};
    std::array<double, 2> hi{-1e300, -1e300};
    for (const Triangle& t : triangles_) {
      for (const Vec* v : {&t.a, &t.b, &t.c}) {
        for (int c = 0; c < 2; ++c) {
          lo_[c] = std::min(lo_[c], (*v)[c]);
          hi[c] = std::max(hi[c], (*v)[c]);
        }
      }
    }
    cell_ = std::max(hi[0] - lo_[0], hi[1] - lo_[1]) / kBins + 1e-12;
    bins_.assign(kBins * kBins, {});
    for (std::size_t k = 0; k < triangles_.size(); ++k) {
      const Triangle& t = triangles_[k];
      const int i0 = Clamp((std::min({t.a[0], t.b[0], t.c[0]}) - lo_[0]) / cell_);
      const int i1 = Clamp((std::max({t.a[0], t.b[0], t.c[0]}) - lo_[0]) / cell_);
      const int j0 = Clamp((std::min({t.a[1], t.b[1], t.c[1]}) - lo_[1]) / cell_);
      const int j1 = Clamp((std::max({t.a[1], t.b[1], t.c[1]}) - lo_[1]) / cell_);
      for (int i = i0; i <= i1; ++i) {
        for (int j = j0; j <= j1; ++j) bins_[static_cast<std::size_t>(j * kBins + i)].push_back(k);
      }
    }
  }

  static int Clamp(double v) { return std::clamp(static_cast<int>(std::floor(v)), 0, kBins - 1); }

  // The largest depth of the mesh over (x, y), -inf where there is none.
  double FrontDepth(double x, double y) const {
    double best = -HUGE_VAL;
    const auto& bin = bins_[static_cast<std::size_t>(Clamp((y - lo_[1]) / cell_) * kBins +
                                                     Clamp((x - lo_[0]) / cell_))];
    for (const std::size_t k : bin) {
      const Triangle& t = triangles_[k];
      const double d =
          (t.b[0] - t.a[0]) * (t.c[1] - t.a[1]) - (t.c[0] - t.a[0]) * (t.b[1] - t.a[1]);
      if (std::fabs(d) < 1e-18) continue;  // seen edge-on: covers no area
      const double u = ((x - t.a[0]) * (t.c[1] - t.a[1]) - (t.c[0] - t.a[0]) * (y - t.a[1])) / d;
      const double v = ((t.b[0] - t.a[0]) * (y - t.a[1]) - (x - t.a[0]) * (t.b[1] - t.a[1])) / d;
      if (u < 0 || v < 0 || u + v > 1) continue;
      best = std::max(best, t.a[2] + u * (t.b[2] - t.a[2]) + v * (t.c[2] - t.a[2]));
    }
    return best;
  }

  static constexpr int kBins = 128;
  std::vector<Triangle> triangles_;
  std::vector<std::vector<std::size_t>> bins_;
  std::array<double, 2> lo_{};
  double cell_ = 1;
  double mesh_error_ = 0;
  double margin_ = 0;
};

// ---- Drawings ------------------------------------------------------------

ToolpathOptions Options(const std::string& view, double tolerance) {
  ToolpathOptions o;
  o.view = *NamedView(view);
  o.tolerance = tolerance;
  o.quantum = Quantum::Parse("0.001");
  o.fit = std::array<double, 2>{200, 150};
  return o;
}

// The exact point of a stroke with its depth (ExactStrokePoint drops it in 2-D).
Vec ExactWithDepth(const PatchSet& set, const Toolpath& path, const Stroke& s, double u) {
  const Patch& patch = set.patches[s.patch];
  return path.map.Apply(s.family == IsolineFamily::kSLines
                            ? EvaluateReference(patch, s.line_param, u)
                            : EvaluateReference(patch, u, s.line_param));
}

bool SameLine(const Stroke& a, const Stroke& b) {
  return a.patch == b.patch && a.family == b.family && a.line_param == b.line_param &&
         a.curve == b.curve;
}

struct Drawn {
  Toolpath before;
  Toolpath after;
  HiddenLineReport report;
  HiddenLineOptions options;
};

Drawn DrawHidden(const PatchSet& set, const ToolpathOptions& o) {
  Drawn d;
  d.before = BuildToolpath(set, o, "mm");
  d.after = d.before;
  d.options = HiddenLineDefaults(o.tolerance);
  d.report = RemoveHiddenLines(set, d.options, &d.after);
  return d;
}

// Every point of every piece (its own points, and 8 more on each chord, at
// their parameters) is not hidden by the reference; every point of the
// original lines (64 per line) that the reference hides is not drawn, unless
// it lies within `locate` + margin of a piece's end. Returns the number of
// hidden points judged.
std::size_t CheckAgainstReference(const PatchSet& set, const Drawn& d, const MeshReference& mesh) {
  const double eps = d.options.eps;
  std::size_t drawn_hidden = 0;
  for (const Stroke& s : d.after.strokes) {
    for (std::size_t k = 0; k + 1 < s.params.size(); ++k) {
      for (int i = 0; i < 8; ++i) {
        const double u = s.params[k] + (s.params[k + 1] - s.params[k]) * i / 8;
        const Vec p = ExactWithDepth(set, d.after, s, u);
        if (mesh.Judge(p, eps) == MeshReference::Verdict::kHidden) ++drawn_hidden;
      }
    }
  }
  EXPECT_EQ(drawn_hidden, 0u) << "drawn points that the mesh reference hides";

  std::size_t hidden = 0;
  std::size_t hidden_drawn = 0;
  for (const Stroke& line : d.before.strokes) {
    for (int i = 0; i <= 64; ++i) {
      const double u = line.params.front() + (line.params.back() - line.params.front()) * i / 64;
      const Vec p = ExactWithDepth(set, d.before, line, u);
      if (mesh.Judge(p, eps) != MeshReference::Verdict::kHidden) continue;
      ++hidden;
      for (const Stroke& piece : d.after.strokes) {
        if (!SameLine(piece, line)) continue;
        const double a = std::min(piece.params.front(), piece.params.back());
        const double b = std::max(piece.params.front(), piece.params.back());
        if (u < a || u > b) continue;
        const double to_end = std::min(PlaneDistance(p, ExactWithDepth(set, d.after, piece, a)),
                                       PlaneDistance(p, ExactWithDepth(set, d.after, piece, b)));
        if (to_end > d.options.locate + mesh.margin()) ++hidden_drawn;
      }
    }
  }
  EXPECT_EQ(hidden_drawn, 0u) << "points the mesh reference hides, drawn (of " << hidden << ")";
  return hidden;
}

PatchSet Teapot() { return ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt"); }

TEST(HiddenLines, TheTeapotAgreesWithAMeshReferenceInTheIsoAndFrontViews) {
  const PatchSet set = Teapot();
  for (const char* view : {"iso", "front"}) {
    SCOPED_TRACE(view);
    const Drawn d = DrawHidden(set, Options(view, 0.05));
    const MeshReference mesh(set, d.after.map, 96);
    ASSERT_LT(mesh.margin(), 0.05);  // the reference is finer than what it judges
    const std::size_t hidden = CheckAgainstReference(set, d, mesh);
    EXPECT_GT(hidden, 5000u);  // the far side is there to be hidden
    EXPECT_LT(d.report.length_after, 0.7 * d.report.length_before);
    EXPECT_GT(d.report.length_after, 0.3 * d.report.length_before);
  }
}

// The teapot's lid (patches 20..27 in the file's order: lid and knob) hides the
// body's far side in the iso view: points of the body (patches 0..11: rim and
// body) that the reference finds behind a lid patch are removed.
TEST(HiddenLines, TheLidHidesTheBodyBehindIt) {
  const PatchSet set = Teapot();
  const Drawn d = DrawHidden(set, Options("iso", 0.05));
  PatchSet lid;
  lid.patches.assign(set.patches.begin() + 20, set.patches.begin() + 28);
  const MeshReference lid_mesh(lid, d.after.map, 96);
  std::size_t behind_lid = 0;
  std::size_t drawn = 0;
  for (const Stroke& line : d.before.strokes) {
    if (line.patch >= 12) continue;
    for (int i = 0; i <= 64; ++i) {
      const double u = double(i) / 64;
      const Vec p = ExactWithDepth(set, d.before, line, u);
      if (lid_mesh.Judge(p, d.options.eps) != MeshReference::Verdict::kHidden) continue;
      ++behind_lid;
      for (const Stroke& piece : d.after.strokes) {
        if (!SameLine(piece, line)) continue;
        const double a = std::min(piece.params.front(), piece.params.back());
        const double b = std::max(piece.params.front(), piece.params.back());
        if (u > a && u < b) ++drawn;
      }
    }
  }
  EXPECT_GT(behind_lid, 200u);
  EXPECT_EQ(drawn, 0u);
}

// ---- A sphere: eight Bézier patches, a quarter circle by a quarter circle --

// The quarter circle from angle 0 to 90° as a cubic Bézier (k = 4/3·tan(π/8)).
std::array<std::array<double, 2>, 4> QuarterCircle(double start) {
  const double k = 4.0 / 3 * std::tan(M_PI / 8);
  const double c = std::cos(start);
  const double s = std::sin(start);
  return {{{c, s}, {c - k * s, s + k * c}, {-s + k * c, c + k * s}, {-s, c}}};
}

PatchSet Sphere(double radius) {
  PatchSet set;
  set.units = "mm";
  for (int half = 0; half < 2; ++half) {
    // Profile: (r, z) from the pole at z = -1 (half 0) or the equator (half 1).
    const auto profile = QuarterCircle(-M_PI / 2 + half * M_PI / 2);
    for (int quarter = 0; quarter < 4; ++quarter) {
      const auto around = QuarterCircle(quarter * M_PI / 2);
      Patch patch;
      patch.origin = "sphere";
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
          patch.g[i][j] = {radius * profile[i][0] * around[j][0],
                           radius * profile[i][0] * around[j][1], radius * profile[i][1]};
        }
      }
      set.patches.push_back(patch);
    }
  }
  return set;
}

TEST(HiddenLines, ASphereFromTheFrontShowsAllOfItsFrontHalfAndNothingBehind) {
  const PatchSet set = Sphere(50);
  ToolpathOptions o = Options("front", 0.05);
  o.fit.reset();
  o.lines_s = 9;
  o.lines_t = 9;
  const Drawn d = DrawHidden(set, o);
  const double centre = d.after.map.Apply({0, 0, 0})[2];
  double drawn_length = 0;
  for (const Stroke& s : d.after.strokes) {
    for (std::size_t k = 0; k + 1 < s.params.size(); ++k) {
      for (int i = 0; i <= 8; ++i) {
        const double u = s.params[k] + (s.params[k + 1] - s.params[k]) * i / 8;
        EXPECT_GE(ExactWithDepth(set, d.after, s, u)[2] - centre, -d.options.eps);
      }
      drawn_length += PlaneDistance(ExactWithDepth(set, d.after, s, s.params[k]),
                                    ExactWithDepth(set, d.after, s, s.params[k + 1]));
    }
  }
  // The front half's exact length: the lines sampled finely, the pieces whose
  // both ends face the viewer.
  double front_length = 0;
  for (const Stroke& s : d.before.strokes) {
    Vec previous = ExactWithDepth(set, d.before, s, 0);
    for (int i = 1; i <= 2048; ++i) {
      const Vec p = ExactWithDepth(set, d.before, s, i / 2048.0);
      // (The meridians in the silhouette plane count as front: depth 0 up to rounding.)
      const double front = centre - 1e-9;
      if (previous[2] >= front && p[2] >= front) front_length += PlaneDistance(previous, p);
      previous = p;
    }
  }
  EXPECT_NEAR(drawn_length, front_length, 0.005 * front_length);
  EXPECT_NEAR(d.report.length_after, 0.5 * d.report.length_before, 0.05 * d.report.length_before);
}

// ---- Planes -----------------------------------------------------------------

// A flat Bézier patch: the square [x0, x1] × [y0, y1] at height z (top view:
// depth = z), its s along x (or reversed: the same square seen from behind).
Patch Square(double x0, double x1, double y0, double y1, double z, bool reversed = false) {
  Patch patch;
  patch.origin = "square";
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double x = x0 + (x1 - x0) * (reversed ? 3 - i : i) / 3;
      patch.g[i][j] = {x, y0 + (y1 - y0) * j / 3, z};
    }
  }
  return patch;
}

TEST(HiddenLines, APlaneInFrontOfAPlaneCutsItsLinesAtTheEdges) {
  for (const bool reversed : {false, true}) {  // an open surface hides from behind as well
    SCOPED_TRACE(reversed ? "front plane seen from behind" : "front plane seen from its front");
    PatchSet set;
    set.patches = {Square(-20, 20, -20, 20, 0), Square(-5, 5, -5, 5, 10, reversed)};
    ToolpathOptions o = Options("top", 0.05);
    o.fit.reset();
    o.lines_s = 5;  // back lines at x = -20, -10, 0, 10, 20; front at -5, -2.5, 0, 2.5, 5
    o.lines_t = 5;
    const Drawn d = DrawHidden(set, o);
    const double q = d.after.quantum.value();
    double front = 0;
    for (const Stroke& s : d.after.strokes) {
      const Vec first = ExactWithDepth(set, d.after, s, s.params.front());
      const Vec last = ExactWithDepth(set, d.after, s, s.params.back());
      if (s.patch == 1) {
        front += PlaneDistance(first, last);
        continue;
      }
      // No point of a back piece lies inside the front square, further than
      // the location tolerance from its edge.
      for (const auto& p : s.points) {
        const Vec model{p[0] * q, p[1] * q, 0};
        const Vec at = d.after.map.Apply({0, 0, 0});
        const double x = (model[0] - at[0]) / d.after.map.scale;
        const double y = (model[1] - at[1]) / d.after.map.scale;
        EXPECT_FALSE(std::fabs(x) < 5 - 0.06 && std::fabs(y) < 5 - 0.06) << x << "," << y;
      }
    }
    EXPECT_NEAR(front, 10 * 10, 1e-6);  // ten lines of 10 mm, all drawn
    // The back lines x = 0 and y = 0 cross the front square and lose 10 mm
    // each, up to the location of their four cuts.
    EXPECT_NEAR(d.report.length_before - d.report.length_after, 2 * 10, 4 * d.options.locate);
  }
}

// The plane z = 0 seen from the front (depth = -y) is a line on the page;
// Newton's Jacobian is singular everywhere on it, so subdivision decides. A
// plane behind it loses at most the location tolerance around each crossing,
// and the edge-on plane's nearest edge line is drawn whole.
TEST(HiddenLines, APatchSeenEdgeOnHidesOnlyAlongItsLine) {
  PatchSet set;
  Patch back;
  back.origin = "back";
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) back.g[i][j] = {-20 + 40.0 * i / 3, 30, -20 + 40.0 * j / 3};
  }
  set.patches = {Square(-10, 10, -10, 10, 0), back};
  ToolpathOptions o = Options("front", 0.05);
  o.fit.reset();
  o.lines_s = 5;  // back s-lines at x = -20, -10, 0, 10, 20 cross the edge-on plane's line
  o.lines_t = 4;  // back t-lines at z = ±20, ±6.67 miss it (one at z = 0 would lie in it)
  const Drawn d = DrawHidden(set, o);
  double back_before = 0;
  double back_after = 0;
  for (const Stroke& s : d.before.strokes) {
    if (s.patch == 1)
      back_before +=
          PlaneDistance(ExactWithDepth(set, d.before, s, 0), ExactWithDepth(set, d.before, s, 1));
  }
  bool nearest_edge_whole = false;
  for (const Stroke& s : d.after.strokes) {
    const double length = PlaneDistance(ExactWithDepth(set, d.after, s, s.params.front()),
                                        ExactWithDepth(set, d.after, s, s.params.back()));
    if (s.patch == 1) back_after += length;
    // The t-line at t = 0 is y = -10, nearest to the viewer.
    if (s.patch == 0 && s.family == IsolineFamily::kTLines && s.line_param == 0 && length > 19.99) {
      nearest_edge_whole = true;
    }
  }
  // The five vertical back lines cross the edge-on plane's line once each.
  EXPECT_LE(back_before - back_after, 5 * 2 * d.options.locate + 1e-9);
  EXPECT_TRUE(nearest_edge_whole);
}

TEST(HiddenLines, RefusesOptionsThatCannotBeMet) {
  const PatchSet set = Sphere(10);
  Toolpath path = BuildToolpath(set, Options("front", 0.05), "mm");
  HiddenLineOptions bad = HiddenLineDefaults(0.05);
  bad.eps = 0;
  EXPECT_THROW(RemoveHiddenLines(set, bad, &path), OptionError);
  bad = HiddenLineDefaults(0.05);
  bad.spacing = bad.locate / 2;
  EXPECT_THROW(RemoveHiddenLines(set, bad, &path), OptionError);
}

// A cut piece keeps the exact cubic of its own stretch (the G5 writer draws
// it): the piece's cubic, evaluated here by Bernstein weights, passes through
// the exact line at the piece's first, middle and last parameters.
TEST(HiddenLines, CutPiecesKeepTheCubicOfTheirOwnStretch) {
  const PatchSet set = Teapot();
  const Drawn d = DrawHidden(set, Options("iso", 0.05));
  std::size_t cut = 0;
  for (const Stroke& s : d.after.strokes) {
    ASSERT_EQ(s.cubics.size(), 1u);
    const double a = s.params.front();
    const double e = s.params.back();
    if (a == 0 && e == 1) continue;
    ++cut;
    for (const double u : {0.0, 0.5, 1.0}) {
      const auto& b = s.cubics[0];
      const double v = 1 - u;
      const double w[4] = {v * v * v, 3 * u * v * v, 3 * u * u * v, u * u * u};
      Vec on_cubic{};
      for (std::size_t k = 0; k < 3; ++k) {
        for (std::size_t i = 0; i < 4; ++i) on_cubic[k] += w[i] * b[i][k];
      }
      const Vec exact = ExactWithDepth(set, d.after, s, a + u * (e - a));
      EXPECT_LT(PlaneDistance(on_cubic, exact), 1e-9)
          << "piece of patch " << s.patch << " at " << u;
    }
  }
  EXPECT_GT(cut, 50u);
}

}  // namespace
}  // namespace fdsurf::host
