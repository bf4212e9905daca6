// SPDX-License-Identifier: MIT
// Triangle meshes (OBJ, PLY) through the fdsurf tool as a user runs it
// (issue 18): the octahedron on the sphere of radius 50 drawn by plot and
// stream lies on that sphere, and broken, non-manifold or inconsistently
// oriented meshes are refused with exit code 2 and a message naming the file
// and the line or edge.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tool_run.h"

namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

using fdsurf::test_support::RunResult;
using fdsurf::test_support::Slurp;

const std::string kExamples = FDSURF_EXAMPLES_DIR;
const std::string kOctahedron = kExamples + "/octahedron.obj";

class MeshCli : public fdsurf::test_support::ToolTest {
 protected:
  MeshCli() : ToolTest("fdsurf_mesh_cli_") {}

  // Bad input: exit code 2, nothing on stdout, `part` on stderr.
  void ExpectRefused(const std::string& args, const std::string& part) {
    const RunResult r = Run(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.out, "") << args;
    EXPECT_NE(r.err.find(part), std::string::npos)
        << args << "\nstderr: " << r.err << "\nwanted: " << part;
  }

  // Every command a user gives a mesh to refuses `file` the same way, and
  // plot writes no file.
  void ExpectEveryCommandRefuses(const std::string& file, const std::string& part) {
    const std::string quoted = "'" + file + "'";
    const std::string svg = (dir_ / "out.svg").string();
    ExpectRefused("check " + quoted + " --grid 4", part);
    ExpectRefused("plot " + quoted + " -o '" + svg + "'", part);
    EXPECT_FALSE(fs::exists(svg));
    ExpectRefused("stream " + quoted, part);
  }
};

// The points of an SVG drawing, in page units with y up (the writers' SVG is
// y down: the page's height minus y), and the page size from its viewBox.
struct Drawing {
  double width = 0;
  double height = 0;
  std::vector<std::array<double, 2>> points;
};

Drawing ParseSvg(const std::string& svg) {
  Drawing d;
  const std::size_t box = svg.find("viewBox=\"0 0 ");
  if (box == std::string::npos) return d;
  std::istringstream(svg.substr(box + 13)) >> d.width >> d.height;
  for (std::size_t at = svg.find("<path d=\""); at != std::string::npos;
       at = svg.find("<path d=\"", at + 1)) {
    const std::size_t begin = at + 9;
    std::istringstream data(svg.substr(begin, svg.find('"', begin) - begin));
    std::string command;
    double x = 0;
    double y = 0;
    // The writer emits "Mx y Lx y Lx y ...": a letter glued to each x.
    while (data >> command >> y) {
      x = std::stod(command.substr(1));
      d.points.push_back({x, d.height - y});
    }
  }
  return d;
}

// What the top view of a sphere of radius R centred on the page must show:
// every point inside the disc of radius R + bound around the page centre
// (the projection of the sphere is its disc; chords of the drawing's
// polylines stay inside it too), the drawing 2R wide and high within the
// bound, and in every one of 16 sectors of the disc a point at least
// R - bound from the centre (the equator, a glue curve of the octahedron's
// pieces, is drawn whole as a circle).
struct TopView {
  double largest_radius = 0;
  double smallest_sector_reach = 0;
  double width = 0;
  double height = 0;
};

TopView Measure(const Drawing& d) {
  TopView v;
  std::array<double, 16> reach{};
  double lo[2] = {HUGE_VAL, HUGE_VAL};
  double hi[2] = {-HUGE_VAL, -HUGE_VAL};
  for (const auto& p : d.points) {
    const double x = p[0] - d.width / 2;
    const double y = p[1] - d.height / 2;
    const double r = std::hypot(x, y);
    v.largest_radius = std::max(v.largest_radius, r);
    const int sector =
        std::clamp(static_cast<int>((std::atan2(y, x) + kPi) / (2 * kPi) * 16), 0, 15);
    reach[sector] = std::max(reach[sector], r);
    for (int c = 0; c < 2; ++c) {
      lo[c] = std::min(lo[c], p[c]);
      hi[c] = std::max(hi[c], p[c]);
    }
  }
  v.smallest_sector_reach = *std::min_element(reach.begin(), reach.end());
  v.width = hi[0] - lo[0];
  v.height = hi[1] - lo[1];
  return v;
}

bool ExtentIsDiameter(const TopView& v, double radius, double bound) {
  return std::fabs(v.width - 2 * radius) <= bound && std::fabs(v.height - 2 * radius) <= bound;
}

