// SPDX-License-Identifier: MIT
// The fdsurf tool as a user runs it: output on success, and on bad input a
// message on stderr naming the file and place, a non-zero exit, empty stdout.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/reference.h"

#include "tool_run.h"

namespace fdsurf::host {
namespace {

namespace fs = std::filesystem;

using fdsurf::test_support::RunResult;
using fdsurf::test_support::Slurp;

class Cli : public fdsurf::test_support::ToolTest {
 protected:
  Cli() : ToolTest("fdsurf_cli_") {}

  // Asserts the contract for bad input.
  void ExpectRefused(const std::string& args, const std::string& stderr_part) {
    const RunResult r = Run(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(r.out, "") << args;
    EXPECT_NE(r.err.find(stderr_part), std::string::npos)
        << args << "\nstderr: " << r.err << "\nwanted: " << stderr_part;
  }
};

const std::string kTeapot = FDSURF_EXAMPLES_DIR "/teapot.bpt";

std::vector<std::vector<std::string>> ParseCsv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) fields.push_back(cell);
    rows.push_back(fields);
  }
  return rows;
}

TEST_F(Cli, SampleFixedPrintsExactMultiplesOfTheQuantumWithinTheBound) {
  const RunResult r = Run("sample '" + kTeapot + "' --grid 3x2 --quantum 0.005");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const auto rows = ParseCsv(r.out);
  ASSERT_EQ(rows.size(), 1u + 32u * 4u * 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"patch", "i", "j", "x", "y", "z"}));
  const PatchSet set = ReadPatchFile(kTeapot);
  for (std::size_t r_index = 1; r_index < rows.size(); ++r_index) {
    const auto& row = rows[r_index];
    ASSERT_EQ(row.size(), 6u);
    const int patch = std::stoi(row[0]);
    const int i = std::stoi(row[1]);
    const int j = std::stoi(row[2]);
    const Point3 exact = EvaluateReference(set.patches[patch], i / 3.0, j / 2.0);
    for (int c = 0; c < 3; ++c) {
      const std::string& text = row[3 + c];
      // Exact decimal with three places, a multiple of 0.005.
      ASSERT_EQ(text.size() - text.find('.'), 4u) << text;
      const long thousandths = std::lround(std::stod(text) * 1000);
      EXPECT_EQ(thousandths % 5, 0) << text;
      EXPECT_LE(std::fabs(std::stod(text) - exact[c]), 0.51 * 0.005 + 1e-12) << text;
    }
  }
}

TEST_F(Cli, SampleDoublePrintsTheReference) {
  const RunResult r = Run("sample '" + kTeapot + "' --grid 2 --engine double");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = ParseCsv(r.out);
  ASSERT_EQ(rows.size(), 1u + 32u * 9u);
  const PatchSet set = ReadPatchFile(kTeapot);
  const Point3 exact = EvaluateReference(set.patches[5], 0.5, 1.0);
  const auto& row = rows[1 + 5 * 9 + 1 * 3 + 2];
  ASSERT_EQ(row[0], "5");
  for (int c = 0; c < 3; ++c) EXPECT_EQ(std::stod(row[3 + c]), exact[c]);
}

TEST_F(Cli, SampleReadsJson) {
  const std::string file = Write("net.json",
                                 R"({"units": "mm", "surfaces": [{"basis": "catmull-rom", "net": [
        [[0,0,0],[1,0,0],[2,0,0],[3,0,0],[4,0,0]],
        [[0,1,0],[1,1,1],[2,1,2],[3,1,1],[4,1,0]],
        [[0,2,0],[1,2,1],[2,2,3],[3,2,1],[4,2,0]],
        [[0,3,0],[1,3,0],[2,3,0],[3,3,0],[4,3,0]]]}]})");
  const RunResult r = Run("sample '" + file + "' --grid 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Two patches (4×5 net), and Catmull-Rom passes through net[1][1] at (0,0).
  const auto rows = ParseCsv(r.out);
  ASSERT_EQ(rows.size(), 1u + 2u * 4u);
  EXPECT_EQ(rows[1], (std::vector<std::string>{"0", "0", "0", "1.000", "1.000", "1.000"}));
  EXPECT_EQ(rows[8], (std::vector<std::string>{"1", "1", "1", "3.000", "2.000", "1.000"}));
}

