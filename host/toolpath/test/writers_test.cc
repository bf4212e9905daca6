// SPDX-License-Identifier: MIT
// Byte-exact tests of the text writers (SVG, G-code, HPGL, JSON strokes) on
// toolpaths built by hand. Every expected file is written out from the
// format's rules (docs/formats.md, "Output of fdsurf plot"): coordinates are
// the exact decimals k·Q, SVG flips y to page height − y, G-code and JSON
// keep y up, HPGL prints the whole plotter units themselves.
#include <cairo.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
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
  // Page 10 mm = 10000 quanta → "10.000"; y' = 5000 − y. The point at
  // x = −0.250 is left of the page: the view starts half the 0.25 mm pen
  // (125 quanta) further left, at −0.375, and is 10.375 wide.
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"10.375mm\" "
      "height=\"5.000mm\" viewBox=\"-0.375 0 10.375 5.000\">\n"
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
  // The point at y = −0.0001 is below the page: the view reaches half the
  // pen (50 quanta) lower, to y = −0.0051, so it is 1.0051 high; its top is
  // still the page's, so the viewBox starts at y' = 0.
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"2.5000in\" "
      "height=\"1.0051in\" viewBox=\"0 0 2.5000 1.0051\">\n"
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

// A 4 × 3 mm page at 0.01 mm with a cross that runs past all four edges:
// x −0.50..4.50 at y 1.00, and y −0.20..3.20 at x 2.00.
Toolpath CrossPastThePage() {
  Toolpath path;
  path.units = "mm";
  path.quantum = Quantum::Parse("0.01");
  path.width = 4;
  path.height = 3;
  path.strokes.push_back(MakeStroke({{-50, 100, 0}, {450, 100, 0}}));
  path.strokes.push_back(MakeStroke({{200, -20, 0}, {200, 320, 0}}));
  return path;
}

TEST(ViewOfPage, IsThePageUnlessAPointLiesOutside) {
  Toolpath path = CrossPastThePage();
  // Half the 0.25 mm pen is 12.5 quanta of 0.01 mm, rounded up to 13.
  PageView view = ViewOfPage(path);
  EXPECT_EQ(view.lo, (std::array<std::int64_t, 2>{-63, -33}));
  EXPECT_EQ(view.hi, (std::array<std::int64_t, 2>{463, 333}));
  EXPECT_TRUE(view.past_page);
  // Only past the top: only the top grows.
  path.strokes = {MakeStroke({{0, 0, 0}, {400, 301, 0}})};
  view = ViewOfPage(path);
  EXPECT_EQ(view.lo, (std::array<std::int64_t, 2>{0, 0}));
  EXPECT_EQ(view.hi, (std::array<std::int64_t, 2>{400, 314}));
  EXPECT_TRUE(view.past_page);
  // On the edges is on the page.
  path.strokes = {MakeStroke({{0, 0, 0}, {400, 300, 0}})};
  view = ViewOfPage(path);
  EXPECT_EQ(view.lo, (std::array<std::int64_t, 2>{0, 0}));
  EXPECT_EQ(view.hi, (std::array<std::int64_t, 2>{400, 300}));
  EXPECT_FALSE(view.past_page);
}

TEST(WriteSvg, AViewPastEveryEdgeKeepsThePagesCoordinates) {
  // View x −0.63..4.63, y −0.33..3.33 (ViewOfPage above): 5.26 × 3.66 mm.
  // y' = 3.00 − y as on the page alone, so the viewBox's top is
  // 3.00 − 3.33 = −0.33 and the points are the ones the page alone has.
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"5.26mm\" "
      "height=\"3.66mm\" viewBox=\"-0.63 -0.33 5.26 3.66\">\n"
      "<title>cross</title>\n"
      "<g fill=\"none\" stroke=\"black\" stroke-width=\"0.25\" stroke-linecap=\"round\" "
      "stroke-linejoin=\"round\">\n"
      "<path d=\"M-0.50 2.00 L4.50 2.00\"/>\n"
      "<path d=\"M2.00 3.20 L2.00 -0.20\"/>\n"
      "</g>\n"
      "</svg>\n";
  EXPECT_EQ(WriteSvg(CrossPastThePage(), "cross"), expected);
}

