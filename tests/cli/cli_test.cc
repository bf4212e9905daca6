// SPDX-License-Identifier: MIT
// The fdsurf tool as a user runs it: output on success, and on bad input a
// message on stderr naming the file and place, a non-zero exit, empty stdout.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
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

  // Runs `fdsurf ARGS` with standard input read from `input` (a file).
  RunResult RunWithInput(const std::string& args, const std::string& input) {
    const fs::path out = dir_ / "stdout";
    const fs::path err = dir_ / "stderr";
    const std::string command = std::string("timeout 120 '") + FDSURF_BINARY + "' " + args + " >'" +
                                out.string() + "' 2>'" + err.string() + "' <'" + input + "'";
    const int status = std::system(command.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, Slurp(out), Slurp(err)};
  }

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
  ExpectRefused("bake '" + kTeapot + "'",
                "unknown command 'bake' (expected sample, check, plot, render, stream, joins, "
                "ports, machine or serve)");
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
  refused("--dims 3", "--dims 3: only G-code and JSON carry a third axis");
  refused("--fit 20", "--fit: '20' is not WxH (like 200x150) or a paper name");
  ExpectRefused("plot '" + kTeapot + "' -o '" + (dir_ / "out.hpgl").string() + "' --quantum 0.01",
                "HPGL positions are plotter units");
  EXPECT_FALSE(fs::exists(dir_ / "out.hpgl"));
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
      "stream '" + kTeapot + "' --fit 24x18 --speed 250 --accel 5000 --pen-delay 5 --plan patches";
  const RunResult free = Run(job);
  ASSERT_EQ(free.exit_code, 0) << free.err;
  EXPECT_NE(free.err.find(" 0 timeouts"), std::string::npos) << free.err;
  const RunResult mega = Run(job + " --sim-cost atmega2560");
  ASSERT_EQ(mega.exit_code, 0) << mega.err;
  EXPECT_EQ(mega.err.find(" 0 timeouts"), std::string::npos) << mega.err;
  EXPECT_NE(mega.err.find("(--tolerance): within"), std::string::npos) << mega.err;
  EXPECT_NE(mega.err.find("of its main loop validating commands"), std::string::npos) << mega.err;
  EXPECT_EQ(free.err.find("of its main loop validating commands"), std::string::npos) << free.err;
  // The lines plan sends one line a command: validating any of them is
  // quicker than the timeout, and the same cost makes none (issue 36, "no
  // stall").
  const std::string lines =
      "stream '" + kTeapot + "' --fit 24x18 --speed 250 --accel 5000 --pen-delay 5 --plan lines";
  const RunResult mega_lines = Run(lines + " --sim-cost atmega2560");
  ASSERT_EQ(mega_lines.exit_code, 0) << mega_lines.err;
  EXPECT_NE(mega_lines.err.find(" 0 timeouts"), std::string::npos) << mega_lines.err;
  EXPECT_NE(mega_lines.err.find("of its main loop validating commands"), std::string::npos)
      << mega_lines.err;
}

// --sim-64bit-tables gives the simulated plotter the job as the Uno (a
// device of 64-bit tables only) is given it: the prepared lines it could
// not hold in pieces, drawn within the same bound (the reference of the
// Uno's end-to-end tests, tests/boards/run_e2e.py).
TEST_F(Cli, StreamSendsTheSimTheUnosPiecesOnRequest) {
  const std::string job = "stream '" + kTeapot +
                          "' --fit 20x15 --lines 0x2 --tick-hz 2000 --speed 20 --prepare-on-host";
  const RunResult whole = Run(job);
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const RunResult pieces = Run(job + " --sim-64bit-tables");
  ASSERT_EQ(pieces.exit_code, 0) << pieces.err;
  // Some lines go in pieces: more commands (57 and 65 with the lines plan).
  const auto commands = [](const std::string& err) {
    const std::size_t at = err.find(" commands, ");
    const std::size_t from = err.rfind('(', at);
    return at == std::string::npos || from == std::string::npos
               ? 0
               : std::stoul(err.substr(from + 1, at - from - 1));
  };
  EXPECT_GT(commands(whole.err), 0u) << whole.err;
  EXPECT_GT(commands(pieces.err), commands(whole.err)) << whole.err << pieces.err;
  EXPECT_NE(pieces.err.find("(--tolerance): within"), std::string::npos) << pieces.err;
  ExpectRefused("stream '" + kTeapot + "' --sim-64bit-tables",
                "--sim-64bit-tables is for --device sim with --prepare-on-host");
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

// A JSON curve from (10, 10) to (40, 30) in mm, monotone in x and y: its
// extent is its end points, so every placement can be worked out by hand.
const char* const kCurveJson = R"({"units": "mm", "curves": [{"type": "cubic", "basis": "bezier",
  "points": [[10, 10, 0], [20, 10, 0], [30, 20, 0], [40, 30, 0]]}]})";