void ExpectOnTheSphere(const Drawing& d, double radius, double bound) {
  ASSERT_GT(d.points.size(), 100u);
  const TopView v = Measure(d);
  EXPECT_LE(v.largest_radius, radius + bound);
  EXPECT_GE(v.smallest_sector_reach, radius - bound);
  EXPECT_TRUE(ExtentIsDiameter(v, radius, bound))
      << "the drawing is " << v.width << " x " << v.height << ", not " << 2 * radius;
}

// The bound `fdsurf check` states for a mesh's pieces: "every point within
// B of its quadric piece, proven (tolerance T)"; returns T after checking
// B <= T.
double StatedTolerance(const std::string& notes) {
  const std::string within = "every point within ";
  const std::string proven = " of its quadric piece, proven (tolerance ";
  const std::size_t at = notes.find(within);
  const std::size_t tol = notes.find(proven, at);
  if (at == std::string::npos || tol == std::string::npos) {
    ADD_FAILURE() << "no stated bound in:\n" << notes.substr(0, 2000);
    return 0;
  }
  const double bound = std::stod(notes.substr(at + within.size()));
  const double tolerance = std::stod(notes.substr(tol + proven.size()));
  EXPECT_LE(bound, tolerance);
  return tolerance;
}

// The meshes' examples use the sphere of radius 50 mm around the origin.
constexpr double kRadius = 50;
// How far plot's drawing of a mesh may stray from its pieces: its tolerance
// (default 0.05 mm), the pieces' own (1e-4 of the mesh's extent: 0.01 mm,
// checked below against what the tool states) and half a quantum (0.001 mm)
// on each axis.
constexpr double kPlotBound = 0.05 + 0.01 + 0.001;

TEST_F(MeshCli, PlotOfTheOctahedronSeenFromTheTopIsTheSpheresDisc) {
  // What the tool states for this mesh: 1e-4 of its 100 mm extent.
  const RunResult check = Run("check '" + kOctahedron + "' --grid 1");
  ASSERT_EQ(check.exit_code, 0) << check.err;
  const double construction = StatedTolerance(check.out);
  EXPECT_EQ(construction, 0.01);

  const std::string svg = (dir_ / "octahedron.svg").string();
  const RunResult plot = Run("plot '" + kOctahedron + "' -o '" + svg + "' --view top --fit none");
  ASSERT_EQ(plot.exit_code, 0) << plot.err;
  EXPECT_EQ(plot.out, "");
  EXPECT_NE(plot.err.find("0 patches, 816 curves"), std::string::npos) << plot.err;
  EXPECT_NE(plot.err.find("wrote " + svg + " (svg"), std::string::npos) << plot.err;
  const std::string text = Slurp(svg);
  ASSERT_NE(text.find("<svg"), std::string::npos) << text.substr(0, 200);
  // --fit none: file units, 5 mm margins.
  const Drawing d = ParseSvg(text);
  EXPECT_NEAR(d.width, 2 * kRadius + 10, kPlotBound);
  EXPECT_NEAR(d.height, 2 * kRadius + 10, kPlotBound);
  ExpectOnTheSphere(d, kRadius, kPlotBound);
}

// The same measure tells a wrong drawing: one vertex moved 5 mm outward.
TEST_F(MeshCli, PlotOfAPerturbedOctahedronFailsTheExtentCheck) {
  std::string obj = Slurp(kOctahedron);
  const std::size_t at = obj.find("\nv 50 0 0\n");
  ASSERT_NE(at, std::string::npos);
  obj.replace(at, 10, "\nv 55 0 0\n");
  const std::string file = Write("perturbed.obj", obj);
  const std::string svg = (dir_ / "perturbed.svg").string();
  const RunResult plot = Run("plot '" + file + "' -o '" + svg + "' --view top --fit none");
  ASSERT_EQ(plot.exit_code, 0) << plot.err;
  const TopView v = Measure(ParseSvg(Slurp(svg)));
  EXPECT_FALSE(ExtentIsDiameter(v, kRadius, kPlotBound)) << v.width << " x " << v.height;
  EXPECT_NEAR(v.width, 2 * kRadius + 5, kPlotBound);
  EXPECT_GT(v.largest_radius, kRadius + 1);
}

