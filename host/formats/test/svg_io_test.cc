// SPDX-License-Identifier: MIT
// The SVG reader: the path grammar, the shapes, transforms, <use>, the page,
// exactness against hand-computed points, the arc bound against an ellipse
// sampled here from its own parametric form, errors, notes and layers.
// Expected values are worked out by hand from the SVG 2 rules, not taken
// from the reader.
#include "fdsurf/host/svg_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numbers>

#include "fdsurf/host/patch_io.h"
#include "format_test_support.h"

namespace fdsurf::host {
namespace {

using format_test::BezierAt;
using format_test::ErrorOf;

constexpr double kPi = std::numbers::pi;

// A 100 × 100 mm page whose user unit is 1 mm: output (x, 100 − y).
std::string Page(const std::string& body, const std::string& extra = "") {
  return R"~(<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" )~"
         R"~(xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" )~"
         R"~(width="100mm" height="100mm" viewBox="0 0 100 100")~" +
         extra + ">\n" + body + "\n</svg>\n";
}

PatchSet Read(const std::string& body, const SvgOptions& options = {}) {
  return ReadSvg(Page(body), "t.svg", options);
}

// Output point of an SVG user point on the test page.
Point3 Out(double x, double y) { return {x, 100 - y, 0}; }

void ExpectNear(const Point3& a, const Point3& b, double tol = 1e-12) {
  EXPECT_NEAR(a[0], b[0], tol);
  EXPECT_NEAR(a[1], b[1], tol);
  EXPECT_NEAR(a[2], b[2], tol);
}

// A straight curve from a to b (output points), parametrised uniformly.
void ExpectLine(const Curve& c, const Point3& a, const Point3& b) {
  EXPECT_TRUE(c.straight);
  EXPECT_EQ(c.basis, Basis::kBezier);
  for (double u : {0.0, 0.25, 0.5, 1.0}) {
    ExpectNear(BezierAt(c, u), {a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]), 0});
  }
}

// ---- the path grammar -------------------------------------------------------

