// SPDX-License-Identifier: MIT
// Reading G-code programs. Expected points are written by hand or computed
// here from the circle (centre + r·(cos, sin)); curves are evaluated here by
// their Bernstein form, not by the library.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numbers>

#include "fdsurf/host/gcode_io.h"
#include "fdsurf/host/patch_io.h"
#include "format_test_support.h"

namespace fdsurf::host {
namespace {

using format_test::BezierAt;
using format_test::ErrorOf;

constexpr double kPi = std::numbers::pi;

PatchSet Read(const std::string& text, const GcodeReadOptions& options = {}) {
  return ReadGcode(text, "p.gcode", options);
}

std::string ReadError(const std::string& text) {
  return ErrorOf([&] { (void)Read(text); });
}

void ExpectPoint(const Point3& got, const Point3& want, double tolerance, const std::string& what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], tolerance) << what << " axis " << k;
}

void ExpectLine(const Curve& c, const Point3& from, const Point3& to) {
  EXPECT_TRUE(c.straight) << c.origin;
  EXPECT_EQ(c.basis, Basis::kBezier);
  ExpectPoint(BezierAt(c, 0), from, 1e-12, c.origin + " start");
  ExpectPoint(BezierAt(c, 1), to, 1e-12, c.origin + " end");
  ExpectPoint(BezierAt(c, 0.5),
              {(from[0] + to[0]) / 2, (from[1] + to[1]) / 2, (from[2] + to[2]) / 2}, 1e-12,
              c.origin + " middle");
}

// The plane of an arc: the axes a, b (angles turn from a to b) and normal n.
struct Plane {
  int a, b, n;
};
constexpr Plane kXY{0, 1, 2};
constexpr Plane kZX{2, 0, 1};
constexpr Plane kYZ{1, 2, 0};

// The curves [first, last) lie on the circle about `centre` (in the plane)
// of radius r, within `bound`, start at angle a0 and turn monotonically by
// `sweep` (radians, + counter-clockwise), each joining the next.
void ExpectArc(const PatchSet& set, std::size_t first, std::size_t last, Plane p,
               std::array<double, 2> centre, double r, double a0, double sweep,
               double bound = 1e-6) {
  ASSERT_LT(first, last);
  ASSERT_LE(last, set.curves.size());
  const auto angle_of = [&](const Point3& q) {
    return std::atan2(q[p.b] - centre[1], q[p.a] - centre[0]);
  };
  const Point3 start = BezierAt(set.curves[first], 0);
  EXPECT_NEAR(start[p.a], centre[0] + r * std::cos(a0), 1e-9);
  EXPECT_NEAR(start[p.b], centre[1] + r * std::sin(a0), 1e-9);
  const Point3 end = BezierAt(set.curves[last - 1], 1);
  EXPECT_NEAR(end[p.a], centre[0] + r * std::cos(a0 + sweep), 1e-9);
  EXPECT_NEAR(end[p.b], centre[1] + r * std::sin(a0 + sweep), 1e-9);
  double turned = 0;
  double previous = angle_of(start);
  for (std::size_t c = first; c < last; ++c) {
    if (c > first) {
      ExpectPoint(BezierAt(set.curves[c], 0), BezierAt(set.curves[c - 1], 1), 1e-12, "join");
    }
    EXPECT_FALSE(set.curves[c].straight);
    for (int k = 1; k <= 64; ++k) {
      const Point3 q = BezierAt(set.curves[c], k / 64.0);
      const double distance = std::hypot(q[p.a] - centre[0], q[p.b] - centre[1]);
      EXPECT_NEAR(distance, r, bound + 1e-12) << set.curves[c].origin << " t=" << k / 64.0;
      double step = angle_of(q) - previous;
      if (step > kPi) step -= 2 * kPi;
      if (step < -kPi) step += 2 * kPi;
      EXPECT_TRUE(sweep > 0 ? step >= -1e-12 : step <= 1e-12) << "turns back at " << c;
      turned += step;
      previous = angle_of(q);
    }
  }
  EXPECT_NEAR(turned, sweep, 1e-9);
}