TEST_F(Cli, CheckReportsTheWorstErrorAndPasses) {
  const RunResult r = Run("check '" + kTeapot + "' --grid 20x30");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("within the 0.51-quantum bound"), std::string::npos) << r.out;
  const std::size_t at = r.out.find("overall: max error ");
  ASSERT_NE(at, std::string::npos) << r.out;
  const double worst = std::stod(r.out.substr(at + 19));
  EXPECT_GT(worst, 0.3);  // rounding to whole quanta alone errs by up to 0.5
  EXPECT_LE(worst, 0.51);
}

TEST_F(Cli, HelpOnTheToolAndEachCommand) {
  for (const std::string args : {"--help", "sample --help", "check --help"}) {
    const RunResult r = Run(args);
    EXPECT_EQ(r.exit_code, 0) << args;
    EXPECT_NE(r.out.find("--"), std::string::npos) << args;
  }
  EXPECT_NE(Run("sample --help").out.find("--engine"), std::string::npos);
}

TEST_F(Cli, VersionIsTheProjectVersion) {
  const RunResult r = Run("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, std::string("fdsurf ") + FDSURF_VERSION + "\n");
  EXPECT_EQ(r.err, "");
}

TEST_F(Cli, BadInputIsRefusedWithNothingOnStdout) {
  ExpectRefused("sample /nonexistent.bpt --grid 4", "/nonexistent.bpt: cannot open");
  ExpectRefused("sample '" + kTeapot + "' --grid 0", "--grid: '0' is out of range");
  ExpectRefused("sample '" + kTeapot + "' --grid 1025", "between 1 and 1024");
  ExpectRefused("sample '" + kTeapot + "' --grid 4xq", "--grid: '4xq' is not N or NxM");
  ExpectRefused("sample '" + kTeapot + "'", "--grid is required");
  ExpectRefused("sample '" + kTeapot + "' --grid 4 --quantum -1", "--quantum: '-1'");
  ExpectRefused("sample '" + kTeapot + "' --grid 4 --engine float", "--engine");
  ExpectRefused("sample '" + kTeapot + "' --grid 4 --frobnicate", "frobnicate");
  ExpectRefused(
      "bake '" + kTeapot + "'",
      "unknown command 'bake' (expected sample, check, plot, render, stream, joins or ports)");
  ExpectRefused("check '" + kTeapot + "' --grid 4 --quantum 0.000000001",
                "teapot.bpt:2 (patch 0): geometry [0][0].z = 2.4 is out of range");

  const std::string truncated = Write("t.bpt", "2\n3 3\n0 0 0\n");
  ExpectRefused("sample '" + truncated + "' --grid 4", "t.bpt:3: file ends where x was expected");
  const std::string garbled = Write("g.bpt", "1\n3 3\n0 0 0\n1 O 0\n");
  ExpectRefused("sample '" + garbled + "' --grid 4", "g.bpt:4: y 'O' is not a number");
  const std::string basis = Write("b.json", R"({"surfaces": [{"basis": "nurbs", "net": []}]})");
  ExpectRefused("sample '" + basis + "' --grid 4", "b.json: surfaces[0].basis: unknown basis");
  const std::string counts =
      Write("c.json", R"({"surfaces": [{"basis": "bezier", "net": [[[0,0,0],[1,1,1]]]}]})");
  ExpectRefused("sample '" + counts + "' --grid 4",
                "c.json: surfaces[0].net: a bezier net must be (3m+1)x(3n+1) points, got 1x2");
  const std::string broken = Write("d.json", "{\"surfaces\": [\n{]}");
  ExpectRefused("sample '" + broken + "' --grid 4", "d.json:2:2: invalid JSON");
  const std::string empty = Write("e.bpt", "  \n");
  ExpectRefused("sample '" + empty + "' --grid 4", "e.bpt:1: file ends where the number");
  // A top-level field is named without a leading dot, like the nested ones.
  const std::string units = Write("u.json", R"({"units": "furlong", "surfaces": []})");
  ExpectRefused("sample '" + units + "' --grid 4", "/u.json: units: must be \"mm\" or \"in\"");
  // A piecewise curve whose segments do not meet: both segments and the gap.
  const std::string torn = Write("r.json", R"({"construct": [{"type": "ruled", "curves": [
    [{"basis": "bezier", "points": [[0,0],[1,0],[2,0],[3,0]]},
     {"basis": "bezier", "points": [[3,0.25],[4,0],[5,0],[6,0]]}],
    [{"basis": "bezier", "points": [[0,3],[1,3],[2,3],[3,3]]},
     {"basis": "bezier", "points": [[3,3],[4,3],[5,3],[6,3]]}]]}]})");
  ExpectRefused("check '" + torn + "' --grid 4",
                "r.json: construct[0].curves[0]: construct[0].curves[0][0] ends at (3, 0, 0) but "
                "construct[0].curves[0][1] starts at (3, 0.25, 0), 0.25 apart (tolerance 6e-09)");
}

