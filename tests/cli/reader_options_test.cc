// SPDX-License-Identifier: MIT
// The readers' options on the command line (--arc-tolerance, --pen-z-below,
// --servo-down-below, --no-block-delete): each changes what is read, a bad
// value or one the format read does not take is refused naming the flag,
// with a non-zero exit and no output.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tool_run.h"

namespace fdsurf::host {
namespace {

using fdsurf::test_support::RunResult;

class ReaderOptions : public fdsurf::test_support::ToolTest {
 protected:
  ReaderOptions() : ToolTest("fdsurf_reader_options_") {}

  // The curve count of `fdsurf plot FILE FLAGS` from its summary line.
  int Curves(const std::string& file, const std::string& flags) {
    const RunResult r = Run("plot '" + file + "' --format json -o '" + Out() + "' " + flags);
    EXPECT_EQ(r.exit_code, 0) << flags << "\n" << r.err;
    const std::size_t at = r.err.find(" curves,");
    if (at == std::string::npos) return -1;
    const std::size_t from = r.err.rfind(' ', at - 1) + 1;
    return std::stoi(r.err.substr(from, at - from));
  }

  void ExpectRefused(const std::string& file, const std::string& flags, const std::string& part) {
    std::filesystem::remove(Out());
    const RunResult r = Run("plot '" + file + "' --format json -o '" + Out() + "' " + flags);
    EXPECT_NE(r.exit_code, 0) << flags;
    EXPECT_EQ(r.out, "") << flags;
    EXPECT_FALSE(std::filesystem::exists(Out())) << flags;
    EXPECT_NE(r.err.find(part), std::string::npos) << flags << "\nstderr: " << r.err;
  }

  std::string Out() const { return (dir_ / "out.json").string(); }
};

TEST_F(ReaderOptions, ArcToleranceSetsTheNumberOfCubics) {
  // A half circle of radius 10 mm: 8 standard cubics within 1e-6 mm, 2 within
  // 1e-2 mm (docs/formats.md, "Circular and elliptical arcs").
  const std::string gcode = Write("half.gcode", "G21\nG0 X10 Y0\nG2 X-10 Y0 I-10 J0\n");
  EXPECT_EQ(Curves(gcode, ""), 8);
  EXPECT_EQ(Curves(gcode, "--arc-tolerance 1e-2"), 2);
  // The same half circle in SVG (mm on the page): the same counts.
  const std::string svg =
      Write("half.svg", R"(<svg xmlns="http://www.w3.org/2000/svg" width="40mm" )"
                        R"(height="40mm" viewBox="0 0 40 40">)"
                        R"(<path d="M30 20 A10 10 0 0 1 10 20"/></svg>)");
  EXPECT_EQ(Curves(svg, ""), 8);
  EXPECT_EQ(Curves(svg, "--arc-tolerance 1e-2"), 2);
}

TEST_F(ReaderOptions, BadArcTolerancesAreRefusedNamingTheFlag) {
  const std::string gcode = Write("half.gcode", "G0 X10 Y0\nG2 X-10 Y0 I-10 J0\n");
  ExpectRefused(gcode, "--arc-tolerance 0", "--arc-tolerance: '0' must be greater than zero");
  ExpectRefused(gcode, "--arc-tolerance -1", "--arc-tolerance: '-1' must be greater than zero");
  ExpectRefused(gcode, "--arc-tolerance x", "--arc-tolerance: 'x' is not a number");
  // Below what double rounding allows at these coordinates.
  ExpectRefused(gcode, "--arc-tolerance 1e-14",
                "half.gcode:2: G2: the arc cannot be drawn within the arc tolerance "
                "(--arc-tolerance) 1e-14");
  const std::string svg =
      Write("big.svg", R"(<svg xmlns="http://www.w3.org/2000/svg" width="40mm" )"
                       R"(height="40mm" viewBox="0 0 40 40">)"
                       R"(<path d="M30 20 A10 10 0 0 1 10 20"/></svg>)");
  ExpectRefused(svg, "--arc-tolerance 1e-15", "the arc tolerance (--arc-tolerance) 1e-15 mm");
}

TEST_F(ReaderOptions, FlagsTheFormatDoesNotTakeAreRefused) {
  const std::string bpt = FDSURF_EXAMPLES_DIR "/teapot.bpt";
  ExpectRefused(bpt, "--arc-tolerance 1e-3", "--arc-tolerance: " + bpt + " is bpt input");
  const std::string svg = Write("a.svg", R"(<svg xmlns="http://www.w3.org/2000/svg" width="10mm" )"
                                         R"(height="10mm"><path d="M1 1 L5 5"/></svg>)");
  ExpectRefused(svg, "--pen-z-below 1", "--pen-z-below: " + svg + " is svg input");
  ExpectRefused(svg, "--servo-down-below 10", "--servo-down-below: " + svg + " is svg input");
  ExpectRefused(svg, "--no-block-delete", "--no-block-delete: " + svg + " is svg input");
  // check reads with the same flags.
  const RunResult r = Run("check '" + bpt + "' --grid 2 --arc-tolerance 1e-3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--arc-tolerance: " + bpt + " is bpt input"), std::string::npos) << r.err;
}

TEST_F(ReaderOptions, GcodePenConventions) {
  // Z 0.5 is up by default (down while Z <= 0), down with --pen-z-below 0.6.
  const std::string z = Write("z.gcode", "G0 Z1\nG0 X0 Y0\nG1 Z0.5\nG1 X10\nG1 Z1\n");
  ExpectRefused(z, "", "z.gcode: the program draws nothing");
  EXPECT_EQ(Curves(z, "--pen-z-below 0.6"), 1);
  ExpectRefused(z, "--pen-z-below high", "--pen-z-below: 'high' is not a number");
  // A servo at 60°: up by default (down below 50°), down below 70°.
  const std::string servo = Write("s.gcode", "M280 P0 S60\nG1 X10\n");
  ExpectRefused(servo, "", "s.gcode: the program draws nothing");
  EXPECT_EQ(Curves(servo, "--servo-down-below 70"), 1);
  // A block-delete line: skipped by default, run with --no-block-delete.
  const std::string skip = Write("b.gcode", "G1 X10\n/G1 X20\n");
  EXPECT_EQ(Curves(skip, ""), 1);
  EXPECT_EQ(Curves(skip, "--no-block-delete"), 2);
}

}  // namespace
}  // namespace fdsurf::host