std::size_t CountNotes(const PatchSet& set, const std::string& part) {
  std::size_t n = 0;
  for (const std::string& note : set.notes) n += note.find(part) != std::string::npos ? 1 : 0;
  return n;
}

// ---- words ------------------------------------------------------------------

TEST(GcodeWords, CompactCaseCommentsAndLineNumbers) {
  const PatchSet set = Read(
      "g21 (metric) ; a comment\n"
      "N10 G1X10Y-2.5 ( move ) F300\n"
      "n20 x 12 y +.5;end\n");
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectLine(set.curves[0], {0, 0, 0}, {10, -2.5, 0});
  ExpectLine(set.curves[1], {10, -2.5, 0}, {12, 0.5, 0});
  EXPECT_EQ(set.curves[0].origin, "p.gcode:2 (G1)");
  EXPECT_EQ(set.units, "mm");
  EXPECT_TRUE(set.keep_order);
  EXPECT_TRUE(set.layers.empty());
}

TEST(GcodeWords, NoExponents) {
  // "X1E3" is X1 and an E word (extrusion, ignored), not X1000.
  const PatchSet set = Read("G21\nG1 X1E3 Y0\n");
  ExpectLine(set.curves[0], {0, 0, 0}, {1, 0, 0});
  EXPECT_EQ(CountNotes(set, "p.gcode:2: E (extrusion) words ignored"), 1u);
}

TEST(GcodeWords, MarlinChecksums) {
  // The checksums were computed by hand (XOR of the bytes before '*').
  const PatchSet set = Read("N1 G1 X10 Y0*25\nN2 G1 X10 Y5*31\n");
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectLine(set.curves[1], {10, 0, 0}, {10, 5, 0});
  EXPECT_EQ(ReadError("N1 G1 X10 Y0*25\nN2 G1 X10 Y5*30\n"),
            "p.gcode:2: checksum *30 is wrong: the line's bytes before '*' give 31");
  EXPECT_EQ(ReadError("N1 G1 X10 Y0*\n"), "p.gcode:1: checksum '*': not a number");
}

TEST(GcodeWords, PercentDelimitsTheProgram) {
  const PatchSet set = Read("%\nG1 X1\n%\nG1 X99\n");
  ASSERT_EQ(set.curves.size(), 1u);
  ExpectLine(set.curves[0], {0, 0, 0}, {1, 0, 0});
}

TEST(GcodeWords, BlockDeleteSkipsOrRuns) {
  const std::string program = "G1 X1\n/G1 X5\nG1 Y1\n";
  const PatchSet skipped = Read(program);
  ASSERT_EQ(skipped.curves.size(), 2u);
  ExpectLine(skipped.curves[1], {1, 0, 0}, {1, 1, 0});
  EXPECT_EQ(CountNotes(skipped, "p.gcode:2: lines starting with '/'"), 1u);
  GcodeReadOptions run;
  run.skip_block_delete = false;
  const PatchSet ran = Read(program, run);
  ASSERT_EQ(ran.curves.size(), 3u);
  ExpectLine(ran.curves[2], {5, 0, 0}, {5, 1, 0});
}

TEST(GcodeWords, Errors) {
  EXPECT_EQ(ReadError("G1 X10\nG1 Y2\nG1 X1 Y\n"), "p.gcode:3: word 'Y': no number");
  EXPECT_EQ(ReadError("G1 X1\n\n\n\n\n\nG1 X ab\n"), "p.gcode:7: word 'X': 'ab' is not a number");
  EXPECT_EQ(ReadError("G1 X1 (open\n"), "p.gcode:1: comment '(' is not closed on its line");
  EXPECT_EQ(ReadError("G1 X#1\n"), "p.gcode:1: word 'X': '#1' is not a number");
  EXPECT_EQ(ReadError("#1=2\n"), "p.gcode:1: '#': parameters and expressions are not supported");
  EXPECT_EQ(ReadError("G1 X1 X2\n"), "p.gcode:1: word 'X' given twice");
  EXPECT_EQ(ReadError("G1 X1 & Y2\n"), "p.gcode:1: unexpected character '&'");
  EXPECT_EQ(ReadError("G0 X1\n"), "p.gcode: the program draws nothing (no move with the pen down)");
  EXPECT_EQ(ReadError("o100 sub\n"), "p.gcode:1: O-word subroutines are not supported");
}