TEST(SvgPath, AbsoluteAndRelativeLines) {
  for (const char* d : {"M10 20 L30 40", "m10 20 l20 20", "M10,20,30,40", "m10 20 20 20"}) {
    const PatchSet set = Read(std::string(R"~(<path d=")~") + d + R"~("/>)~");
    ASSERT_EQ(set.curves.size(), 1u) << d;
    ExpectLine(set.curves[0], Out(10, 20), Out(30, 40));
  }
}

TEST(SvgPath, HorizontalVerticalAndImplicitRepeats) {
  const PatchSet set = Read(R"~(<path d="M10 10 H20 30 V40 h5 v-5 5"/>)~");
  ASSERT_EQ(set.curves.size(), 6u);
  ExpectLine(set.curves[0], Out(10, 10), Out(20, 10));
  ExpectLine(set.curves[1], Out(20, 10), Out(30, 10));
  ExpectLine(set.curves[2], Out(30, 10), Out(30, 40));
  ExpectLine(set.curves[3], Out(30, 40), Out(35, 40));
  ExpectLine(set.curves[4], Out(35, 40), Out(35, 35));
  ExpectLine(set.curves[5], Out(35, 35), Out(35, 40));
}

TEST(SvgPath, CubicsAreExactAndSReflects) {
  const PatchSet set = Read(R"~(<path d="M0 0 C10 0 20 10 20 20 s10 20 20 20 S 50 50 60 60"/>)~");
  ASSERT_EQ(set.curves.size(), 3u);
  const Curve& c = set.curves[0];
  EXPECT_FALSE(c.straight);
  // The cubic at u = 1/2 by hand: (0 + 3·10 + 3·20 + 20)/8, (0 + 0 + 3·10 + 20)/8.
  ExpectNear(BezierAt(c, 0.5), Out(110.0 / 8, 50.0 / 8));
  // s: first control = (20,20) reflected (20,10) = (20,30); others relative to (20,20).
  ExpectNear(set.curves[1].g[1], Out(20, 30));
  ExpectNear(set.curves[1].g[2], Out(30, 40));
  ExpectNear(set.curves[1].g[3], Out(40, 40));
  // S after s: (30,40) reflected about (40,40) = (50,40).
  ExpectNear(set.curves[2].g[1], Out(50, 40));
}

TEST(SvgPath, SAfterALineStartsAtTheCurrentPoint) {
  const PatchSet set = Read(R"~(<path d="M0 0 L10 0 S20 10 30 0"/>)~");
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectNear(set.curves[1].g[1], Out(10, 0));
}

TEST(SvgPath, QuadraticsAreDegreeElevatedExactly) {
  const PatchSet set = Read(R"~(<path d="M0 0 Q30 0 30 30 T60 60 t0 30"/>)~");
  ASSERT_EQ(set.curves.size(), 3u);
  // The quadratic at u by hand: (1−u)²·P0 + 2u(1−u)·Q + u²·P2.
  for (double u : {0.1, 0.5, 0.9}) {
    const double a = (1 - u) * (1 - u);
    const double b = 2 * u * (1 - u);
    const double e = u * u;
    ExpectNear(BezierAt(set.curves[0], u), Out(b * 30 + e * 30, e * 30));
    // T: control (30,30) reflected (30,0) = (30,60), from (30,30) to (60,60).
    ExpectNear(BezierAt(set.curves[1], u), Out(a * 30 + b * 30 + e * 60, a * 30 + b * 60 + e * 60));
    // t: control (60,60) reflected (30,60) = (90,60), to (60,90).
    ExpectNear(BezierAt(set.curves[2], u), Out(a * 60 + b * 90 + e * 60, a * 60 + b * 60 + e * 90));
  }
}

TEST(SvgPath, CompactNumbers) {
  const PatchSet set = Read(R"~(<path d="M-.5.5L1e1-2E0l+1.5e+1 .25"/>)~");
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectLine(set.curves[0], Out(-0.5, 0.5), Out(10, -2));
  ExpectLine(set.curves[1], Out(10, -2), Out(25, -1.75));
}

TEST(SvgPath, ArcFlagsWithoutSeparators) {
  // From (0,0) to (10,10), radius 10, small arc, sweep 1 (angles increase,
  // clockwise on the screen): the centre is (0,10).
  for (const char* d :
       {"M0 0a10 10 0 0110 10", "M0 0 A10,10,0,0,1,10,10", "M0,0a10 10 0 0 1 10 10"}) {
    const PatchSet set = Read(std::string(R"~(<path d=")~") + d + R"~("/>)~");
    ASSERT_FALSE(set.curves.empty()) << d;
    ExpectNear(set.curves.front().g[0], Out(0, 0));
    ExpectNear(set.curves.back().g[3], Out(10, 10));
    for (const Curve& c : set.curves) {
      for (double u = 0; u <= 1; u += 0.125) {
        const Point3 p = BezierAt(c, u);
        EXPECT_NEAR(std::hypot(p[0] - 0, p[1] - 90), 10, 1e-6) << d;
      }
    }
  }
}

TEST(SvgPath, CloseAndWhatFollowsIt) {
  const PatchSet set = Read(R"~(<path d="M0 0 L10 0 L10 10 Z L5 5 M20 20 L30 20 z"/>)~");
  ASSERT_EQ(set.curves.size(), 6u);
  ExpectLine(set.curves[2], Out(10, 10), Out(0, 0));
  ExpectLine(set.curves[3], Out(0, 0), Out(5, 5));
  ExpectLine(set.curves[5], Out(30, 20), Out(20, 20));
}

TEST(SvgPath, ZeroRadiusArcIsALineAndEqualEndsDrawNothing) {
  const PatchSet set = Read(R"~(<path d="M0 0 A0 5 0 0 1 10 0 A5 5 0 0 1 10 0"/>)~");
  ASSERT_EQ(set.curves.size(), 1u);
  ExpectLine(set.curves[0], Out(0, 0), Out(10, 0));
}

TEST(SvgPath, TooSmallRadiiAreScaledUp) {
  // Radius 1 cannot reach from (0,50) to (20,50): scaled to 10, a half circle
  // about (10,50).
  const PatchSet set = Read(R"~(<path d="M0 50 A1 1 0 0 1 20 50"/>)~");
  ASSERT_FALSE(set.curves.empty());
  for (const Curve& c : set.curves) {
    for (double u = 0; u <= 1; u += 0.25) {
      const Point3 p = BezierAt(c, u);
      EXPECT_NEAR(std::hypot(p[0] - 10, p[1] - 50), 10, 1e-6);
    }
  }
  // Sweep 1 from the left end: through the top of the screen (SVG y = 40).
  bool reaches_top = false;
  for (const Curve& c : set.curves) reaches_top |= std::abs(BezierAt(c, 1)[1] - 60) < 1e-9;
  EXPECT_TRUE(reaches_top);
}

TEST(SvgPath, ErrorsNameTheLineElementAttributeAndColumn) {
  EXPECT_EQ(ErrorOf([] { Read("<g>\n<path id=\"p3\" d=\"M0 0 C 1 2 x\"/></g>"); }),
            "t.svg:3: <path id=\"p3\"> d: expected a number after 'C' at column 12");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<path d="L0 0"/>)~"); }),
            "t.svg:2: <path> d: path data must start with 'M' or 'm', not 'L' at column 1");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<path d="M0 0 K1 1"/>)~"); }),
            "t.svg:2: <path> d: unknown path command 'K' at column 6");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<path d="M0 0 A1 1 0 2 0 5 5"/>)~"); }),
            "t.svg:2: <path> d: expected a flag 0 or 1 after 'A' at column 13");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<path d="M0 0 L1e999 1"/>)~"); }),
            "t.svg:2: <path> d: number '1e999' is out of range at column 7");
}

