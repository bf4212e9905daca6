// SPDX-License-Identifier: MIT
// The G-code reader on programs nobody here wrote: LinuxCNC's sample
// programs (Debian's linuxcnc-uspace, GPL-2+; fetched by
// tests/thirdparty/fetch_linuxcnc_ncfiles.sh into FDSURF_LINUXCNC_NCFILES).
// tort.ngc is LinuxCNC's arc torture test: random G2/G3 arcs in all three
// planes, helical, each with a comment "(START END)" giving its start and end
// angles in degrees. Those comments are the reference: the centre is taken
// from the line's own I/J/K words (read here with a regex), the angles from
// the comment, and every drawn arc is checked against them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numbers>
#include <regex>
#include <sstream>

#include "fdsurf/host/gcode_io.h"
#include "format_test_support.h"

namespace fdsurf::host {
namespace {

using format_test::BezierAt;

constexpr double kPi = std::numbers::pi;

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string Dir() {
  const char* dir = std::getenv("FDSURF_LINUXCNC_NCFILES");
  return dir == nullptr ? "" : dir;
}

double Wrap(double degrees) {
  double d = std::fmod(degrees, 360);
  if (d < 0) d += 360;
  return d;
}

double AngleDifference(double a, double b) {
  const double d = Wrap(a - b);
  return std::min(d, 360 - d);
}

TEST(GcodeThirdParty, LinuxCncTortureArcsMatchTheirStatedAngles) {
  const std::string path = Dir() + "/tort.ngc";
  const std::string text = Slurp(path);
  ASSERT_FALSE(text.empty()) << "no " << path
                             << " (run tests/thirdparty/fetch_linuxcnc_ncfiles.sh)";
  GcodeReadOptions options;
  options.pen_z_threshold = 1e9;  // draw every move: the arcs are what is checked
  const PatchSet set = ReadGcode(text, "tort.ngc", options);
  EXPECT_EQ(set.units, "mm");
  std::map<int, std::vector<const Curve*>> by_line;
  for (const Curve& c : set.curves) {
    const std::size_t colon = c.origin.find(':');
    by_line[std::stoi(c.origin.substr(colon + 1))].push_back(&c);
  }
  const std::regex arc_line(R"(G(17|18|19) G([23]) (?:F\d+ )?\((\d+) (\d+)\)(.*))");
  const std::regex offset(R"(([IJK])(-?[0-9.]+))");
  std::istringstream lines(text);
  std::string line;
  int number = 0;
  int checked = 0;
  while (std::getline(lines, line)) {
    ++number;
    std::smatch m;
    if (!std::regex_search(line, m, arc_line)) continue;
    const int plane = std::stoi(m[1]);
    const bool clockwise = m[2] == "2";
    const double start_deg = std::stod(m[3]);
    const double end_deg = std::stod(m[4]);
    const std::string words = m[5];
    std::map<char, double> offsets;
    for (auto it = std::sregex_iterator(words.begin(), words.end(), offset);
         it != std::sregex_iterator(); ++it) {
      offsets[(*it)[1].str()[0]] = std::stod((*it)[2]);
    }
    // LinuxCNC's planes: angles turn from a to b.
    const int a = plane == 17 ? 0 : plane == 18 ? 2 : 1;
    const int b = plane == 17 ? 1 : plane == 18 ? 0 : 2;
    const char letters[3] = {'I', 'J', 'K'};
    const auto& curves = by_line[number];
    ASSERT_FALSE(curves.empty()) << "line " << number;
    const Point3 start = BezierAt(*curves.front(), 0);
    const Point3 end = BezierAt(*curves.back(), 1);
    const double ca = start[a] + offsets[letters[a]];
    const double cb = start[b] + offsets[letters[b]];
    const double radius = std::hypot(offsets[letters[a]], offsets[letters[b]]);
    const auto angle = [&](const Point3& q) {
      return std::atan2(q[b] - cb, q[a] - ca) * 180 / kPi;
    };
    // The comment's angles are whole degrees, cut (not rounded): within 1°.
    // Its G18 angles are not in one convention (the start's from X towards
    // Z, the end's from Z towards X: line 22 says 164 to 135 where its own
    // I, K and end point are at 165° and 315° from X): for G18 only the
    // circle itself is checked.
    const bool comment_usable = plane != 18;
    if (comment_usable)
      EXPECT_LT(AngleDifference(angle(start), start_deg), 1.01)
          << "line " << number << ": " << line;
    if (comment_usable)
      EXPECT_LT(AngleDifference(angle(end), end_deg), 1.01) << "line " << number << ": " << line;
    double turned = 0;
    double previous = angle(start);
    for (const Curve* c : curves) {
      for (int k = 1; k <= 32; ++k) {
        const Point3 q = BezierAt(*c, k / 32.0);
        EXPECT_NEAR(std::hypot(q[a] - ca, q[b] - cb), radius, 1e-5) << "line " << number;
        double step = angle(q) - previous;
        if (step > 180) step -= 360;
        if (step < -180) step += 360;
        turned += step;
        previous = angle(q);
      }
    }
    // The sweep the comment implies, in the arc's direction (equal angles:
    // a full circle).
    double want = clockwise ? Wrap(start_deg - end_deg) : Wrap(end_deg - start_deg);
    if (want == 0) want = 360;
    if (!comment_usable) {
      ++checked;
      continue;
    }
    EXPECT_NEAR(std::fabs(turned), want, 2.02) << "line " << number << ": " << line;
    EXPECT_EQ(turned < 0, clockwise) << "line " << number;
    ++checked;
  }
  EXPECT_EQ(checked, 138);  // every G2/G3 line of the file
}

TEST(GcodeThirdParty, LinuxCncToolLengthOffsetsAreRefused) {
  // cds.ngc (Tom Kramer's circle-diamond-square) uses G43 H1 on line 11.
  const std::string text = Slurp(Dir() + "/cds.ngc");
  ASSERT_FALSE(text.empty());
  try {
    (void)ReadGcode(text, "cds.ngc");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "cds.ngc:11: G43: tool length offsets are not supported");
  }
}

}  // namespace
}  // namespace fdsurf::host