// ---- motion, modes, units ----------------------------------------------------

TEST(GcodeMotion, ModalMotionAndTravel) {
  // No pen commands: G1 draws, G0 is travel; bare coordinates continue the mode.
  const PatchSet set = Read("G0 X5 Y5\nG1 X6\nY6\nG0 X0\nX1 Y1\nG1 Y2\n");
  ASSERT_EQ(set.curves.size(), 3u);
  ExpectLine(set.curves[0], {5, 5, 0}, {6, 5, 0});
  ExpectLine(set.curves[1], {6, 5, 0}, {6, 6, 0});
  ExpectLine(set.curves[2], {1, 1, 0}, {1, 2, 0});
  EXPECT_EQ(set.curves[1].origin, "p.gcode:3 (G1)");
}

TEST(GcodeMotion, RelativeMode) {
  const PatchSet set = Read("G91\nG1 X2 Y1\nX2\nG90\nX0\n");
  ASSERT_EQ(set.curves.size(), 3u);
  ExpectLine(set.curves[0], {0, 0, 0}, {2, 1, 0});
  ExpectLine(set.curves[1], {2, 1, 0}, {4, 1, 0});
  ExpectLine(set.curves[2], {4, 1, 0}, {0, 1, 0});
}

TEST(GcodeMotion, UnitsAndMixedUnits) {
  const PatchSet inches = Read("G20\nG1 X1 Y2\n");
  EXPECT_EQ(inches.units, "in");
  ExpectLine(inches.curves[0], {0, 0, 0}, {1, 2, 0});
  // The program's first unit stays; later inch values are converted.
  const PatchSet mixed = Read("G21\nG1 X10\nG20\nG1 X1\nG21\nG1 Y5\n");
  EXPECT_EQ(mixed.units, "mm");
  ExpectLine(mixed.curves[1], {10, 0, 0}, {25.4, 0, 0});
  ExpectLine(mixed.curves[2], {25.4, 0, 0}, {25.4, 5, 0});
  EXPECT_EQ(CountNotes(mixed, "p.gcode:3: G20: the values that follow are converted to mm"), 1u);
  const PatchSet unsaid = Read("G1 X1\n");
  EXPECT_EQ(unsaid.units, "mm");
  EXPECT_EQ(CountNotes(unsaid, "millimetres assumed"), 1u);
}

TEST(GcodeMotion, G92SetsThePosition) {
  // At (10, 0) the program calls the point (0, 0): X5 is then machine X15.
  const PatchSet set = Read("G1 X10\nG92 X0 Y0\nG1 X5\nG91\nG1 Y1\n");
  ASSERT_EQ(set.curves.size(), 3u);
  ExpectLine(set.curves[1], {10, 0, 0}, {15, 0, 0});
  ExpectLine(set.curves[2], {15, 0, 0}, {15, 1, 0});
}

TEST(GcodeMotion, G28TravelsHome) {
  const PatchSet set = Read("G1 X10 Y10\nG28\nG1 X1\n");
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectLine(set.curves[1], {0, 0, 0}, {1, 0, 0});
  EXPECT_EQ(CountNotes(set, "p.gcode:2: G28: home is taken as where the program started"), 1u);
}

TEST(GcodeMotion, EndAndIgnoredCodes) {
  const PatchSet set =
      Read("G21 G17 G90 G94 G64 G54 M8\nG4 P0.5\nG1 X1 F100 S200\nG64\nM2\nG1 X50\n");
  ASSERT_EQ(set.curves.size(), 1u);
  EXPECT_EQ(CountNotes(set, "p.gcode:1: G64 ignored"), 1u);  // once, with its first line
  EXPECT_EQ(CountNotes(set, "G64"), 1u);
  EXPECT_EQ(CountNotes(set, "p.gcode:1: G54 ignored (G54 is the only coordinate system)"), 1u);
  EXPECT_EQ(CountNotes(set, "p.gcode:1: G94 ignored"), 1u);
  EXPECT_EQ(CountNotes(set, "p.gcode:1: M8 ignored"), 1u);
  EXPECT_EQ(CountNotes(set, "G4"), 0u);  // dwell: no note
  EXPECT_EQ(CountNotes(set, "p.gcode:5: the program ends here"), 1u);
}

