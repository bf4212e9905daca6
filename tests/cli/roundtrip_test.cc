// SPDX-License-Identifier: MIT
// The round trip SVG -> G-code with G5 cubics -> fdsurf's G-code reader gives
// back the SVG's own curves: `fdsurf plot drawing.svg --flavor marlin` keeps
// the page's coordinates (--origin keep is the default for a file with a
// page) and writes every cubic as one G5, whose control points are printed at
// the quantum (0.001 mm), so each control point read back lies within half a
// quantum per axis of the one the SVG reader made.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fdsurf/host/patch_io.h"
#include "tool_run.h"

namespace fdsurf::host {
namespace {

class RoundTrip : public fdsurf::test_support::ToolTest {
 protected:
  RoundTrip() : ToolTest("fdsurf_roundtrip_") {}
};

// A 100 x 80 mm page: a cubic, a smooth continuation, a quadratic, a line
// and an elliptical arc under a rotation.
const char* const kDrawing =
    R"svg(<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="80mm" viewBox="0 0 100 80">
  <path d="M 10 70 C 20 40 40 40 50 60 S 80 70 90 20 Q 60 10 40 15 L 12 30"
        fill="none" stroke="black"/>
  <g transform="rotate(20 50 40)">
    <path d="M 30 40 A 20 10 0 1 1 70 40" fill="none" stroke="red"/>
  </g>
</svg>
)svg";

TEST_F(RoundTrip, SvgToG5AndBackGivesTheSameCurves) {
  const std::string svg = Write("drawing.svg", kDrawing);
  const std::string gcode = (dir_ / "drawing.gcode").string();
  const auto run = Run("plot '" + svg + "' --flavor marlin --no-plan -q -o '" + gcode + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const PatchSet drawn = ReadPatchFile(svg);
  const PatchSet read_back = ReadPatchFile(gcode);
  ASSERT_EQ(read_back.curves.size(), drawn.curves.size());
  ASSERT_GT(drawn.curves.size(), 6u);  // the arc is several cubics
  const double half_quantum = 0.0005 + 1e-9;
  for (std::size_t i = 0; i < drawn.curves.size(); ++i) {
    SCOPED_TRACE(drawn.curves[i].origin);
    ASSERT_EQ(drawn.curves[i].basis, Basis::kBezier);
    ASSERT_EQ(read_back.curves[i].basis, Basis::kBezier);
    for (std::size_t k = 0; k < 4; ++k) {
      for (std::size_t a = 0; a < 2; ++a) {
        EXPECT_NEAR(read_back.curves[i].g[k][a], drawn.curves[i].g[k][a], half_quantum)
            << "control point " << k << " axis " << a;
      }
    }
  }
}

}  // namespace
}  // namespace fdsurf::host