// The page of an SVG written by fdsurf: its width and height attributes (mm or in).
std::array<double, 2> SvgPage(const std::string& svg) {
  const auto attribute = [&](const std::string& name) {
    const std::size_t at = svg.find(" " + name + "=\"");
    if (at == std::string::npos) return -1.0;
    return std::stod(svg.substr(at + name.size() + 3));
  };
  return {attribute("width"), attribute("height")};
}

// The first position a G-code program moves to: "G0 X.. Y.." as text.
std::string FirstMove(const std::string& gcode) {
  const std::size_t at = gcode.find("\nG0 X");
  if (at == std::string::npos) return "";
  return gcode.substr(at + 4, gcode.find('\n', at + 1) - at - 4);
}

TEST_F(Cli, FitTakesPaperNamesPortraitOrLandscapeInEitherUnit) {
  const std::string out = (dir_ / "page.svg").string();
  // ISO 216 (mm) and the US sizes (8.5 x 11 and 8.5 x 14 inches), portrait.
  struct Paper {
    const char* name;
    double width_mm;
    double height_mm;
  };
  const Paper papers[] = {{"A3", 297, 420},
                          {"A4", 210, 297},
                          {"A5", 148, 210},
                          {"letter", 215.9, 279.4},
                          {"legal", 215.9, 355.6}};
  for (const Paper& paper : papers) {
    for (const bool landscape : {false, true}) {
      for (const std::string units : {"mm", "in"}) {
        const std::string fit = std::string(paper.name) + (landscape ? ":landscape" : "");
        const RunResult r = Run("plot '" + kTeapot + "' --lines 2 -q --units " + units + " --fit " +
                                fit + " -o '" + out + "'");
        ASSERT_EQ(r.exit_code, 0) << fit << r.err;
        const double per_unit = units == "in" ? 25.4 : 1.0;
        const double w = (landscape ? paper.height_mm : paper.width_mm) / per_unit;
        const double h = (landscape ? paper.width_mm : paper.height_mm) / per_unit;
        const auto page = SvgPage(Slurp(out));
        // The writer prints the page in whole quanta (0.001 mm, 0.0001 in).
        EXPECT_NEAR(page[0], w, units == "in" ? 1e-4 : 1e-3) << fit << " " << units;
        EXPECT_NEAR(page[1], h, units == "in" ? 1e-4 : 1e-3) << fit << " " << units;
      }
    }
  }
  EXPECT_EQ(SvgPage(Slurp(out))[0] > 0, true);
  for (const char* bad : {"A7", "A4:sideways", "200x150:landscape", "letterx", "x", ":landscape"}) {
    ExpectRefused(
        "plot '" + kTeapot + "' --fit '" + bad + "' -o '" + (dir_ / "bad.svg").string() + "'",
        std::string("--fit: '") + bad +
            "' is not WxH (like 200x150) or a paper name (A3, A4, A5, letter, legal, "
            "optionally :landscape)");
    EXPECT_FALSE(fs::exists(dir_ / "bad.svg")) << bad;
  }
  ExpectRefused("stream '" + kTeapot + "' --fit A7", "--fit: 'A7' is not WxH");
}