TEST(GcodeMotion, CodesThatMoveAreRefused) {
  EXPECT_EQ(ReadError("G1 X1\nG81 X1 Y1 Z-1 R1\n"),
            "p.gcode:2: G81: canned cycles are not supported");
  EXPECT_EQ(ReadError("G38.2 Z-5\n"), "p.gcode:1: G38.2: probing is not supported");
  EXPECT_EQ(ReadError("G33 Z-5 K1\n"), "p.gcode:1: G33: threading is not supported");
  EXPECT_EQ(ReadError("G55\n"), "p.gcode:1: G55: only one coordinate system (G54) is supported");
  EXPECT_EQ(ReadError("G41 D1\n"), "p.gcode:1: G41: cutter compensation is not supported");
  EXPECT_EQ(ReadError("G12 X1\n"), "p.gcode:1: G12: not supported (an unknown G code may move)");
  EXPECT_EQ(ReadError("G1 A10\n"), "p.gcode:1: word 'A': only the X, Y and Z axes are supported");
  EXPECT_EQ(ReadError("G0 G1 X1\n"), "p.gcode:1: two motion codes, G0 and G1, on one line");
  EXPECT_EQ(ReadError("G1 X1 I2\n"),
            "p.gcode:1: word 'I': no G2, G3, G5 or G5.1 on the line to use it");
}

// ---- pen ---------------------------------------------------------------------

TEST(GcodePen, SpindleCommands) {
  // M3 down, M5 up; with pen commands G0 follows the pen too.
  const PatchSet set = Read("G0 X1\nM3\nG1 X2\nG0 X3\nM5\nG1 X4\nM4\nG1 X5\n");
  ASSERT_EQ(set.curves.size(), 3u);
  ExpectLine(set.curves[0], {1, 0, 0}, {2, 0, 0});
  ExpectLine(set.curves[1], {2, 0, 0}, {3, 0, 0});
  ExpectLine(set.curves[2], {4, 0, 0}, {5, 0, 0});
}

TEST(GcodePen, MarlinServo) {
  const PatchSet set = Read("M280 P0 S90\nG1 X1\nM280 P0 S30\nG1 X2\nM280 P0 S50\nG1 X3\n");
  ASSERT_EQ(set.curves.size(), 1u);
  ExpectLine(set.curves[0], {1, 0, 0}, {2, 0, 0});
  GcodeReadOptions options;
  options.servo_down_below = 100;
  EXPECT_EQ(Read("M280 P0 S90\nG1 X1\n", options).curves.size(), 1u);
  EXPECT_EQ(ReadError("M280 P0\n"), "p.gcode:1: M280: no S (servo angle)");
}

TEST(GcodePen, ZThreshold) {
  // Z ≤ 0 is down; Z is unknown (up) until the program names it; a move that
  // enters or leaves the paper is travel.
  const PatchSet set = Read("G1 X1\nG1 Z0\nG1 X2\nG1 X3 Z1\nG1 X4\nG1 Z-0.5\nG1 X5\n");
  ASSERT_EQ(set.curves.size(), 2u);
  ExpectLine(set.curves[0], {1, 0, 0}, {2, 0, 0});
  ExpectLine(set.curves[1], {4, 0, -0.5}, {5, 0, -0.5});
  GcodeReadOptions high;
  high.pen_z_threshold = 2;
  EXPECT_EQ(Read("G1 Z1\nG1 X1\n", high).curves.size(), 1u);
}

// ---- arcs ----------------------------------------------------------------------

