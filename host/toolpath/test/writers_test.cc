// SPDX-License-Identifier: MIT
// Byte-exact tests of the text writers (SVG, G-code, HPGL, JSON strokes) on
// toolpaths built by hand. Every expected file is written out from the
// format's rules (docs/formats.md, "Output of fdsurf plot"): coordinates are
// the exact decimals k·Q, SVG flips y to page height − y, G-code and JSON
// keep y up, HPGL prints the whole plotter units themselves.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fdsurf/host/writers.h"

namespace fdsurf::host {
namespace {

Stroke MakeStroke(std::vector<std::array<std::int64_t, 3>> points) {
  Stroke s;
  s.points = std::move(points);
  return s;
}

// A 10 × 5 mm page at 0.001 mm: two strokes, one with a negative x and a
// point one quantum below the top edge.
Toolpath MillimetrePath() {
  Toolpath path;
  path.dims = 2;
  path.units = "mm";
  path.quantum = Quantum::Parse("0.001");
  path.width = 10;
  path.height = 5;
  path.strokes.push_back(MakeStroke({{0, 0, 0}, {1500, 2000, 0}, {3000, 0, 0}}));
  path.strokes.push_back(MakeStroke({{-250, 4999, 0}, {10000, 5000, 0}}));
  return path;
}

// A 2.5 × 1 in page at 0.0001 in.
Toolpath InchPath() {
  Toolpath path;
  path.dims = 2;
  path.units = "in";
  path.quantum = Quantum::Parse("0.0001");
  path.width = 2.5;
  path.height = 1;
  path.strokes.push_back(MakeStroke({{0, 0, 0}, {12345, 6789, 0}, {20000, 10, 0}}));
  path.strokes.push_back(MakeStroke({{500, -1, 0}, {7, 10000, 0}}));
  return path;
}

// 3-D at 0.01 mm on a 20 × 10 mm page; z is the depth below the top (≤ 0).
Toolpath ThreeDPath() {
  Toolpath path;
  path.dims = 3;
  path.units = "mm";
  path.quantum = Quantum::Parse("0.01");
  path.width = 20;
  path.height = 10;
  path.depth = 1.5;
  path.strokes.push_back(MakeStroke({{100, 200, -50}, {150, 250, -150}, {200, 200, 0}}));
  path.strokes.push_back(MakeStroke({{1999, 0, -1}, {0, 999, -100}}));
  return path;
}

// ---- SVG

TEST(WriteSvg, MillimetresFlipYIntoTheViewBox) {
  // Page 10 mm = 10000 quanta → "10.000"; y' = 5000 − y.
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"10.000mm\" "
      "height=\"5.000mm\" viewBox=\"0 0 10.000 5.000\">\n"
      "<title>two strokes</title>\n"
      "<g fill=\"none\" stroke=\"black\" stroke-width=\"0.25\" stroke-linecap=\"round\" "
      "stroke-linejoin=\"round\">\n"
      "<path d=\"M0.000 5.000 L1.500 3.000 L3.000 5.000\"/>\n"
      "<path d=\"M-0.250 0.001 L10.000 0.000\"/>\n"
      "</g>\n"
      "</svg>\n";
  EXPECT_EQ(WriteSvg(MillimetrePath(), "two strokes"), expected);
}

TEST(WriteSvg, InchesUseATenThousandthPenAndFourDecimals) {
  // Page 2.5 in = 25000 quanta of 0.0001 in; y' = 10000 − y; pen 0.01 in.
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"2.5000in\" "
      "height=\"1.0000in\" viewBox=\"0 0 2.5000 1.0000\">\n"
      "<title>in</title>\n"
      "<g fill=\"none\" stroke=\"black\" stroke-width=\"0.01\" stroke-linecap=\"round\" "
      "stroke-linejoin=\"round\">\n"
      "<path d=\"M0.0000 1.0000 L1.2345 0.3211 L2.0000 0.9990\"/>\n"
      "<path d=\"M0.0500 1.0001 L0.0007 0.0000\"/>\n"
      "</g>\n"
      "</svg>\n";
  EXPECT_EQ(WriteSvg(InchPath(), "in"), expected);
}

TEST(WriteSvg, EscapesTheTitleAndRoundsThePageUpToAWholeQuantum) {
  Toolpath path;
  path.units = "mm";
  path.quantum = Quantum::Parse("0.001");
  path.width = 10.0004;  // 10000.4 quanta → 10001
  path.height = 2;
  path.strokes.push_back(MakeStroke({{1, 2, 0}}));
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"10.001mm\" "
      "height=\"2.000mm\" viewBox=\"0 0 10.001 2.000\">\n"
      "<title>a &amp; &lt;b&gt; &quot;c&quot;</title>\n"
      "<g fill=\"none\" stroke=\"black\" stroke-width=\"0.25\" stroke-linecap=\"round\" "
      "stroke-linejoin=\"round\">\n"
      "<path d=\"M0.001 1.998\"/>\n"
      "</g>\n"
      "</svg>\n";
  EXPECT_EQ(WriteSvg(path, "a & <b> \"c\""), expected);
}

// ---- G-code

TEST(WriteGcode, MillimetresWithZPen) {
  // Defaults: pen up Z5, down Z0, plunge F300, draw F1500 on the first G1.
  const std::string expected =
      "; source: two.bpt\n"
      "; page 10x5 mm\n"
      "G21 ; units: mm\n"
      "G90 ; absolute positions\n"
      "G0 Z5\n"
      "G0 X0.000 Y0.000\n"
      "G1 Z0 F300\n"
      "G1 X1.500 Y2.000 F1500\n"
      "G1 X3.000 Y0.000\n"
      "G0 Z5\n"
      "G0 X-0.250 Y4.999\n"
      "G1 Z0 F300\n"
      "G1 X10.000 Y5.000 F1500\n"
      "G0 Z5\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(MillimetrePath(), GcodeOptions{}, {"source: two.bpt", "page 10x5 mm"}),
            expected);
}

TEST(WriteGcode, ZPenHeightsAndFeedsFromTheOptions) {
  const GcodeOptions options{
      .pen_up_z = 2.5, .pen_down_z = -0.25, .feed = 800, .plunge_feed = 120.5};
  const std::string expected =
      "G21 ; units: mm\n"
      "G90 ; absolute positions\n"
      "G0 Z2.5\n"
      "G0 X0.000 Y0.000\n"
      "G1 Z-0.25 F120.5\n"
      "G1 X1.500 Y2.000 F800\n"
      "G1 X3.000 Y0.000\n"
      "G0 Z2.5\n"
      "G0 X-0.250 Y4.999\n"
      "G1 Z-0.25 F120.5\n"
      "G1 X10.000 Y5.000 F800\n"
      "G0 Z2.5\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(MillimetrePath(), options, {}), expected);
}

TEST(WriteGcode, InchesWithM3PenAndDwell) {
  const GcodeOptions options{.pen = "m3", .feed = 60, .dwell = 0.5, .power = 255};
  const std::string expected =
      "; inch\n"
      "G20 ; units: in\n"
      "G90 ; absolute positions\n"
      "M5\n"
      "G4 P0.5\n"
      "G0 X0.0000 Y0.0000\n"
      "M3 S255\n"
      "G4 P0.5\n"
      "G1 X1.2345 Y0.6789 F60\n"
      "G1 X2.0000 Y0.0010\n"
      "M5\n"
      "G4 P0.5\n"
      "G0 X0.0500 Y-0.0001\n"
      "M3 S255\n"
      "G4 P0.5\n"
      "G1 X0.0007 Y1.0000 F60\n"
      "M5\n"
      "G4 P0.5\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(InchPath(), options, {"inch"}), expected);
}

TEST(WriteGcode, ThreeDPlungesToTheFirstDepthAndCarriesZ) {
  // Travel at pen_up_z; the plunge goes to the stroke's first Z at the
  // plunge feed; every further point has its Z.
  const std::string expected =
      "G21 ; units: mm\n"
      "G90 ; absolute positions\n"
      "G0 Z5\n"
      "G0 X1.00 Y2.00\n"
      "G1 Z-0.50 F300\n"
      "G1 X1.50 Y2.50 Z-1.50 F1500\n"
      "G1 X2.00 Y2.00 Z0.00\n"
      "G0 Z5\n"
      "G0 X19.99 Y0.00\n"
      "G1 Z-0.01 F300\n"
      "G1 X0.00 Y9.99 Z-1.00 F1500\n"
      "G0 Z5\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(ThreeDPath(), GcodeOptions{}, {}), expected);
  // In 3-D the pen is the Z axis whatever --pen says.
  EXPECT_EQ(WriteGcode(ThreeDPath(), GcodeOptions{.pen = "m3"}, {}), expected);
}

// ---- HPGL

TEST(WriteHpgl, PlotterUnitsPenUpThenPenDown) {
  Toolpath path;
  path.units = "mm";
  path.quantum = Quantum::Parse("0.025");
  path.width = 20;
  path.height = 10;
  // 400 units = 10 mm; a one-point stroke is a dot (PD with no points).
  path.strokes.push_back(MakeStroke({{0, 0, 0}, {400, 400, 0}, {800, 0, 0}}));
  path.strokes.push_back(MakeStroke({{40, 80, 0}}));
  path.strokes.push_back(MakeStroke({{799, 399, 0}, {1, 2, 0}}));
  const std::string expected =
      "IN;SP1;\n"
      "PU0,0;PD400,400,800,0;\n"
      "PU40,80;PD;\n"
      "PU799,399;PD1,2;\n"
      "PU;SP0;\n";
  EXPECT_EQ(WriteHpgl(path), expected);
}

TEST(WriteHpgl, RefusesAnythingButPlotterUnits) {
  Toolpath mm = MillimetrePath();  // 0.001 mm
  EXPECT_THROW(WriteHpgl(mm), OutputError);
  Toolpath inch = MillimetrePath();
  inch.units = "in";
  inch.quantum = Quantum::Parse("0.025");
  EXPECT_THROW(WriteHpgl(inch), OutputError);
}

// ---- JSON strokes

TEST(WriteStrokesJson, TwoDimensionsMillimetres) {
  // bbox [xmin, ymin, xmax, ymax] over every point; y as drawn (up).
  const std::string expected =
      "{\"units\":\"mm\",\"quantum\":0.001,\"dims\":2,\"width\":10.000,\"height\":5.000,"
      "\"bbox\":[-0.250,0.000,10.000,5.000],\"strokes\":[\n"
      "[[0.000,0.000],[1.500,2.000],[3.000,0.000]],\n"
      "[[-0.250,4.999],[10.000,5.000]]]}\n";
  EXPECT_EQ(WriteStrokesJson(MillimetrePath()), expected);
}

TEST(WriteStrokesJson, TwoDimensionsInches) {
  const std::string expected =
      "{\"units\":\"in\",\"quantum\":0.0001,\"dims\":2,\"width\":2.5000,\"height\":1.0000,"
      "\"bbox\":[0.0000,-0.0001,2.0000,1.0000],\"strokes\":[\n"
      "[[0.0000,0.0000],[1.2345,0.6789],[2.0000,0.0010]],\n"
      "[[0.0500,-0.0001],[0.0007,1.0000]]]}\n";
  EXPECT_EQ(WriteStrokesJson(InchPath()), expected);
}

TEST(WriteStrokesJson, ThreeDimensionsCarryZ) {
  // bbox [xmin, ymin, zmin, xmax, ymax, zmax].
  const std::string expected =
      "{\"units\":\"mm\",\"quantum\":0.01,\"dims\":3,\"width\":20.00,\"height\":10.00,"
      "\"bbox\":[0.00,0.00,-1.50,19.99,9.99,0.00],\"strokes\":[\n"
      "[[1.00,2.00,-0.50],[1.50,2.50,-1.50],[2.00,2.00,0.00]],\n"
      "[[19.99,0.00,-0.01],[0.00,9.99,-1.00]]]}\n";
  EXPECT_EQ(WriteStrokesJson(ThreeDPath()), expected);
}

}  // namespace
}  // namespace fdsurf::host