TEST_F(Cli, OriginKeepWritesTheFilesCoordinates) {
  const std::string file = Write("curve.json", kCurveJson);
  const RunResult keep = Run("plot '" + file + "' --view top --origin keep --format gcode -q");
  ASSERT_EQ(keep.exit_code, 0) << keep.err;
  EXPECT_EQ(FirstMove(keep.out), "X10.000 Y10.000");
  EXPECT_NE(keep.out.find("\nG1 X40.000 Y30.000"), std::string::npos) << keep.out;
  // min without a page: the lower-left corner (10, 10) at the 5 mm margin.
  const RunResult min =
      Run("plot '" + file + "' --view top --origin min --fit none --format gcode -q");
  ASSERT_EQ(min.exit_code, 0) << min.err;
  EXPECT_EQ(FirstMove(min.out), "X5.000 Y5.000");
  // center on 100 x 100 with no margin: scale 100/30, the 66.667-high
  // drawing centred, so (10, 10) goes to (0, 16.667).
  const RunResult center = Run("plot '" + file +
                               "' --view top --origin center --fit 100x100 --margin 0 "
                               "--format gcode -q");
  ASSERT_EQ(center.exit_code, 0) << center.err;
  EXPECT_EQ(FirstMove(center.out), "X0.000 Y16.667");
  // keep with a page the drawing lies in: that page, unscaled.
  const std::string svg = (dir_ / "keep.svg").string();
  const RunResult paged =
      Run("plot '" + file + "' --view top --origin keep --fit 50x40 -q -o '" + svg + "'");
  ASSERT_EQ(paged.exit_code, 0) << paged.err;
  EXPECT_EQ(SvgPage(Slurp(svg)), (std::array<double, 2>{50, 40}));
  EXPECT_NE(Slurp(svg).find("M10.000 30.000"), std::string::npos);  // y down: 40 - 10
  // keep with a page it does not fit: refused, no file.
  const std::string small = (dir_ / "small.svg").string();
  ExpectRefused("plot '" + file + "' --view top --origin keep --fit 30x30 -o '" + small + "'",
                "--fit 30x30 is a page the drawing does not lie inside as it is (x 10..40, y "
                "10..30)");
  EXPECT_FALSE(fs::exists(small));
  ExpectRefused("plot '" + file + "' --origin middle",
                "--origin: 'middle' is not keep, center or min");
}

// A drawing below 0 under keep: G-code carries it as it is, the SVG shows
// more than the page so that nothing is cut off (and says so), and a
// machine's travel starts at 0, so stream refuses it.
TEST_F(Cli, OriginKeepBelowZeroIsWrittenToGcodeAndSvgAndRefusedForStream) {
  std::string text = kCurveJson;
  text.replace(text.find("[10, 10, 0]"), 11, "[-10, 10, 0]");
  const std::string file = Write("negative.json", text);
  const RunResult gcode = Run("plot '" + file + "' --view top --origin keep --format gcode -q");
  ASSERT_EQ(gcode.exit_code, 0) << gcode.err;
  EXPECT_EQ(FirstMove(gcode.out), "X-10.000 Y10.000");
  // The page: 0 to the far edge plus the 5 mm margin, 45 x 35. The view
  // grows left to x = -10 less half the 0.25 mm pen.
  const std::string svg = (dir_ / "negative.svg").string();
  const RunResult shown = Run("plot '" + file + "' --view top --origin keep -o '" + svg + "'");
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  EXPECT_NE(shown.err.find("fdsurf: note: the drawing runs past its 45 x 35 mm page; the SVG "
                           "shows x -10.125..45.000, y 0.000..35.000 mm\n"),
            std::string::npos)
      << shown.err;
  const std::string written = Slurp(svg);
  EXPECT_NE(written.find(R"(width="55.125mm" height="35.000mm" viewBox="-10.125 0 55.125 35.000")"),
            std::string::npos)
      << written;
  EXPECT_NE(written.find("M-10.000 25.000"), std::string::npos) << written;  // 35 - 10
  ExpectRefused("stream '" + file + "' --view top --origin keep",
                "--origin keep: the drawing runs over x -10..40, y 10..30 mm, outside the "
                "machine's travel x 0..45, y 0..35");
}