TEST(GcodeArcs, QuarterAndHalfCirclesWithOffsets) {
  // G2 from (10, 0) about (0, 0) clockwise to (0, −10); then G3 about (0, −5)
  // counter-clockwise from (0, −10) to (0, 0) (half a circle, radius 5).
  const PatchSet set = Read("G0 X10 Y0\nG2 X0 Y-10 I-10 J0\nG3 X0 Y0 I0 J5\n");
  std::size_t split = 0;
  while (split < set.curves.size() && set.curves[split].origin == "p.gcode:2 (G2)") ++split;
  ExpectArc(set, 0, split, kXY, {0, 0}, 10, 0, -kPi / 2);
  ExpectArc(set, split, set.curves.size(), kXY, {0, -5}, 5, -kPi / 2, kPi);
}

TEST(GcodeArcs, RadiusFormBothSigns) {
  // From (0, 0) to (10, 0), R 5√2: the centre (5, ∓5) for R > 0 (the short
  // way, 90°) and (5, ±5) for R < 0 (270°).
  const double r = 5 * std::sqrt(2.0);
  const PatchSet cw_short = Read("G2 X10 Y0 R" + std::to_string(r) + "\n");
  ExpectArc(cw_short, 0, cw_short.curves.size(), kXY, {5, -5}, r, 3 * kPi / 4, -kPi / 2, 2e-6);
  const PatchSet cw_long = Read("G2 X10 Y0 R-" + std::to_string(r) + "\n");
  ExpectArc(cw_long, 0, cw_long.curves.size(), kXY, {5, 5}, r, -3 * kPi / 4, -3 * kPi / 2, 2e-6);
  const PatchSet ccw_short = Read("G3 X10 Y0 R" + std::to_string(r) + "\n");
  ExpectArc(ccw_short, 0, ccw_short.curves.size(), kXY, {5, 5}, r, -3 * kPi / 4, kPi / 2, 2e-6);
  const PatchSet ccw_long = Read("G3 X10 Y0 R-" + std::to_string(r) + "\n");
  ExpectArc(ccw_long, 0, ccw_long.curves.size(), kXY, {5, -5}, r, 3 * kPi / 4, 3 * kPi / 2, 2e-6);
}

TEST(GcodeArcs, FullCircleAndTurns) {
  const PatchSet set = Read("G0 X3 Y0\nG3 I-3 J0\n");
  ExpectArc(set, 0, set.curves.size(), kXY, {0, 0}, 3, 0, 2 * kPi);
  EXPECT_GE(set.curves.size(), 4u);  // pieces of at most 90°
  const PatchSet twice = Read("G0 X3 Y0\nG2 X3 Y0 I-3 J0 P2\n");
  ExpectArc(twice, 0, twice.curves.size(), kXY, {0, 0}, 3, 0, -4 * kPi);
}

TEST(GcodeArcs, Planes) {
  // G18: angles turn from Z to X (seen from +Y); G19: from Y to Z.
  GcodeReadOptions all;  // Z is an arc axis here, not the pen
  all.pen_z_threshold = 100;
  const PatchSet zx = Read("G18\nG0 X0 Z5\nG3 X5 Z0 I0 K-5\n", all);
  ExpectArc(zx, 0, zx.curves.size(), kZX, {0, 0}, 5, 0, kPi / 2);
  const PatchSet yz = Read("G19\nG0 Y5 Z0\nG2 Y0 Z-5 J-5 K0\n", all);
  ExpectArc(yz, 0, yz.curves.size(), kYZ, {0, 0}, 5, 0, -kPi / 2);
  EXPECT_EQ(ReadError("G17\nG2 X1 Y1 K1\n"),
            "p.gcode:2: G2: K is not an offset in the G17 (XY) plane");
}

TEST(GcodeArcs, HelixMovesTheNormalAxisAlong) {
  GcodeReadOptions options;
  options.pen_z_threshold = 100;
  const PatchSet set = Read("G0 X4 Y0 Z0\nG3 X-4 Y0 Z-2 I-4 J0\n", options);
  ExpectArc(set, 0, set.curves.size(), kXY, {0, 0}, 4, 0, kPi);
  EXPECT_NEAR(BezierAt(set.curves.back(), 1)[2], -2, 1e-12);
  EXPECT_EQ(CountNotes(set, "p.gcode:2: G3: a helical move"), 1u);
}

