// SPDX-License-Identifier: MIT
// `fdsurf plot -o X.gcode` states the machine time a G-code machine takes
// (issue 15, "Knowing before starting"): on stderr and as header comments.
// A 40 mm square, whose time follows from the trapezoid formulas by hand
// (docs/toolpaths.md, "Time estimate"), checks the figure; reading the file
// back with fdsurf's own G-code reader, before and after a sender's comment
// stripping, checks that the header lines are comments of the flavour.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <sstream>
#include <string>

#include "fdsurf/host/patch_io.h"
#include "tool_run.h"

namespace fdsurf::host {
namespace {

using test_support::RunResult;
using test_support::Slurp;

class PlotEstimate : public test_support::ToolTest {
 protected:
  PlotEstimate() : ToolTest("fdsurf_plot_estimate_") {}

  // A 60 x 60 mm page with the square (10, 10)..(50, 50) in output
  // coordinates (SVG's y runs down: M 10 50 is the output's (10, 10)).
  std::string Square() {
    return Write("square.svg",
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"60mm\" height=\"60mm\" "
                 "viewBox=\"0 0 60 60\"><path d=\"M 10 50 H 50 V 10 H 10 Z\" fill=\"none\" "
                 "stroke=\"black\"/></svg>");
  }

  // plot of the square (planned into one stroke) with the pen switched by M3/M5 (so that the only
  // moves are the travel and the four sides): feed 1200 mm/min (20 mm/s),
  // G0 3000 mm/min (50 mm/s), 100 mm/s², dwell 0.2 s.
  RunResult PlotSquare(const std::string& flavor, const std::string& junction,
                       const std::string& out) {
    return Run("plot '" + Square() + "' --flavor " + flavor +
               " --pen m3 --feed 1200 --travel-rate 3000 --accel 100 --dwell 0.2"
               " --junction-deviation " +
               junction + " -o '" + out + "'");
  }
};

constexpr double kAccel = 100;  // mm/s²
constexpr double kFeed = 20;    // mm/s
constexpr double kRapid = 50;   // mm/s
constexpr double kSide = 40;    // mm

// A move of length L from v0 to v1 that reaches v (trapezoid): the ramps
// take (v − v0)/a + (v − v1)/a and cover (v² − v0²)/2a + (v² − v1²)/2a;
// the rest is at v.
double Trapezoid(double length, double v0, double v1, double v) {
  const double ramps = (v * v - v0 * v0) / (2 * kAccel) + (v * v - v1 * v1) / (2 * kAccel);
  return (v - v0) / kAccel + (v - v1) / kAccel + (length - ramps) / v;
}

// The square's time with a corner speed `corner`: travel out and back (a
// triangle, 14.14 mm is too short to reach 50 mm/s: 2·√(L/a)), three
// dwells (M5 at the start, M3, M5), the four sides entering and leaving at
// the corners' speed (at rest at the stroke's ends).
double SquareSeconds(double corner) {
  const double travel = 2 * 2 * std::sqrt(std::hypot(10.0, 10.0) / kAccel);
  EXPECT_LT(std::hypot(10.0, 10.0), kRapid * kRapid / kAccel);  // the triangle case
  const double dwells = 3 * 0.2;
  const double sides =
      2 * Trapezoid(kSide, 0, corner, kFeed) + 2 * Trapezoid(kSide, corner, corner, kFeed);
  return travel + dwells + sides;
}

// The header's "estimated time H:MM:SS = S.SS s".
double HeaderSeconds(const std::string& gcode) {
  std::smatch m;
  if (!std::regex_search(gcode, m, std::regex("estimated time [0-9:]+ = ([0-9.]+) s"))) {
    ADD_FAILURE() << "no estimate in:\n" << gcode;
    return -1;
  }
  return std::stod(m[1].str());
}

// What a sender such as Grbl's own line reader keeps of a program: `( … )`
// and `; …` to the end of the line removed, blank lines dropped.
std::string StripComments(const std::string& gcode, std::size_t* comment_lines) {
  std::istringstream in(gcode);
  std::string line;
  std::string out;
  *comment_lines = 0;
  while (std::getline(in, line)) {
    std::string kept;
    bool in_paren = false;
    for (const char c : line) {
      if (in_paren) {
        EXPECT_NE(c, '(') << "nested parenthesis in: " << line;
        in_paren = c != ')';
      } else if (c == '(') {
        in_paren = true;
      } else if (c == ';') {
        break;
      } else {
        kept += c;
      }
    }
    EXPECT_FALSE(in_paren) << "unclosed comment: " << line;
    if (kept.find_first_not_of(' ') == std::string::npos) {
      ++*comment_lines;
      continue;
    }
    out += kept + "\n";
  }
  return out;
}

// Exact stops at the corners (junction deviation 0): each side is the
// whole trapezoid 0 → 20 → 0 mm/s, 40/20 + 20/100 = 2.2 s.
TEST_F(PlotEstimate, SquareWithStopsAtCornersTakesTheTrapezoidsTime) {
  const std::string out = (dir_ / "square.gcode").string();
  const RunResult r = PlotSquare("grbl", "0", out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string gcode = Slurp(out);
  const double expected = SquareSeconds(0);
  EXPECT_NEAR(expected, 10.904, 0.001);  // by hand: 1.504 + 0.6 + 4 × 2.2
  // The header prints two decimals.
  EXPECT_NEAR(HeaderSeconds(gcode), expected, 0.005 + 1e-9);
  EXPECT_NE(gcode.find("(estimate: pen down 160.0 mm, travel 28.3 mm, 1 pen lift)"),
            std::string::npos)
      << gcode;
  EXPECT_NE(gcode.find("(estimate: extent x 10..50, y 10..50 mm)"), std::string::npos) << gcode;
  EXPECT_NE(gcode.find("accel 100 mm/s^2, junction deviation 0 mm, dwell 0.2 s"), std::string::npos)
      << gcode;
  // stderr says the same, as stream --dry-run does.
  EXPECT_NE(r.err.find("machine time: 10.9 s (0:11)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pen down: 160.0 mm, travel (G0): 28.3 mm, 1 pen lift"), std::string::npos)
      << r.err;
}

// Grbl's junction deviation δ = 0.01 mm at a 90° corner: v² = a·δ·s/(1 − s)
// with s = sin 45°, 1.554 mm/s; the sides no longer stop there.
TEST_F(PlotEstimate, SquareWithJunctionDeviationPassesTheCornersAtGrblsSpeed) {
  const std::string out = (dir_ / "square.gcode").string();
  const RunResult r = PlotSquare("marlin", "0.01", out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double s = std::sin(M_PI / 4);
  const double corner = std::sqrt(kAccel * 0.01 * s / (1 - s));
  EXPECT_NEAR(corner, 1.554, 0.001);
  const double expected = SquareSeconds(corner);
  EXPECT_LT(expected, SquareSeconds(0) - 0.05);
  EXPECT_NEAR(HeaderSeconds(Slurp(out)), expected, 0.005 + 1e-9);
}

// Grbl's per-axis limits ($120..$122): a move accelerates at most at
// min(accel, limit_i / |u_i|). With X held to 50 mm/s² and stops at the
// corners, the horizontal sides ramp at 50 (20²/50 = 8 mm of ramps: 0.8 s
// + 32/20 s = 2.4 s), the vertical ones at 100 (2.2 s), and the diagonal
// travel at 50/cos 45° = 70.7 mm/s² (a triangle, 2·√(L/a) each way).
TEST_F(PlotEstimate, AnAxisLimitSlowsTheMovesAlongThatAxis) {
  const std::string out = (dir_ / "square.gcode").string();
  const RunResult r = Run("plot '" + Square() +
                          "' --flavor grbl --pen m3 --feed 1200 --travel-rate 3000 --accel 100 "
                          "--dwell 0.2 --junction-deviation 0 --accel-x 50 -o '" +
                          out + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double diagonal_accel = 50 / std::cos(M_PI / 4);
  const double travel = 2 * 2 * std::sqrt(std::hypot(10.0, 10.0) / diagonal_accel);
  const double horizontal = 2 * kFeed / 50 + (kSide - kFeed * kFeed / 50) / kFeed;
  EXPECT_NEAR(horizontal, 2.4, 1e-12);
  const double expected = travel + 3 * 0.2 + 2 * horizontal + 2 * Trapezoid(kSide, 0, 0, kFeed);
  EXPECT_NEAR(expected, 11.589, 0.001);
  EXPECT_NEAR(HeaderSeconds(Slurp(out)), expected, 0.005 + 1e-9);
  EXPECT_GT(expected, SquareSeconds(0) + 0.5);  // what the square takes without the limit
  EXPECT_NE(Slurp(out).find("accel 100 mm/s^2, X 50 mm/s^2 per axis, junction"), std::string::npos);
  EXPECT_NE(r.err.find("accel 100 mm/s², X 50 mm/s² per axis"), std::string::npos) << r.err;
}

// The header's lines are comments in both syntaxes: the file reads back as
// the square alone, and so does what a sender keeps after stripping them.
TEST_F(PlotEstimate, HeaderIsCommentsThatReaderAndSenderSkip) {
  for (const char* flavor : {"grbl", "marlin", "generic", "linuxcnc"}) {
    SCOPED_TRACE(flavor);
    const std::string out = (dir_ / (std::string(flavor) + ".gcode")).string();
    const RunResult r = PlotSquare(flavor, "0.01", out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string gcode = Slurp(out);
    const PatchSet read = ReadPatchFile(out);
    ASSERT_EQ(read.curves.size(), 4u);  // the square's four sides
    std::size_t comments = 0;
    const std::string stripped = Write("stripped.gcode", StripComments(gcode, &comments));
    // Every header line, the estimate's five among them, is a whole comment.
    std::istringstream lines(gcode);
    std::string line;
    std::size_t header = 0;
    while (std::getline(lines, line) && line.rfind("G2", 0) != 0) {
      ++header;
      if (line.find("estimate") < 3) {  // "(estimate…" or "; estimate…"
        EXPECT_LE(line.size(), 80u) << line;
      }
    }
    EXPECT_GE(comments, header);
    EXPECT_GE(header, 9u);  // 4 of plot, the flavour's (not generic), 5 of the estimate
    EXPECT_EQ(ReadPatchFile(stripped).curves.size(), read.curves.size());
  }
}

}  // namespace
}  // namespace fdsurf::host