// An SVG whose drawing runs past its page on every side, as Inkscape's own
// examples do (markers.svg: x -14.5..102.5 on a 100 mm page): the SVG and
// the PNG show all of it at the file's coordinates.
TEST_F(Cli, AnSvgPastItsPageIsShownWhole) {
  // y_out = 100 - y_svg: the lines run x -10..110 at y 50, and y 108..-5
  // at x 50; the view is that plus half the pen, 0.125 mm.
  const std::string file = Write("cross.svg", R"(<svg xmlns="http://www.w3.org/2000/svg"
    width="100mm" height="100mm" viewBox="0 0 100 100">
    <path d="M -10 50 L 110 50 M 50 -8 L 50 105" stroke="black"/></svg>)");
  const std::string svg = (dir_ / "cross-out.svg").string();
  const std::string png = (dir_ / "cross.png").string();
  // 481 px over the 120.25 mm view: 4 px per mm, 113.25 mm = 453 px high.
  const RunResult r = Run("plot '" + file + "' -o '" + svg + "' --png '" + png + "' --size 481");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("fdsurf: note: the drawing runs past its 100 x 100 mm page; the SVG and "
                       "the PNG show x -10.125..110.125, y -5.125..108.125 mm\n"),
            std::string::npos)
      << r.err;
  // The viewBox's top is y' = 100 - 108.125: the points keep their places.
  const std::string written = Slurp(svg);
  EXPECT_NE(written.find(R"(width="120.250mm" height="113.250mm" viewBox="-10.125 -8.125 )"
                         R"(120.250 113.250")"),
            std::string::npos)
      << written;
  // The file's own ends (planning may draw a line either way).
  for (const char* end : {"-10.000 50.000", "110.000 50.000", "50.000 -8.000", "50.000 105.000"}) {
    EXPECT_NE(written.find(end), std::string::npos) << end << "\n" << written;
  }
  // The PNG's size from its IHDR chunk (big-endian width and height).
  const std::string picture = Slurp(png);
  ASSERT_GT(picture.size(), 24u);
  const auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) v = v << 8 | static_cast<unsigned char>(picture[at + k]);
    return v;
  };
  EXPECT_EQ(picture.substr(12, 4), "IHDR");
  EXPECT_EQ(be32(16), 481u);
  EXPECT_EQ(be32(20), 453u);
  // --quiet leaves the note out too.
  const RunResult quiet = Run("plot '" + file + "' -q -o '" + svg + "'");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
}

// Headers and summaries count what the drawing holds: curves are not "0
// patches".
TEST_F(Cli, CountsSayCurvesForADrawingOfCurves) {
  const std::string file = Write("curve.json", kCurveJson);
  const RunResult gcode = Run("plot '" + file + "' --format gcode -q");
  ASSERT_EQ(gcode.exit_code, 0) << gcode.err;
  EXPECT_NE(gcode.out.find("; source: " + file + " (1 curve)\n"), std::string::npos) << gcode.out;
  const RunResult teapot = Run("plot '" + kTeapot + "' --lines 2 --format gcode -q");
  ASSERT_EQ(teapot.exit_code, 0) << teapot.err;
  EXPECT_NE(teapot.out.find("; source: " + kTeapot + " (32 patches)\n"), std::string::npos);
  // check: the overall line is the worst over the curves, named by its curve.
  const RunResult check = Run("check '" + file + "' --grid 16");
  ASSERT_EQ(check.exit_code, 0) << check.out << check.err;
  const std::size_t at = check.out.find("overall: max error ");
  ASSERT_NE(at, std::string::npos) << check.out;
  const std::string overall = check.out.substr(at, check.out.find('\n', at) - at);
  EXPECT_NE(overall.find(" in curve 0, 1 curve: within the 0.51-quantum bound"), std::string::npos)
      << overall;
  // The same worst error as the curves' own line prints.
  const std::size_t curves = check.out.find("curves: max error ");
  ASSERT_NE(curves, std::string::npos) << check.out;
  EXPECT_EQ(check.out.substr(curves + 18, 8), overall.substr(19, 8)) << check.out;
  EXPECT_GT(std::stod(overall.substr(19)), 0.0);
}