// ---- shapes -------------------------------------------------------------------

TEST(SvgShapes, LinePolylinePolygon) {
  const PatchSet set =
      Read(R"~(<line x1="1" y1="2" x2="3" y2="4"/><polyline points="0,0 10,0 10,10"/>)~"
           R"~(<polygon points="20 20, 30 20 30 30"/>)~");
  ASSERT_EQ(set.curves.size(), 6u);
  ExpectLine(set.curves[0], Out(1, 2), Out(3, 4));
  ExpectLine(set.curves[2], Out(10, 0), Out(10, 10));
  ExpectLine(set.curves[5], Out(30, 30), Out(20, 20));  // the polygon closes
}

TEST(SvgShapes, RectSquareAndRounded) {
  const PatchSet square = Read(R"~(<rect x="10" y="20" width="30" height="40"/>)~");
  ASSERT_EQ(square.curves.size(), 4u);
  ExpectLine(square.curves[0], Out(10, 20), Out(40, 20));
  ExpectLine(square.curves[1], Out(40, 20), Out(40, 60));
  ExpectLine(square.curves[3], Out(10, 60), Out(10, 20));
  // rx alone: ry = rx (auto); rx = 50 is clamped to half the width (15).
  for (const char* rect : {R"~(<rect x="10" y="20" width="30" height="40" rx="15"/>)~",
                           R"~(<rect x="10" y="20" width="30" height="40" rx="50" ry="15"/>)~"}) {
    const PatchSet round = Read(rect);
    ASSERT_GT(round.curves.size(), 4u) << rect;
    // Width 30 = 2·15: no straight top edge; the left and right edges are 10 long.
    int straight = 0;
    for (const Curve& c : round.curves) straight += c.straight ? 1 : 0;
    EXPECT_EQ(straight, 2) << rect;
    // Every point of the top-left corner is 15 from its centre (25, 35).
    for (const Curve& c : round.curves) {
      const Point3 p = BezierAt(c, 0.5);
      if (!c.straight && p[0] < 25 && p[1] > 100 - 35) {
        EXPECT_NEAR(std::hypot(p[0] - 25, p[1] - 65), 15, 1e-6);
      }
    }
  }
  EXPECT_EQ(ErrorOf([] { Read(R"~(<rect id="r" width="-1" height="2"/>)~"); }),
            "t.svg:2: <rect id=\"r\"> width: must not be negative");
}