// Bad plot options: a clear message, a non-zero exit, and no output file at
// all (not even an empty or partial one).
TEST_F(Cli, PlotRefusesBadOptionsAndLeavesNoFile) {
  const std::string out = (dir_ / "out.svg").string();
  const auto refused = [&](const std::string& args, const std::string& part) {
    ExpectRefused("plot '" + kTeapot + "' -o '" + out + "' " + args, part);
    EXPECT_FALSE(fs::exists(out)) << args;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      EXPECT_EQ(entry.path().filename().string().find("out.svg"), std::string::npos) << args;
    }
  };
  refused("--tolerance -0.1", "--tolerance: '-0.1' must be greater than zero");
  refused("--tolerance abc", "--tolerance: 'abc' is not a number");
  refused("--tolerance 0.0005", "--tolerance 0.0005 mm is too small");
  refused("--view diagonal", "--view: 'diagonal' is not a view");
  refused("--view 10,100", "elevation 100 is outside -90..90");
  refused("--lines 1", "--lines: '1' is not U or UxV");
  refused("--lines 0x0", "both families are left out");
  refused("--fit 20x10 --margin 10", "--fit: the page 20x10 leaves no room");
  refused("--fit 20", "--fit: '20' is not WxH");
  refused("--dims 3", "--dims 3: only G-code and JSON carry a third axis");
  refused("--format hpgl --quantum 0.01", "HPGL positions are plotter units");
  ExpectRefused("plot '" + kTeapot + "' -o '" + (dir_ / "missing" / "out.svg").string() + "'",
                "missing/out.svg.fdsurf-");
  ExpectRefused(
      "plot '" + kTeapot + "' -o '" + out + "' --png '" + (dir_ / "no" / "t.png").string() + "'",
      "t.png");
  EXPECT_FALSE(fs::exists(out));  // the SVG is not written when the PNG cannot be
  ExpectRefused("render '" + kTeapot + "'", "--output is required");
}