// One rule for both commands: the teapot (no page of its own) is centred on
// 200 x 150 mm by plot and by stream alike, so plot's page and drawing are
// the ones the simulated plotter draws.
TEST_F(Cli, PlotAndStreamPlaceTheSameFileOnTheSamePage) {
  const std::string plotted = (dir_ / "plot.svg").string();
  const std::string drawn = (dir_ / "drawn.svg").string();
  const RunResult plot = Run("plot '" + kTeapot + "' --lines 2 -q -o '" + plotted + "'");
  ASSERT_EQ(plot.exit_code, 0) << plot.err;
  const RunResult stream =
      Run("stream '" + kTeapot + "' --lines 2 -q --speed 400 --accel 10000 --pen-delay 5 --svg '" +
          drawn + "'");
  ASSERT_EQ(stream.exit_code, 0) << stream.err;
  const std::string a = Slurp(plotted);
  const std::string b = Slurp(drawn);
  EXPECT_EQ(SvgPage(a), (std::array<double, 2>{200, 150}));
  EXPECT_EQ(SvgPage(b), SvgPage(a));
  // The same map: the extent of every coordinate in the paths agrees within
  // the two tolerances (0.05 mm each) and a step.
  const auto extent = [](const std::string& svg) {
    std::array<double, 4> box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t at = svg.find(" d=\""); at != std::string::npos;
         at = svg.find(" d=\"", at + 1)) {
      std::istringstream path(svg.substr(at + 4, svg.find('"', at + 4) - at - 4));
      std::string token;
      while (path >> token) {
        const double x = std::stod(token.substr(token[0] == 'M' || token[0] == 'L' ? 1 : 0));
        path >> token;
        const double y = std::stod(token);
        box = {std::min(box[0], x), std::min(box[1], y), std::max(box[2], x), std::max(box[3], y)};
      }
    }
    return box;
  };
  const auto pa = extent(a);
  const auto pb = extent(b);
  EXPECT_GT(pa[2] - pa[0], 100);  // fitted, not the teapot's few file units
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(pa[k], pb[k], 0.1 + 0.0125) << k;
}

TEST_F(Cli, DashReadsStandardInputForEveryCommand) {
  const std::string json = Write("curve.json", kCurveJson);
  // sample and check print the same as for the file (names aside).
  for (const std::string command : {"sample", "check"}) {
    const RunResult by_name = Run(command + " '" + kTeapot + "' --grid 2");
    const RunResult piped = RunWithInput(command + " - --grid 2", kTeapot);
    ASSERT_EQ(piped.exit_code, 0) << command << piped.err;
    EXPECT_EQ(piped.out, by_name.out) << command;
  }
  // plot: the same strokes, JSON carries no file name.
  const RunResult by_name = Run("plot '" + json + "' --format json -q");
  const RunResult piped = RunWithInput("plot - --format json -q", json);
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  EXPECT_EQ(piped.out, by_name.out);
  const std::string png = (dir_ / "in.png").string();
  const RunResult render = RunWithInput("render - -q -o '" + png + "' --size 100", kTeapot);
  ASSERT_EQ(render.exit_code, 0) << render.err;
  EXPECT_EQ(Slurp(png).substr(1, 3), "PNG");
  const RunResult stream =
      RunWithInput("stream - --view top --speed 400 --accel 10000 --pen-delay 5", json);
  ASSERT_EQ(stream.exit_code, 0) << stream.err;
  EXPECT_NE(stream.err.find("<stdin>: 1 curve streamed"), std::string::npos) << stream.err;
  // The format from the content, or --input-format; errors name <stdin>.
  const std::string empty = Write("empty", "  \n");
  const RunResult nothing = RunWithInput("plot -", empty);
  EXPECT_EQ(nothing.exit_code, 2);
  EXPECT_NE(nothing.err.find("fdsurf: error: <stdin>: the input is empty"), std::string::npos)
      << nothing.err;
  const RunResult told = RunWithInput("check - --grid 2 --input-format bpt", json);
  EXPECT_EQ(told.exit_code, 2);
  EXPECT_NE(told.err.find("<stdin>:1: the number of patches"), std::string::npos) << told.err;
  const std::string word = Write("word", "hello\n");
  const RunResult unknown = RunWithInput("plot -", word);
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("<stdin>: cannot tell the format from the content; say it with "
                             "--input-format"),
            std::string::npos)
      << unknown.err;
  EXPECT_EQ(unknown.out, "");
  // A file without a suffix is read by its content too.
  const std::string bare = Write("bare", kCurveJson);
  EXPECT_EQ(Run("plot '" + bare + "' --format json -q").out, by_name.out);
}