TEST(GcodeArcs, TheBoundIsTheOption) {
  // A coarser tolerance gives fewer pieces, each still within it.
  GcodeReadOptions coarse;
  coarse.arc_tolerance = 1e-2;
  const PatchSet set = Read("G0 X100 Y0\nG3 I-100 J0\n", coarse);
  ExpectArc(set, 0, set.curves.size(), kXY, {0, 0}, 100, 0, 2 * kPi, 1e-2);
  const PatchSet fine = Read("G0 X100 Y0\nG3 I-100 J0\n");
  EXPECT_GT(fine.curves.size(), set.curves.size());
  EXPECT_EQ(ErrorOf([&] {
              GcodeReadOptions zero;
              zero.arc_tolerance = 0;
              (void)Read("G1 X1\n", zero);
            }),
            "arc tolerance 0 must be > 0");
}

TEST(GcodeArcs, FewCubicsAtTheDefaultTolerance) {
  // The standard circle cubic's error falls as the sixth power of the angle:
  // a half circle of radius 10 within 1e-6 mm is 8 cubics (the Hermite
  // cubic of the rational quadratic needed 64), a full one of 100 is 22
  // (was 128).
  const PatchSet half = Read("G0 X10 Y0\nG2 X-10 Y0 I-10 J0\n");
  EXPECT_EQ(half.curves.size(), 8u);
  ExpectArc(half, 0, half.curves.size(), kXY, {0, 0}, 10, 0, -kPi);
  const PatchSet full = Read("G0 X100 Y0\nG3 I-100 J0\n");
  EXPECT_EQ(full.curves.size(), 22u);
  ExpectArc(full, 0, full.curves.size(), kXY, {0, 0}, 100, 0, 2 * kPi);
}

TEST(GcodeArcs, RefusesAToleranceTheArithmeticCannotMeet) {
  GcodeReadOptions fine;
  fine.arc_tolerance = 1e-14;
  EXPECT_EQ(ErrorOf([&] { (void)Read("G0 X100 Y0\nG3 I-100 J0\n", fine); })
                .rfind("p.gcode:2: G3: the arc cannot be drawn within the arc tolerance "
                       "(--arc-tolerance) 1e-14: rounding alone moves it by ",
                       0),
            0u);
}

TEST(GcodeArcs, Errors) {
  EXPECT_EQ(ReadError("G1 X1\nG2 X2 Y0 R1 I1\n"), "p.gcode:2: G2: R and I/J given together");
  EXPECT_EQ(ReadError("G2 X2 Y0\n"), "p.gcode:1: G2: neither R nor I/J given");
  EXPECT_EQ(ReadError("G2 X10 Y0 R4\n"),
            "p.gcode:1: G2: R 4 is less than half the distance 10 to the end point");
  EXPECT_EQ(ReadError("G2 R4\n"),
            "p.gcode:1: G2: R with the end point at the start (a full circle needs I/J)");
  EXPECT_EQ(ReadError("G2 X10 Y0 I4 J0\n"),
            "p.gcode:1: G2: the end point is not on the arc: it is 6 from the centre, the start 4");
  EXPECT_EQ(ReadError("G2 X10 Y0 I0 J0\n"), "p.gcode:1: G2: the centre is at the start point");
}

// ---- G5, G5.1 ----------------------------------------------------------------

TEST(GcodeSplines, CubicIsExactAndContinues) {
  // LinuxCNC's "curvy N": the controls are start + (I, J) and end + (P, Q);
  // the second G5 without I J starts with −(P, Q) of the first.
  const PatchSet set = Read("G90 G17\nG0 X0 Y0\nG5 I0 J30 P0 Q-30 X10 Y10\nG5 P0 Q-30 X20 Y20\n");
  ASSERT_EQ(set.curves.size(), 2u);
  const std::array<Point3, 4> first = {Point3{0, 0, 0}, Point3{0, 30, 0}, Point3{10, -20, 0},
                                       Point3{10, 10, 0}};
  const std::array<Point3, 4> second = {Point3{10, 10, 0}, Point3{10, 40, 0}, Point3{20, -10, 0},
                                        Point3{20, 20, 0}};
  EXPECT_EQ(set.curves[0].g, first);
  EXPECT_EQ(set.curves[1].g, second);
  EXPECT_EQ(set.curves[0].basis, Basis::kBezier);
  EXPECT_FALSE(set.curves[0].straight);
}