TEST(SvgShapes, CircleAndEllipseLieOnTheirCurves) {
  const PatchSet set = Read(
      R"~(<circle cx="50" cy="50" r="20"/><ellipse id="e" cx="30" cy="40" rx="20" ry="10"/>)~");
  bool saw_ellipse = false;
  for (const Curve& c : set.curves) {
    const bool ellipse = c.origin.find("<ellipse id=\"e\">") != std::string::npos;
    saw_ellipse |= ellipse;
    for (double u = 0; u <= 1; u += 0.1) {
      const Point3 p = BezierAt(c, u);
      if (ellipse) {
        // (x − 30)²/20² + (y − 60)²/10² = 1 to within the bound (1e-6 mm
        // in distance; the implicit form's gradient is ≥ 2/20).
        const double f = std::pow((p[0] - 30) / 20, 2) + std::pow((p[1] - 60) / 10, 2) - 1;
        EXPECT_NEAR(f, 0, 2e-6 * 2 / 10);
      } else {
        EXPECT_NEAR(std::hypot(p[0] - 50, p[1] - 50), 20, 1e-6);
      }
    }
  }
  EXPECT_TRUE(saw_ellipse);
  // A closed outline from the rightmost point.
  ExpectNear(set.curves.front().g[0], Out(70, 50));
  ExpectNear(set.curves.back().g[3], Out(50, 40), 1e-9);
}

// ---- transforms, use, viewports --------------------------------------------------

// The end points of the one line in `body`, in output coordinates.
std::array<Point3, 2> LineEnds(const std::string& body) {
  const PatchSet set = Read(body);
  EXPECT_EQ(set.curves.size(), 1u) << body;
  if (set.curves.empty()) return {};
  return {set.curves[0].g[0], set.curves[0].g[3]};
}

TEST(SvgTransform, EachFunction) {
  const std::string line = R"~(<line x1="1" y1="2" x2="3" y2="4" transform=")~";
  auto ends = [&](const std::string& t) { return LineEnds(line + t + R"~("/>)~"); };
  ExpectNear(ends("translate(10 20)")[0], Out(11, 22));
  ExpectNear(ends("translate(10)")[0], Out(11, 2));
  ExpectNear(ends("scale(2)")[1], Out(6, 8));
  ExpectNear(ends("scale(2, -1)")[1], Out(6, -4));
  ExpectNear(ends("rotate(90)")[0], Out(-2, 1), 1e-12);  // (x, y) → (−y, x)
  // rotate(90, 10, 10): (1,2) − (10,10) = (−9,−8) → (8,−9), + (10,10) = (18, 1).
  ExpectNear(ends("rotate(90, 10, 10)")[0], Out(18, 1), 1e-12);
  ExpectNear(ends("skewX(45)")[0], Out(3, 2), 1e-12);  // x + tan45·y
  ExpectNear(ends("skewY(45)")[0], Out(1, 3), 1e-12);
  ExpectNear(ends("matrix(1 2 3 4 5 6)")[0], Out(1 + 6 + 5, 2 + 8 + 6));
  // A list applies right to left: scale first, then translate.
  ExpectNear(ends("translate(10,0) scale(2)")[0], Out(12, 4));
  ExpectNear(ends("scale(2),translate(10,0)")[0], Out(22, 4));
}

TEST(SvgTransform, NestedGroupsCompose) {
  const auto e =
      LineEnds(R"~(<g transform="translate(10 0)"><g transform="scale(2)">)~"
               R"~(<line x1="1" y1="2" x2="3" y2="4" transform="translate(0 1)"/></g></g>)~");
  ExpectNear(e[0], Out(12, 6));
}

TEST(SvgTransform, Errors) {
  EXPECT_EQ(ErrorOf([] { Read(R"~(<g transform="rotate(1, 2)"><line/></g>)~"); }),
            "t.svg:2: <g> transform: rotate() takes 1 or 3 numbers, not 2 at column 1");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<g transform="scale(1) spin(3)"><line/></g>)~"); }),
            "t.svg:2: <g> transform: unknown transform 'spin' at column 10");
}