TEST_F(Cli, PlotWritesEachFormat) {
  for (const char* format : {"svg", "gcode", "hpgl", "json"}) {
    const std::string out = (dir_ / (std::string("teapot.") + format)).string();
    const RunResult r = Run("plot '" + kTeapot + "' -o '" + out + "' --lines 4 --fit 150x100");
    EXPECT_EQ(r.exit_code, 0) << format << r.err;
    EXPECT_NE(r.err.find("wrote " + out + " (" + format), std::string::npos) << r.err;
    EXPECT_GT(fs::file_size(out), 1000u) << format;
  }
  const RunResult render =
      Run("render '" + kTeapot + "' -o '" + (dir_ / "t.png").string() + "' --size 300");
  EXPECT_EQ(render.exit_code, 0) << render.err;
  const std::string png = Slurp(dir_ / "t.png");
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  // Every output went through a temporary that is gone afterwards.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

TEST_F(Cli, StreamDrawsOnTheSimulatedPlotterAndReports) {
  const std::string svg = (dir_ / "drawn.svg").string();
  const std::string png = (dir_ / "drawn.png").string();
  const RunResult r = Run("stream '" + kTeapot +
                          "' --fit 24x18 --lines 3 --speed 250 --accel 5000 --pen-delay 5 --svg '" +
                          svg + "' --png '" + png + "' --size 300");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("32 patches streamed to the simulated plotter"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bytes of G-code for the same drawing"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(--tolerance): within"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pen delay 5 ms): kept"), std::string::npos) << r.err;
  EXPECT_NE(Slurp(svg).find("<svg"), std::string::npos);
  EXPECT_EQ(Slurp(png).substr(1, 3), "PNG");
  // Through a lossy link: the same result, with retransmissions reported.
  const RunResult lossy =
      Run("stream '" + kTeapot +
          "' --fit 24x18 --lines 3 --speed 250 --accel 5000 --pen-delay 5 --faults 0.05 --seed 9");
  ASSERT_EQ(lossy.exit_code, 0) << lossy.err;
  EXPECT_NE(lossy.err.find("(--tolerance): within"), std::string::npos) << lossy.err;
  EXPECT_EQ(lossy.err.find(" 0 resent"), std::string::npos) << lossy.err;
}

// Issue 12, defect 1: two patches 70 m apart at 1 µm steps were sent, and
// the device faulted mid-job with an undecoded "detail 4" (exit 3). Now the
// host refuses the job before sending anything (exit 2), in millimetres.
TEST_F(Cli, StreamRefusesATravelTooLongForTheDeviceBeforeSendingAnything) {
  std::ifstream in(kTeapot);
  std::string count;
  std::string line;
  std::getline(in, count);
  std::string patch;
  for (int k = 0; k < 17 && std::getline(in, line); ++k) patch += line + "\n";
  std::string far;
  std::istringstream rows(patch);
  std::getline(rows, line);
  far += line + "\n";
  while (std::getline(rows, line)) {
    std::istringstream xyz(line);
    double x = 0, y = 0, z = 0;
    xyz >> x >> y >> z;
    far += std::to_string(x + 70000) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
  }
  const std::string file = Write("far.bpt", "2\n" + patch + far);
  const RunResult r = Run("stream '" + file +
                          "' --fit none --view top --step 0.001 --speed 10 --accel 100 --lines 2");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is more than the device can travel: at most 67108864 steps of 0.001 mm"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("frames sent"), std::string::npos) << r.err;
}

// With the device's compute time charged as on an ATmega2560, validating a
// 16-line teapot patch takes longer than the link's first retransmit
// timeout: the link shows it (timeouts, resent frames) and still finishes
// with the same drawing; without the cost there are none.
TEST_F(Cli, StreamChargesTheDevicesComputeTimeOnRequest) {
  const std::string job =
      "stream '" + kTeapot + "' --fit 24x18 --speed 250 --accel 5000 --pen-delay 5";
  const RunResult free = Run(job);
  ASSERT_EQ(free.exit_code, 0) << free.err;
  EXPECT_NE(free.err.find(" 0 timeouts"), std::string::npos) << free.err;
  const RunResult mega = Run(job + " --sim-cost atmega2560");
  ASSERT_EQ(mega.exit_code, 0) << mega.err;
  EXPECT_EQ(mega.err.find(" 0 timeouts"), std::string::npos) << mega.err;
  EXPECT_NE(mega.err.find("(--tolerance): within"), std::string::npos) << mega.err;
}

TEST_F(Cli, StreamRefusesBadOptionsAndMissingDevices) {
  ExpectRefused("stream '" + kTeapot + "' --device serial", "--device: 'serial' is not sim");
  ExpectRefused("stream '" + kTeapot + "' --device usb --faults 0.1",
                "--svg, --png, --waveform, --faults and --sim-cost are for --device sim");
  ExpectRefused("stream '" + kTeapot + "' --sim-cost z80", "--sim-cost");
  ExpectRefused("stream '" + kTeapot + "' --travel 100x100", "--travel X 100 mm is smaller than");
  ExpectRefused("stream '" + kTeapot + "' --tolerance 0.005", "--tolerance 0.005 mm is too small");
  ExpectRefused("stream '" + kTeapot + "' --tick-hz 30000", "--tick-hz: 30000 does not divide");
  ExpectRefused("stream '" + kTeapot + "' --tick-hz 5000",
                "--speed 100 mm/s is 8000 steps/s, more than the device's 5000 ticks/s");
  ExpectRefused("stream '" + kTeapot + "' --device gpio:gpiochip0:1,2,3", "--device: ");
  // No such hardware here: a clear message and exit code 3.
  const RunResult usb = Run("stream '" + kTeapot + "' --device usb:1209:0001");
  EXPECT_EQ(usb.exit_code, 3) << usb.err;
  EXPECT_NE(usb.err.find("1209:0001"), std::string::npos) << usb.err;
  const RunResult gpio = Run("stream '" + kTeapot + "' --device gpio:gpiochip99:1,2,3,4,5,6");
  EXPECT_EQ(gpio.exit_code, 3) << gpio.err;
  EXPECT_NE(gpio.err.find("gpiochip99"), std::string::npos) << gpio.err;
  // A tolerance that whole steps cannot keep is refused before anything moves.
  EXPECT_EQ(Run("stream '" + kTeapot + "' --step 0.1 --tolerance 0.05").exit_code, 2);
}

}  // namespace
}  // namespace fdsurf::host