TEST(GcodeSplines, CubicRules) {
  EXPECT_EQ(ReadError("G5 P0 Q1 X1 Y1\n"),
            "p.gcode:1: G5: I and J are required on the first G5 of a series");
  EXPECT_EQ(ReadError("G5 I1 J1 P1 Q1 X1 Y1\nG1 X2\nG5 P1 Q1 X3 Y3\n"),
            "p.gcode:3: G5: I and J are required on the first G5 of a series");
  EXPECT_EQ(ReadError("G5 I1 X1 Y1 P0 Q0\n"), "p.gcode:1: G5: I and J must be given together");
  EXPECT_EQ(ReadError("G5 I1 J1 X1 Y1\n"), "p.gcode:1: G5: P and Q are both required");
  EXPECT_EQ(ReadError("G18\nG5 I1 J1 P1 Q1 X1 Y1\n"), "p.gcode:2: G5: needs the XY plane (G17)");
  EXPECT_EQ(ReadError("G5 I1 J1 P1 Q1 X1 Y1 Z1\n"),
            "p.gcode:1: G5: Z is not allowed (G5 moves in X and Y only)");
}

TEST(GcodeSplines, QuadraticIsRaisedExactly) {
  const PatchSet set = Read("G0 X1 Y1\nG5.1 X7 Y1 I3 J6\n");
  ASSERT_EQ(set.curves.size(), 1u);
  // The quadratic with control (4, 7): q(t) = (1−t)²·p0 + 2t(1−t)·c + t²·p2.
  for (int k = 0; k <= 10; ++k) {
    const double t = k / 10.0;
    const double u = 1 - t;
    const Point3 want = {u * u * 1 + 2 * t * u * 4 + t * t * 7,
                         u * u * 1 + 2 * t * u * 7 + t * t * 1, 0};
    ExpectPoint(BezierAt(set.curves[0], t), want, 1e-13, "t=" + std::to_string(t));
  }
  EXPECT_EQ(ReadError("G5.1 X1 Y1\n"), "p.gcode:1: G5.1: I and J are both zero or missing");
}

// ---- layers, dispatch -----------------------------------------------------------

TEST(GcodeLayers, ToolChangesAndPauses) {
  const PatchSet set = Read(
      "G1 X1\n"    // 1: "start"
      "T2 M6\n"    // 2
      "G1 X2\n"    // 3: "T2"
      "M0\n"       // 4
      "M1\n"       // 5: an empty layer, left out
      "G1 X3\n");  // 6: "after M1 at line 5"
  EXPECT_EQ(set.layers, (std::vector<std::string>{"start", "T2", "after M1 at line 5"}));
  ASSERT_EQ(set.curves.size(), 3u);
  EXPECT_EQ(set.curves[0].layer, 0);
  EXPECT_EQ(set.curves[1].layer, 1);
  EXPECT_EQ(set.curves[2].layer, 2);
}

TEST(GcodeDispatch, ReadPatchFileTakesTheSuffixes) {
  for (const char* suffix : {".gcode", ".NGC", ".nc", ".G", ".gco"}) {
    SCOPED_TRACE(suffix);
    const std::string path = testing::TempDir() + "/fdsurf_gcode_dispatch" + suffix;
    {
      std::ofstream out(path);
      out << "G21\nG1 X3 Y4\n";
    }
    const PatchSet set = ReadPatchFile(path);
    std::remove(path.c_str());
    ASSERT_EQ(set.curves.size(), 1u);
    ExpectLine(set.curves[0], {0, 0, 0}, {3, 4, 0});
  }
}

}  // namespace
}  // namespace fdsurf::host
