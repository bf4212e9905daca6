// SPDX-License-Identifier: MIT
// `fdsurf stream --hidden remove`: the visible pieces of the lines streamed
// as curves. The teapot through the tool: what the simulated plotter drew is
// within the bound, as long as what `plot --hidden remove` draws, and far
// shorter than the whole drawing. A torus (examples/closed-nets.json, closed
// both ways) seen from above, in 3-D on the simulated plotter run here:
// every drawn point lies on the upper half, and all of the upper half's
// lines are drawn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fdsurf/host/link.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/sim/plotter.h"
#include "tool_run.h"

namespace fdsurf::host {
namespace {

using fdsurf::test_support::RunResult;
using fdsurf::test_support::Slurp;
using Point2 = std::array<double, 2>;
using Polyline = std::vector<Point2>;

double Distance(const Point2& a, const Point2& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }

// The pen-down length of polylines, each walked through the points at least
// `spacing` apart (and its last point). The plotter's path is a staircase of
// motor steps, some 10% longer than the curve it follows; chords of 20 steps
// or more measure the curve instead, to well under 0.1% here.
double PenDownLength(const std::vector<Polyline>& lines, double spacing) {
  double length = 0;
  for (const Polyline& line : lines) {
    if (line.empty()) continue;
    Point2 last = line.front();
    for (std::size_t k = 1; k < line.size(); ++k) {
      if (Distance(line[k], last) >= spacing || k + 1 == line.size()) {
        length += Distance(line[k], last);
        last = line[k];
      }
    }
  }
  return length;
}

// The polylines of an SVG that WriteSvg wrote ("Mx y Lx y ..." per path;
// y is flipped, which lengths do not see).
std::vector<Polyline> SvgPolylines(const std::string& svg) {
  std::vector<Polyline> lines;
  for (std::size_t at = svg.find("<path d=\""); at != std::string::npos;
       at = svg.find("<path d=\"", at + 1)) {
    const std::size_t begin = at + 9;
    const std::string data = svg.substr(begin, svg.find('"', begin) - begin);
    Polyline line;
    for (std::size_t k = data.find_first_of("ML"); k != std::string::npos;
         k = data.find_first_of("ML", k + 1)) {
      std::size_t used = 0;
      const double x = std::stod(data.substr(k + 1), &used);
      const double y = std::stod(data.substr(k + 1 + used));
      line.push_back({x, y});
    }
    lines.push_back(std::move(line));
  }
  return lines;
}

// The strokes of `plot --format json`: "strokes":[[[x,y],[x,y],...],...].
std::vector<Polyline> JsonStrokes(const std::string& json) {
  std::vector<Polyline> lines;
  std::size_t k = json.find("\"strokes\":[");
  if (k == std::string::npos) return lines;
  k += 11;
  int depth = 1;  // inside the strokes array
  for (; k < json.size() && depth > 0; ++k) {
    if (json[k] == ']') --depth;
    if (json[k] != '[') continue;
    ++depth;
    if (depth == 2) lines.emplace_back();
    if (depth == 3) {
      std::size_t used = 0;
      const double x = std::stod(json.substr(k + 1), &used);
      const std::size_t comma = json.find(',', k + 1 + used);
      const double y = std::stod(json.substr(comma + 1));
      lines.back().push_back({x, y});
    }
  }
  return lines;
}

class StreamHidden : public fdsurf::test_support::ToolTest {
 protected:
  StreamHidden() : ToolTest("fdsurf_stream_hidden_") {}
};

const std::string kTeapot = std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt";
const std::string kTeapotOptions = " --view iso --fit 100x75 --lines 8";

TEST_F(StreamHidden, TheTeapotDrawsWhatPlotDrawsWithinTheBound) {
  const std::string svg = (dir_ / "hidden.svg").string();
  const RunResult r = Run("stream '" + kTeapot + "' --device sim --hidden remove" + kTeapotOptions +
                          " --svg '" + svg + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("hidden: 504 strokes -> "), std::string::npos) << r.err;
  // The visible pieces go out as curves, not as the teapot's patches.
  EXPECT_NE(r.err.find(" curves streamed to the simulated plotter"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(--tolerance): within"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("): kept"), std::string::npos) << r.err;

  const std::string json = (dir_ / "hidden.json").string();
  const RunResult plot =
      Run("plot '" + kTeapot + "' --hidden remove" + kTeapotOptions + " -o '" + json + "'");
  ASSERT_EQ(plot.exit_code, 0) << plot.err;
  const std::string whole_svg = (dir_ / "whole.svg").string();
  const RunResult whole =
      Run("stream '" + kTeapot + "' --device sim" + kTeapotOptions + " --svg '" + whole_svg + "'");
  ASSERT_EQ(whole.exit_code, 0) << whole.err;

  // mm; chords of 0.25 mm = 20 steps.
  const double streamed = PenDownLength(SvgPolylines(Slurp(svg)), 0.25);
  const double plotted = PenDownLength(JsonStrokes(Slurp(json)), 0.0);
  const double all = PenDownLength(SvgPolylines(Slurp(whole_svg)), 0.25);
  // The same pieces: the cuts may differ by where the samples fell (the
  // plot's points are at its quantum, the stream's at the step), each by at
  // most the cut location (0.05 mm) at either end of ~220 strokes, 22 mm.
  ASSERT_GT(plotted, 1000);
  EXPECT_NEAR(streamed, plotted, 0.01 * plotted) << "stream " << streamed << ", plot " << plotted;
  // About half of the teapot faces away.
  EXPECT_LT(streamed, 0.6 * all) << "hidden " << streamed << ", whole " << all;
}

// ---- A torus from above, in 3-D --------------------------------------------

// The torus of examples/closed-nets.json (its first construction).
PatchSet Torus() {
  const PatchSet file = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/closed-nets.json");
  PatchSet set = file;
  set.patches.clear();
  for (const Patch& patch : file.patches) {
    if (patch.origin.find("construct[0]") != std::string::npos) set.patches.push_back(patch);
  }
  return set;
}

// The isolines `fdsurf` draws of the torus at 8 lines a patch, each once:
// every patch's lines but the last of each family (the next patch's first,
// the net being closed both ways), exactly at 513 points, through `map`.
std::vector<std::vector<std::array<double, 3>>> TorusLines(const PatchSet& set,
                                                           const OutputMap& map) {
  std::vector<std::vector<std::array<double, 3>>> lines;
  for (const Patch& patch : set.patches) {
    for (int family = 0; family < 2; ++family) {
      for (int i = 0; i + 1 < 8; ++i) {
        const double fixed = i / 7.0;
        std::vector<std::array<double, 3>> line;
        for (int k = 0; k <= 512; ++k) {
          const double u = k / 512.0;
          line.push_back(map.Apply(family == 0 ? EvaluateReference(patch, fixed, u)
                                               : EvaluateReference(patch, u, fixed)));
        }
        lines.push_back(std::move(line));
      }
    }
  }
  return lines;
}

TEST_F(StreamHidden, ATorusFromAboveDrawsAllOfItsUpperHalfAndNothingBelow) {
  const PatchSet set = Torus();
  ASSERT_EQ(set.patches.size(), 48u);
  ToolpathOptions options;
  options.view = *NamedView("top");
  options.fit = std::array<double, 2>{60, 60};
  options.margin = 5;
  options.lines_s = 8;
  options.lines_t = 8;
  options.tolerance = 0.05;
  options.dims = 3;
  options.mode = StepMode::kStepExact;
  MachineOptions machine;
  machine.travel = {60, 60, 13};
  machine.speed = 250;
  machine.accel = 5000;
  machine.pen_delay_ms = 5;
  const double step = machine.step.value();

  // Where the whole drawing's job puts the torus (independent of the
  // hidden-line code): its lines, and the Z of its middle plane in steps,
  // halfway between their lowest and highest points (the torus is
  // symmetric about it).
  const StreamJob whole = BuildStreamJob(set, options, machine, "mm");
  const auto lines = TorusLines(set, whole.page.map);
  double z_lo = HUGE_VAL;
  double z_hi = -HUGE_VAL;
  for (const auto& line : lines) {
    for (const auto& p : line) {
      z_lo = std::min(z_lo, p[2]);
      z_hi = std::max(z_hi, p[2]);
    }
  }
  const double middle = (z_lo + z_hi) / 2 / step;

  const VisibleCurves visible = VisibleCurvesOf(set, options, machine, "mm");
  const StreamJob job = BuildStreamJob(visible.set, visible.options, visible.machine, "mm");
  sim::PlotterOptions plotter_options;
  plotter_options.axes = 3;
  sim::SimulatedPlotter plotter(plotter_options);
  HostLink link;
  for (std::size_t k = 0; k < job.commands.size(); ++k) {
    ASSERT_TRUE(link.Enqueue(job.commands[k], job.labels[k]).ok()) << job.labels[k];
  }
  const sim::RunResult run = plotter.Run(link, 3600ull * 1'000'000);
  ASSERT_TRUE(run.finished) << run.error;

  // Every drawn point at or above the middle plane, up to the depth margin
  // (eps), the tolerance and the step rounding of Z.
  const double slack = (visible.hidden.eps + options.tolerance) / step + 1;
  std::size_t points = 0;
  std::size_t below = 0;
  double lowest = HUGE_VAL;
  std::vector<Polyline> drawn;
  for (const sim::DrawnPath& path : plotter.DrawnPaths()) {
    Polyline line;
    for (const auto& p : path.points) {
      ++points;
      lowest = std::min(lowest, static_cast<double>(p[2]) - middle);
      if (static_cast<double>(p[2]) < middle - slack) ++below;
      line.push_back({p[0] * step, p[1] * step});
    }
    drawn.push_back(std::move(line));
  }
  ASSERT_GT(points, 10000u);
  EXPECT_EQ(below, 0u) << "lowest point " << lowest << " steps from the middle plane";

  // The upper half's exact length in the plane (mm): the chords of the
  // lines whose both ends are above the middle plane.
  double upper = 0;
  for (const auto& line : lines) {
    for (std::size_t k = 1; k < line.size(); ++k) {
      const double face = middle * step - 1e-9;
      if (line[k - 1][2] >= face && line[k][2] >= face) {
        upper += Distance({line[k - 1][0], line[k - 1][1]}, {line[k][0], line[k][1]});
      }
    }
  }
  EXPECT_NEAR(PenDownLength(drawn, 0.25), upper, 0.005 * upper);
}

}  // namespace
}  // namespace fdsurf::host