// Outputs whose suffix says another format, or none fdsurf writes, are
// refused before anything is drawn, and nothing is left behind.
TEST_F(Cli, OutputSuffixMustSayTheFormat) {
  const auto refused = [&](const std::string& args, const std::string& file,
                           const std::string& part) {
    ExpectRefused(args, part);
    EXPECT_FALSE(fs::exists(dir_ / file)) << args;
  };
  const std::string d = dir_.string() + "/";
  refused("plot '" + kTeapot + "' -o '" + d + "x.pdf'", "x.pdf",
          "x.pdf' has no suffix of a format fdsurf writes (.svg, .gcode, .nc, .ngc, .hpgl, .plt, "
          ".json)");
  refused("plot '" + kTeapot + "' -o '" + d + "x.svg' --format gcode", "x.svg",
          "x.svg' says svg but --format is gcode");
  refused("render '" + kTeapot + "' -o '" + d + "out.svg'", "out.svg",
          "-o: '" + d + "out.svg' does not end in .png; the picture is PNG");
  refused("plot '" + kTeapot + "' -o '" + d + "x.svg' --png '" + d + "x.jpg'", "x.jpg",
          "--png: '" + d + "x.jpg' does not end in .png");
  EXPECT_FALSE(fs::exists(dir_ / "x.svg"));
  // Upper-case suffixes are the same formats; stdout is SVG unless told.
  EXPECT_EQ(Run("plot '" + kTeapot + "' --lines 2 -q -o '" + d + "T.GCODE'").exit_code, 0);
  EXPECT_EQ(Slurp(dir_ / "T.GCODE").substr(0, 1), ";");
  EXPECT_NE(Run("plot '" + kTeapot + "' --lines 2 -q").out.find("<svg"), std::string::npos);
}

// CLI11's own errors read like the tool's others and exit 2; --help and
// --version still print and exit 0.
TEST_F(Cli, ArgumentErrorsHaveTheToolsPrefixAndExitTwo) {
  const auto argument_error = [&](const std::string& args, const std::string& part) {
    const RunResult r = Run(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_EQ(r.out, "") << args;
    EXPECT_EQ(r.err.rfind("fdsurf: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(part), std::string::npos) << r.err;
  };
  argument_error("plot '" + kTeapot + "' --bogus", "--bogus (see fdsurf plot --help)");
  argument_error("plot", "FILE is required");
  argument_error("sample '" + kTeapot + "' --grid", "--grid");
  argument_error("plot '" + kTeapot + "' --units cm", "--units: cm not in {mm,in}");
  argument_error("stream '" + kTeapot + "' --faults 0.9", "--faults");
  argument_error("plot '" + kTeapot + "' --input-format pdf", "--input-format");
  const RunResult help = Run("plot --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--origin"), std::string::npos);
  EXPECT_EQ(help.err, "");
  EXPECT_EQ(Run("--help").exit_code, 0);
  const RunResult version = Run("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("fdsurf ", 0), 0u) << version.out;
}

}  // namespace
}  // namespace fdsurf::host