TEST(SvgUse, HrefAndXlinkHrefWithOffset) {
  for (const char* attr : {"href", "xlink:href"}) {
    const PatchSet set =
        Read(std::string(R"~(<defs><line id="l" x1="1" y1="2" x2="3" y2="4"/></defs>)~") + "<use " +
             attr + R"~(="#l" x="10" y="20" transform="scale(2)"/>)~");
    ASSERT_EQ(set.curves.size(), 1u) << attr;
    // translate(x, y) after the use's transform: 2·((1,2) + (10,20)).
    ExpectNear(set.curves[0].g[0], Out(22, 44));
    EXPECT_TRUE(set.notes.empty()) << set.notes[0];
  }
  EXPECT_EQ(ErrorOf([] { Read(R"~(<use id="u" href="#nope"/>)~"); }),
            "t.svg:2: <use id=\"u\"> href: no element has the id 'nope'");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<g id="g"><use href="#g"/></g>)~"); }),
            "t.svg:2: <use> href: refers to an element that contains this <use> (a cycle)");
}

TEST(SvgUse, SymbolWithViewBox) {
  // A 10×10 symbol shown at 20×20: scale 2.
  const PatchSet set =
      Read(R"~(<symbol id="s" viewBox="0 0 10 10"><line x1="0" y1="0" x2="10" y2="10"/></symbol>)~"
           R"~(<use href="#s" x="5" y="5" width="20" height="20"/>)~");
  ASSERT_EQ(set.curves.size(), 1u);
  ExpectNear(set.curves[0].g[0], Out(5, 5));
  ExpectNear(set.curves[0].g[3], Out(25, 25));
}

std::array<Point3, 2> PageLine(const std::string& svg_attributes, PatchSet* out = nullptr) {
  const std::string text = R"~(<svg xmlns="http://www.w3.org/2000/svg" )~" + svg_attributes +
                           R"~(><line x1="0" y1="0" x2="10" y2="0"/></svg>)~";
  const PatchSet set = ReadSvg(text, "p.svg");
  if (out) *out = set;
  return {set.curves.at(0).g[0], set.curves.at(0).g[3]};
}

TEST(SvgPage, UnitsAndViewBox) {
  PatchSet set;
  // 96 px per inch: 10 px = 2.6458333 mm; the page 1 in × 2 in.
  auto e = PageLine(R"~(width="1in" height="2in")~", &set);
  ASSERT_TRUE(set.page.has_value());
  EXPECT_NEAR((*set.page)[0], 25.4, 1e-12);
  EXPECT_NEAR((*set.page)[1], 50.8, 1e-12);
  ExpectNear(e[0], {0, 50.8, 0});
  ExpectNear(e[1], {10 * 25.4 / 96, 50.8, 0});
  EXPECT_EQ(set.units, "mm");
  for (const auto& [unit, mm] : std::vector<std::pair<std::string, double>>{{"mm", 1},
                                                                            {"cm", 10},
                                                                            {"pt", 25.4 / 72},
                                                                            {"pc", 25.4 / 6},
                                                                            {"px", 25.4 / 96},
                                                                            {"", 25.4 / 96}}) {
    PageLine("width=\"10" + unit + "\" height=\"20" + unit + "\"", &set);
    EXPECT_NEAR((*set.page)[0], 10 * mm, 1e-12) << unit;
    EXPECT_NEAR((*set.page)[1], 20 * mm, 1e-12) << unit;
  }
  // viewBox 0 0 100 100 into 200 × 100 mm, xMidYMid meet: scale 1, x offset 50.
  e = PageLine(R"~(width="200mm" height="100mm" viewBox="0 0 100 100")~");
  ExpectNear(e[0], {50, 100, 0});
  ExpectNear(e[1], {60, 100, 0});
  e = PageLine(
      R"~(width="200mm" height="100mm" viewBox="0 0 100 100" preserveAspectRatio="xMinYMin meet")~");
  ExpectNear(e[0], {0, 100, 0});
  e = PageLine(
      R"~(width="200mm" height="100mm" viewBox="0 0 100 100" preserveAspectRatio="none")~");
  ExpectNear(e[1], {20, 100, 0});
  // A viewBox alone: its size in px.
  e = PageLine(R"~(viewBox="-10 0 96 96")~", &set);
  EXPECT_NEAR((*set.page)[0], 25.4, 1e-12);
  ExpectNear(e[0], {10 * 25.4 / 96, 25.4, 0}, 1e-12);
}

TEST(SvgPage, NestedSvgViewport) {
  const PatchSet set = Read(R"~(<svg x="10" y="10" width="20" height="20" viewBox="0 0 10 10">)~"
                            R"~(<line x1="0" y1="0" x2="10" y2="0"/></svg>)~");
  ASSERT_EQ(set.curves.size(), 1u);
  ExpectNear(set.curves[0].g[0], Out(10, 10));
  ExpectNear(set.curves[0].g[3], Out(30, 10));
}

// ---- the arc bound --------------------------------------------------------------

// The distance from q to the ellipse θ ↦ map(c + R(φ)(rx cos θ, ry sin θ)),
// found on a fine grid and refined by golden-section search.
double DistanceToEllipse(const Point3& q, const std::function<Point3(double)>& ellipse) {
  auto d = [&](double t) {
    const Point3 p = ellipse(t);
    return std::hypot(p[0] - q[0], p[1] - q[1]);
  };
  const int n = 720;
  int best = 0;
  for (int i = 1; i < n; ++i) {
    if (d(2 * kPi * i / n) < d(2 * kPi * best / n)) best = i;
  }
  double a = 2 * kPi * (best - 1) / n;
  double b = 2 * kPi * (best + 1) / n;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int k = 0; k < 100; ++k) {
    const double x1 = b - g * (b - a);
    const double x2 = a + g * (b - a);
    if (d(x1) < d(x2)) {
      b = x2;
    } else {
      a = x1;
    }
  }
  return d((a + b) / 2);
}

struct ArcCase {
  double cx, cy, rx, ry, phi_deg, from_deg, to_deg;
  const char* transform;
  // The transform as a function, written here again (not the reader's).
  std::function<std::array<double, 2>(double, double)> map;
};

// Every point of the arc's cubics within `tolerance` of the exact ellipse,
// sampled from its own parametric form, and the largest distance seen.
double WorstArcDistance(const ArcCase& a, double tolerance) {
  const double phi = a.phi_deg * kPi / 180;
  auto user = [&](double t) {
    const double x = a.rx * std::cos(t);
    const double y = a.ry * std::sin(t);
    return std::array<double, 2>{a.cx + std::cos(phi) * x - std::sin(phi) * y,
                                 a.cy + std::sin(phi) * x + std::cos(phi) * y};
  };
  auto page = [&](double t) {
    const auto u = user(t);
    const auto m = a.map(u[0], u[1]);
    return Point3{m[0], 100 - m[1], 0};
  };
  const auto p0 = user(a.from_deg * kPi / 180);
  const auto p1 = user(a.to_deg * kPi / 180);
  const double sweep = a.to_deg - a.from_deg;
  char d[256];
  std::snprintf(d, sizeof d, "M%.17g %.17g A%.17g %.17g %.17g %d %d %.17g %.17g", p0[0], p0[1],
                a.rx, a.ry, a.phi_deg, std::abs(sweep) > 180 ? 1 : 0, sweep > 0 ? 1 : 0, p1[0],
                p1[1]);
  SvgOptions options;
  options.arc_tolerance = tolerance;
  const PatchSet set = Read(
      std::string("<g transform=\"") + a.transform + "\"><path d=\"" + d + "\"/></g>", options);
  double worst = 0;
  for (const Curve& c : set.curves) {
    for (int i = 0; i <= 10; ++i) {
      worst = std::max(worst, DistanceToEllipse(BezierAt(c, i / 10.0), page));
    }
  }
  return worst;
}

std::vector<ArcCase> ArcCases() {
  auto identity = [](double x, double y) { return std::array<double, 2>{x, y}; };
  return {
      {50, 50, 40, 20, 30, 10, 300, "", identity},
      {50, 50, 45, 45, 0, 0, -90, "", identity},
      {40, 60, 30, 10, -70, 200, 30, "", identity},
      // Non-uniform scale and a skew: the bound holds on the page.
      {20, 20, 15, 8, 15, -30, 200, "translate(30 40) scale(2 0.5) skewX(30)",
       [](double x, double y) {
         const double sx = x + std::tan(kPi / 6) * y;
         return std::array<double, 2>{30 + 2 * sx, 40 + 0.5 * y};
       }},
  };
}

TEST(SvgArcBound, CubicsLieWithinTheToleranceOfTheExactEllipse) {
  for (double tolerance : {1e-2, 1e-4, 1e-6}) {
    for (const ArcCase& a : ArcCases()) {
      const double worst = WorstArcDistance(a, tolerance);
      EXPECT_LE(worst, tolerance) << "arc about (" << a.cx << ", " << a.cy << ") " << a.transform;
      // The check itself is sharp enough to see an error of the tolerance's size.
      if (tolerance >= 1e-4) {
        EXPECT_GT(worst, tolerance / 1000) << "the sampling does not see the error";
      }
    }
  }
}

TEST(SvgArcBound, RefusesAToleranceThatIsNotPositive) {
  SvgOptions options;
  options.arc_tolerance = 0;
  EXPECT_THROW(Read(R"~(<circle r="1"/>)~", options), OptionError);
}

// ---- what is left out, files, errors ------------------------------------------

TEST(SvgLeftOut, HiddenAndUnsupportedElementsAreCountedInANote) {
  const PatchSet set = Read(
      R"~(<text>a</text><text>b</text><image href="x.png"/>)~"
      R"~(<line x2="1" display="none"/><line x2="1" style="fill:red; display : none"/>)~"
      R"~(<g visibility="hidden"><line x2="1"/><line x2="2" visibility="visible"/></g>)~"
      R"~(<style>line { stroke: red }</style><defs><path id="unused" d="M0 0 L1 1"/></defs>)~"
      R"~(<line x2="3" clip-path="url(#c)"/><clipPath id="c"><rect width="1" height="1"/></clipPath>)~"
      R"~(<mask/><pattern/><marker/>)~");
  // Drawn: the visible child of the hidden group and the clipped line.
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectLine(set.curves[0], Out(0, 0), Out(2, 0));
  ASSERT_EQ(set.notes.size(), 1u);
  EXPECT_EQ(set.notes[0],
            "t.svg: left out: 2 <text>, 1 <image>, 2 hidden (display:none), 1 hidden "
            "(visibility:hidden), 1 <style> sheet (CSS not applied), 1 unused <defs> element, "
            "1 clip-path (drawn unclipped), 1 <clipPath>, 1 <mask>, 1 <pattern>, 1 <marker>");
}

TEST(SvgErrors, MalformedXmlNothingToDrawAndTheRoot) {
  EXPECT_EQ(ErrorOf([] { ReadSvg("<svg>\n<path d='M0 0 L1 1'>\n</svg>", "x.svg"); }),
            "x.svg:3: malformed XML: Start-end tags mismatch");
  EXPECT_EQ(ErrorOf([] { ReadSvg("<html/>", "x.svg"); }),
            "x.svg:1: the root element is <html>, not <svg>");
  EXPECT_EQ(ErrorOf([] { Read("<text>only</text>"); }),
            "t.svg: nothing to draw: no path or shape is visible (t.svg: left out: 1 <text>)");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<polyline id="q" points="1 2 3"/>)~"); }),
            "t.svg:2: <polyline id=\"q\"> points: an odd number of coordinates");
  EXPECT_EQ(ErrorOf([] { Read(R"~(<circle r="5%"/>)~"); }),
            "t.svg:2: <circle> r: percentage lengths are not supported");
}

TEST(SvgFiles, OriginsNameTheElementAndLine) {
  const PatchSet set = Read("\n\n<path id=\"p3\" d=\"M0 0 L1 1\"/>");
  EXPECT_EQ(set.curves.at(0).origin, "t.svg: <path id=\"p3\"> (line 4)");
}

TEST(SvgFiles, ReadPatchFileTakesSvgByNameAndByContent) {
  const std::string text = Page(R"~(<line x1="1" y1="2" x2="3" y2="4"/>)~");
  for (const char* name : {"svg_io_test_a.SVG", "svg_io_test_b.drawing"}) {
    const std::string path = testing::TempDir() + name;
    std::ofstream(path) << "<?xml version=\"1.0\"?>\n" << text;
    const PatchSet set = ReadPatchFile(path);
    ASSERT_EQ(set.curves.size(), 1u) << name;
    ExpectNear(set.curves[0].g[0], Out(1, 2));
    std::remove(path.c_str());
  }
  EXPECT_TRUE(LooksLikeSvg("  <svg/>"));
  EXPECT_TRUE(LooksLikeSvg("<!-- c -->\n<svg/>"));
  EXPECT_FALSE(LooksLikeSvg("{\"patches\": []}"));
  EXPECT_FALSE(LooksLikeSvg("1\n3 3\n"));
}

// ---- layers ----------------------------------------------------------------------

TEST(SvgLayers, InkscapeLayersInDocumentOrder) {
  PatchSet set = Read(
      R"~(<g inkscape:groupmode="layer" inkscape:label="Pen 1"><line x2="1"/>)~"
      R"~(<g inkscape:groupmode="layer" inkscape:label="sub"><line x2="2"/></g></g>)~"
      R"~(<g inkscape:groupmode="layer" id="layer2"><line x2="3" stroke="red"/></g>)~"
      R"~(<g inkscape:groupmode="layer" inkscape:label="off" style="display:none"><line/></g>)~");
  ASSERT_EQ(set.layers, (std::vector<std::string>{"Pen 1", "layer2"}));
  ASSERT_EQ(set.curves.size(), 3u);
  EXPECT_EQ(set.curves[0].layer, 0);
  EXPECT_EQ(set.curves[1].layer, 0);  // a sublayer belongs to its top layer
  EXPECT_EQ(set.curves[2].layer, 1);
  SelectLayer(&set, "2");
  ASSERT_EQ(set.curves.size(), 1u);
  ExpectLine(set.curves[0], Out(0, 0), Out(3, 0));
  EXPECT_EQ(set.curves[0].layer, 0);
  EXPECT_EQ(set.layers, (std::vector<std::string>{"layer2"}));
}

TEST(SvgLayers, StrokeColoursWithoutInkscapeLayers) {
  PatchSet set =
      Read(R"~(<g stroke="#ff0000"><line x2="1"/><line x2="2" style="stroke:blue"/></g>)~"
           R"~(<line x2="3" stroke="#ff0000"/><line x2="4"/>)~");
  ASSERT_EQ(set.layers, (std::vector<std::string>{"#ff0000", "blue", "none"}));
  EXPECT_EQ(set.curves[2].layer, 0);
  EXPECT_EQ(set.curves[3].layer, 2);
  EXPECT_EQ(ErrorOf([&] { SelectLayer(&set, "green"); }),
            "--layer green: no such layer; the drawing has 1 \"#ff0000\", 2 \"blue\", 3 \"none\"");
  SelectLayer(&set, "#ff0000");
  EXPECT_EQ(set.curves.size(), 2u);
  // One colour: no layers.
  const PatchSet one = Read(R"~(<line x2="1" stroke="red"/><line x2="2" stroke="red"/>)~");
  EXPECT_TRUE(one.layers.empty());
  PatchSet none = one;
  EXPECT_EQ(ErrorOf([&] { SelectLayer(&none, "1"); }), "--layer 1: the drawing has no layers");
}

}  // namespace
}  // namespace fdsurf::host