// The octahedron file at the mesh's defaults (8 sections, tolerance 1e-4 of
// the extent: 816 curves) takes 30 to 60 s on the simulated plotter, at the
// stream's defaults or with --fit 40x40 --speed 250; through the JSON "mesh"
// field, one section per piece and a tolerance of 0.05 mm give 144 curves
// and about 5 to 10 s on a 30 mm page. Nearly all of it is the tool's check
// of the drawing against the exact curves (sim::CompareDrawing on 20,000
// samples per curve, host::ReferenceLines), which the sanitizer build runs
// some 80 times slower: there the test is skipped (tests/CMakeLists.txt).
TEST_F(MeshCli, StreamOfTheOctahedronDrawsTheSpheresDiscOnTheSimulatedPlotter) {
  const std::string json =
      Write("octahedron.json", R"({"units": "mm", "construct": [{"type": "quadric-hermite", )"
                               R"("mesh": ")" +
                                   kOctahedron +
                                   R"(", "mu": "normals", "sections": 1, "tolerance": 0.05}]})");
  const std::string svg = (dir_ / "drawn.svg").string();
  const RunResult r =
      Run("stream '" + json +
          "' --view top --fit 30x30 --speed 400 --accel 10000 --pen-delay 5 --svg '" + svg + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("144 curves streamed to the simulated plotter"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("drawing vs exact curves: max deviation"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(--tolerance): within"), std::string::npos) << r.err;
  EXPECT_NE(
      r.err.find("(400 mm/s, 10000 mm/s² on the path, 20000 mm/s² per axis, pen delay 5 ms): kept"),
      std::string::npos)
      << r.err;
  // What the plotter drew: a 20 mm drawing (30 mm page, 5 mm margins), so
  // the scale is 0.2; the stream's tolerance (0.05 mm), the pieces' scaled,
  // and a diagonal motor step (0.0125 mm).
  const double scale = 20 / (2 * kRadius);
  const double bound = 0.05 + 0.05 * scale + 0.0125 * std::sqrt(2.0);
  const Drawing d = ParseSvg(Slurp(svg));
  EXPECT_EQ(d.width, 30);
  EXPECT_EQ(d.height, 30);
  ExpectOnTheSphere(d, kRadius * scale, bound);
}

TEST_F(MeshCli, TheAppleIsRefusedBecauseItsNormalsWouldHaveToTurnTooFar) {
  const std::string apple = kExamples + "/apple.ply";
  const RunResult r = Run("check '" + apple + "' --grid 33x17");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("apple.ply: the normals would have to turn by up to "), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("more than 30 changes the surface, so it is refused"), std::string::npos)
      << r.err;
}

TEST_F(MeshCli, BrokenObjIsRefusedNamingTheFileAndLine) {
  const std::string file =
      Write("bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 7//1\n");
  ExpectEveryCommandRefuses(
      file, "bad-index.obj:5: f: '7//1': vertex index 7 out of range (the file has 3 vertices)");
}

TEST_F(MeshCli, TruncatedPlyIsRefusedNamingTheFileAndLine) {
  // terrain.ply's 14-line header and its first 3 of 25 vertices.
  std::istringstream terrain(Slurp(kExamples + "/terrain.ply"));
  std::string head;
  std::string line;
  for (int k = 0; k < 17 && std::getline(terrain, line); ++k) head += line + "\n";
  ASSERT_NE(head.find("element vertex 25\n"), std::string::npos);
  const std::string file = Write("truncated.ply", head);
  ExpectEveryCommandRefuses(
      file, "truncated.ply:17: the file ends before vertex 3 of 25 (it is truncated)");

  // A binary body has no lines: the element is named instead.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  binary += std::string(9 * 4, '\0');                     // three vertices at the origin
  binary += std::string(1, '\3') + std::string(7, '\0');  // 3 corners, 1 index and 3 of 4 bytes
  ExpectEveryCommandRefuses(
      Write("truncated-binary.ply", binary),
      "truncated-binary.ply: face 0: the file ends inside it (it is truncated)");
}

TEST_F(MeshCli, NonManifoldObjIsRefusedNamingTheEdge) {
  // Three triangles on the edge from (0,0,0) to (1,0,0): file vertices 1
  // and 2, named 0-based.
  const std::string file = Write("fin.obj",
                                 "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
                                 "f 1 2 3\nf 2 1 4\nf 1 2 5\n");
  ExpectEveryCommandRefuses(file,
                            "fin.obj: the edge between vertices 0 and 1 belongs to 3 triangles (at "
                            "most 2: the mesh is not a manifold)");
}

TEST_F(MeshCli, InconsistentlyOrientedObjIsRefusedNamingTheEdge) {
  // The octahedron with its first face turned over.
  std::string obj = Slurp(kOctahedron);
  const std::size_t at = obj.find("f 1//1 3//3 5//5\n");
  ASSERT_NE(at, std::string::npos);
  obj.replace(at, 17, "f 1//1 5//5 3//3\n");
  ExpectEveryCommandRefuses(Write("flipped.obj", obj),
                            "flipped.obj: the edge between vertices 0 and 2: triangles 0 and 4 run "
                            "along it in the same direction (inconsistent orientation)");
}

}  // namespace