// The inked pixels' box of a PNG read back by cairo (libpng), as
// {left, top, right, bottom}; anything not white is ink.
std::array<int, 4> InkBox(cairo_surface_t* image) {
  const int width = cairo_image_surface_get_width(image);
  const int height = cairo_image_surface_get_height(image);
  const int stride = cairo_image_surface_get_stride(image);
  const unsigned char* data = cairo_image_surface_get_data(image);
  std::array<int, 4> box{width, height, -1, -1};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint32_t pixel = 0;
      std::memcpy(&pixel, data + static_cast<std::ptrdiff_t>(y) * stride + 4 * x, 4);
      if ((pixel & 0xFFFFFFu) == 0xFFFFFFu) continue;
      box = {std::min(box[0], x), std::min(box[1], y), std::max(box[2], x), std::max(box[3], y)};
    }
  }
  return box;
}

TEST(RenderPng, ShowsTheSameViewAsTheSvg) {
  // 526 px over the 526-quantum view: one pixel per quantum, 366 px high.
  // Pixel x = x − (−63), pixel y = 366 − (y − (−33)): the horizontal line
  // runs over x 13..513 at row 233, the vertical one over rows 13..353 at
  // x 263; the 1 px round pen adds up to a pixel on each side.
  const std::string file = ::testing::TempDir() + "/writers_test_cross.png";
  RenderPng(CrossPastThePage(), 526, file);
  cairo_surface_t* image = cairo_image_surface_create_from_png(file.c_str());
  ASSERT_EQ(cairo_surface_status(image), CAIRO_STATUS_SUCCESS);
  EXPECT_EQ(cairo_image_surface_get_width(image), 526);
  EXPECT_EQ(cairo_image_surface_get_height(image), 366);
  const std::array<int, 4> ink = InkBox(image);
  cairo_surface_destroy(image);
  std::remove(file.c_str());
  const std::array<int, 4> drawn{13, 13, 513, 353};
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(ink[k], drawn[k], 1) << "side " << k;
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

// ---- G-code flavours

// One 2-D stroke on a 0.01 mm grid with its exact cubic: Bézier (1, 1),
// (1.004, 2.996), (3, 3), (3, 1) mm. Rounded to 0.01 mm the control points
// are (1, 1), (1, 3), (3, 3), (3, 1), so G5 prints I0 J2 (first control point
// − start) and P0 Q2 (second control point − end). Two layers, one stroke each.
Toolpath CubicPath() {
  Toolpath path;
  path.dims = 2;
  path.units = "mm";
  path.quantum = Quantum::Parse("0.01");
  path.width = 5;
  path.height = 5;
  path.tolerance = 0.05;
  path.layers = {"black", "red"};
  Stroke arch = MakeStroke({{100, 100, 0}, {200, 280, 0}, {300, 100, 0}});
  arch.cubics.push_back({{{1, 1, 0}, {1.004, 2.996, 0}, {3, 3, 0}, {3, 1, 0}}});
  path.strokes.push_back(arch);
  Stroke line = MakeStroke({{300, 100, 0}, {400, 100, 0}});
  line.layer = 1;
  path.strokes.push_back(line);  // no cubics: G1 whatever the flavour
  return path;
}

TEST(WriteGcode, MarlinWritesG5MillisecondDwellsServoPenAndPausesBetweenLayers) {
  const GcodeOptions options{.flavor = "marlin",
                             .pen = "servo",
                             .servo_up = 70,
                             .servo_down = 20,
                             .servo_index = 1,
                             .feed = 600,
                             .travel_rate = 1200,
                             .dwell = 0.25};
  // Time by hand: pen-down 2·√(1 + 1.8²) + 1 = 5.118 mm at 600 mm/min
  // (0.512 s); travel √2 + 0 + √17 = 5.537 mm at 1200 mm/min (0.277 s);
  // 5 dwells of 0.25 s (1.25 s): 2.04 s → 0:00:02.
  const std::string expected =
      "; marlin\n"
      "; flavor marlin, cubics as G5, dwell G4 P in milliseconds\n"
      "; estimated time 0:00:02 = 2.04 s of machine time, docs/toolpaths.md\n"
      "; estimate: pen down 5.1 mm, travel 5.5 mm, 2 pen lifts\n"
      "; estimate: extent x 1..4, y 1..2.8 mm\n"
      "; estimate assumes: feed 600, plunge 300, G0 1200 mm/min\n"
      "; estimate assumes: accel none, junction deviation 0.01 mm, dwell 0.25 s\n"
      "G21 ; units: mm\n"
      "G90 ; absolute positions\n"
      "M280 P1 S70\n"
      "G4 P250\n"
      "; layer 'black'\n"
      "G0 X1.00 Y1.00\n"
      "M280 P1 S20\n"
      "G4 P250\n"
      "G5 I0.00 J2.00 P0.00 Q2.00 X3.00 Y1.00 F600\n"
      "M280 P1 S70\n"
      "G4 P250\n"
      "; pen change: layer 'red'\n"
      "M0\n"
      "G0 X3.00 Y1.00\n"
      "M280 P1 S20\n"
      "G4 P250\n"
      "G1 X4.00 Y1.00 F600\n"
      "M280 P1 S70\n"
      "G4 P250\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(CubicPath(), options, {"marlin"}), expected);
}

TEST(WriteGcode, LinuxCncSelectsG17AndUsesParenthesisComments) {
  // Time: 0.512 s drawing, 5.537 mm at 3000 mm/min (0.111 s), 5 dwells of
  // 0.5 s: 3.12 s → 0:00:03.
  const GcodeOptions options{
      .flavor = "linuxcnc", .pen = "m3", .feed = 600, .dwell = 0.5, .power = 100};
  const std::string expected =
      "(source: a [b])\n"
      "(flavor linuxcnc, cubics as G5, dwell G4 P in seconds)\n"
      "(estimated time 0:00:03 = 3.12 s of machine time, docs/toolpaths.md)\n"
      "(estimate: pen down 5.1 mm, travel 5.5 mm, 2 pen lifts)\n"
      "(estimate: extent x 1..4, y 1..2.8 mm)\n"
      "(estimate assumes: feed 600, plunge 300, G0 3000 mm/min)\n"
      "(estimate assumes: accel none, junction deviation 0.01 mm, dwell 0.5 s)\n"
      "G21 (units: mm)\n"
      "G90 (absolute positions)\n"
      "G17 (XY plane, for G5)\n"
      "M5\n"
      "G4 P0.5\n"
      "(layer 'black')\n"
      "G0 X1.00 Y1.00\n"
      "M3 S100\n"
      "G4 P0.5\n"
      "G5 I0.00 J2.00 P0.00 Q2.00 X3.00 Y1.00 F600\n"
      "M5\n"
      "G4 P0.5\n"
      "(pen change: layer 'red')\n"
      "M0\n"
      "G0 X3.00 Y1.00\n"
      "M3 S100\n"
      "G4 P0.5\n"
      "G1 X4.00 Y1.00 F600\n"
      "M5\n"
      "G4 P0.5\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(CubicPath(), options, {"source: a (b)"}), expected);
}

TEST(WriteGcode, GrblDrawsTheCubicAsItsSegmentsWithSecondDwells) {
  // Time: 0.512 s drawing, 0.111 s travel, 2 plunges of 5 mm at 300 mm/min
  // (2 s), 2 lifts of 5 mm at 3000 mm/min (0.2 s): 2.82 s → 0:00:03.
  const GcodeOptions options{.flavor = "grbl", .feed = 600};
  const std::string expected =
      "(flavor grbl, cubics as G1 segments, dwell G4 P in seconds)\n"
      "(estimated time 0:00:03 = 2.82 s of machine time, docs/toolpaths.md)\n"
      "(estimate: pen down 5.1 mm, travel 5.5 mm, 2 pen lifts)\n"
      "(estimate: extent x 1..4, y 1..2.8 mm)\n"
      "(estimate assumes: feed 600, plunge 300, G0 3000 mm/min)\n"
      "(estimate assumes: accel none, junction deviation 0.01 mm, dwell 0.2 s)\n"
      "G21 (units: mm)\n"
      "G90 (absolute positions)\n"
      "G0 Z5\n"
      "(layer 'black')\n"
      "G0 X1.00 Y1.00\n"
      "G1 Z0 F300\n"
      "G1 X2.00 Y2.80 F600\n"
      "G1 X3.00 Y1.00\n"
      "G0 Z5\n"
      "(pen change: layer 'red')\n"
      "M0\n"
      "G0 X3.00 Y1.00\n"
      "G1 Z0 F300\n"
      "G1 X4.00 Y1.00 F600\n"
      "G0 Z5\n"
      "G0 X0 Y0\n"
      "M2\n";
  EXPECT_EQ(WriteGcode(CubicPath(), options, {}), expected);
  // Marlin without G5 writes the same segments (with ; comments).
  const std::string marlin =
      WriteGcode(CubicPath(), GcodeOptions{.flavor = "marlin", .feed = 600, .g5 = false}, {});
  EXPECT_NE(marlin.find("G1 X2.00 Y2.80 F600\nG1 X3.00 Y1.00\n"), std::string::npos);
  EXPECT_EQ(marlin.find("G5"), std::string::npos);
}

TEST(WriteGcode, RefusesServoWithoutM280AndUnknownFlavours) {
  EXPECT_THROW(WriteGcode(CubicPath(), GcodeOptions{.flavor = "grbl", .pen = "servo"}, {}),
               OptionError);
  EXPECT_THROW(WriteGcode(CubicPath(), GcodeOptions{.flavor = "generic", .pen = "servo"}, {}),
               OptionError);
  EXPECT_THROW(WriteGcode(CubicPath(), GcodeOptions{.flavor = "reprap"}, {}), OptionError);
}

TEST(WriteGcode, RefusesG5WhoseRoundedControlPointsBreakTheTolerance) {
  // The first control point (1.004, 2.996) is printed as (1.00, 3.00): 0.0057 mm
  // away. Within a 0.0057 mm tolerance the convex-hull bound is not met.
  Toolpath path = CubicPath();
  path.tolerance = 0.0056;
  EXPECT_THROW(WriteGcode(path, GcodeOptions{.flavor = "marlin"}, {}), OptionError);
  path.tolerance = 0.0057;
  EXPECT_NO_THROW(WriteGcode(path, GcodeOptions{.flavor = "marlin"}, {}));
}

TEST(WriteGcode, GenericIgnoresCubicsAndNamesLayersWithSemicolons) {
  const std::string out = WriteGcode(CubicPath(), GcodeOptions{}, {});
  EXPECT_EQ(out.find("G5"), std::string::npos);
  EXPECT_EQ(out.find("estimated"), std::string::npos);  // generic: no new header lines
  // Asked for, generic states the estimate too (fdsurf plot asks).
  const std::string with = WriteGcode(CubicPath(), GcodeOptions{.estimate_in_header = true}, {});
  EXPECT_EQ(with.rfind("; estimated time 0:00:03 = ", 0), 0u) << with;
  EXPECT_NE(out.find("G0 Z5\n; pen change: layer 'red'\nM0\nG0 X3.00 Y1.00\n"), std::string::npos);
}

TEST(EstimateGcodeSeconds, AddsDrawingTravelPlungesAndLifts) {
  // MillimetrePath, Z pen: strokes 2·√(1.5² + 2²) = 5.0 mm and
  // √(10.25² + 0.001²) mm at F1500; travel 0 +
  // |(3,0)→(−0.25,4.999)| + |(10,5)→(0,0)| at 3000; plunges 2×5 mm at F300,
  // lifts 2×5 mm at 3000.
  const double down = 5.0 + std::hypot(10.25, 0.001);
  const double travel = std::hypot(3.25, 4.999) + std::hypot(10.0, 5.0) + 10.0;
  const double expected = 60 * (down / 1500 + travel / 3000 + 10.0 / 300);
  EXPECT_NEAR(EstimateGcodeSeconds(MillimetrePath(), GcodeOptions{}), expected, 1e-9);
  // M3: no Z moves, five dwells (one initial lift, two per stroke).
  const double m3 = 60 * (down / 1500 + (travel - 10.0) / 3000) + 5 * 0.2;
  EXPECT_NEAR(EstimateGcodeSeconds(MillimetrePath(), GcodeOptions{.pen = "m3"}), m3, 1e-9);
}

// ---- SVG layers

TEST(WriteSvg, LayersBecomeInkscapeLayerGroups) {
  const std::string expected =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" "
      "xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\" version=\"1.1\" "
      "width=\"5.00mm\" height=\"5.00mm\" viewBox=\"0 0 5.00 5.00\">\n"
      "<title>layers</title>\n"
      "<g fill=\"none\" stroke=\"black\" stroke-width=\"0.25\" stroke-linecap=\"round\" "
      "stroke-linejoin=\"round\">\n"
      "<g inkscape:groupmode=\"layer\" inkscape:label=\"black\">\n"
      "<path d=\"M1.00 4.00 L2.00 2.20 L3.00 4.00\"/>\n"
      "</g>\n"
      "<g inkscape:groupmode=\"layer\" inkscape:label=\"red &amp; blue\">\n"
      "<path d=\"M3.00 4.00 L4.00 4.00\"/>\n"
      "</g>\n"
      "</g>\n"
      "</svg>\n";
  Toolpath path = CubicPath();
  path.layers[1] = "red & blue";
  EXPECT_EQ(WriteSvg(path, "layers"), expected);
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
