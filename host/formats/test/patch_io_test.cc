// SPDX-License-Identifier: MIT
// Reading BPT and JSON, and the quantum's exact decimal form.
#include <gtest/gtest.h>

#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quantum.h"
#include "format_test_support.h"

namespace fdsurf::host {
namespace {

using format_test::ErrorOf;

// A string of `count` BPT patches whose control point (i,j) is (i, j, p).
std::string BptText(int count) {
  std::string text = std::to_string(count) + "\n";
  for (int p = 0; p < count; ++p) {
    text += "3 3\n";
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        text += std::to_string(i) + " " + std::to_string(j) + " " + std::to_string(p) + "\n";
      }
    }
  }
  return text;
}

TEST(Bpt, ReadsTheTeapot) {
  const PatchSet set = ReadPatchFile(FDSURF_EXAMPLES_DIR "/teapot.bpt");
  ASSERT_EQ(set.patches.size(), 32u);
  EXPECT_EQ(set.patches[0].basis, Basis::kBezier);
  EXPECT_EQ(set.patches[0].g[0][0], (Point3{1.4, 0.0, 2.4}));
  EXPECT_EQ(set.patches[0].g[3][3], (Point3{0.0, -1.5, 2.4}));
  EXPECT_EQ(set.patches[1].g[0][1], (Point3{-0.784, -1.4, 2.4}));
  EXPECT_NE(set.patches[1].origin.find("teapot.bpt:19"), std::string::npos)
      << set.patches[1].origin;
}

TEST(Bpt, RowIndexIsS) {
  const PatchSet set = ParseBpt(BptText(2), "t.bpt");
  ASSERT_EQ(set.patches.size(), 2u);
  EXPECT_EQ(set.patches[1].g[2][3], (Point3{2, 3, 1}));
}

TEST(Bpt, RefusesMalformedInputNamingTheLine) {
  const std::string good = BptText(1);
  EXPECT_EQ(ErrorOf([] { ParseBpt("", "a.bpt"); }),
            "a.bpt:1: file ends where the number of patches was expected");
  EXPECT_EQ(ErrorOf([] { ParseBpt("x\n", "a.bpt"); }),
            "a.bpt:1: the number of patches 'x' is not a whole number");
  EXPECT_EQ(ErrorOf([] { ParseBpt("0\n", "a.bpt"); }),
            "a.bpt:1: the number of patches must be between 1 and 1000000, got 0");
  EXPECT_EQ(ErrorOf([] { ParseBpt("1\n3 2\n", "a.bpt"); }),
            "a.bpt:2: patch 0: expected the degrees '3 3', found '3 2' (only bicubic patches are "
            "supported)");
  std::string bad_number = good;
  bad_number.replace(bad_number.find("2 1 0"), 5, "2 1x 0");
  EXPECT_EQ(ErrorOf([&] { ParseBpt(bad_number, "a.bpt"); }), "a.bpt:12: y '1x' is not a number");
  std::string nan = good;
  nan.replace(nan.find("3 3 0"), 5, "3 3 nan");
  EXPECT_EQ(ErrorOf([&] { ParseBpt(nan, "a.bpt"); }), "a.bpt:18: z 'nan' is not finite");
  std::string huge = good;
  huge.replace(huge.find("0 0 0"), 5, "1e999 0 0");
  EXPECT_EQ(ErrorOf([&] { ParseBpt(huge, "a.bpt"); }), "a.bpt:3: x '1e999' is out of range");
  EXPECT_EQ(ErrorOf([&] { ParseBpt(BptText(2).substr(0, 60), "a.bpt"); }).substr(0, 6), "a.bpt:");
  std::string two_declared = good;
  two_declared[0] = '2';
  EXPECT_EQ(ErrorOf([&] { ParseBpt(two_declared, "a.bpt"); }),
            "a.bpt:18: file ends after 1 of 2 patches");
  EXPECT_EQ(ErrorOf([&] { ParseBpt(good + "7\n", "a.bpt"); }),
            "a.bpt:19: unexpected data after the last of 1 patches");
}

// A rows × cols net whose point (r, c) is (r, c, z), as JSON text.
std::string NetJson(int rows, int cols, int z) {
  std::string text = "[";
  for (int r = 0; r < rows; ++r) {
    text += r > 0 ? ",[" : "[";
    for (int c = 0; c < cols; ++c) {
      if (c > 0) text += ",";
      text += "[";
      text += std::to_string(r) + "," + std::to_string(c) + "," + std::to_string(z);
      text += "]";
    }
    text += "]";
  }
  text += "]";
  return text;
}

TEST(Json, CutsNetsIntoPatchesInOrder) {
  // A 7×4 Bézier net: 2×1 patches sharing row 3. A 5×6 B-spline net: 2×3.
  const std::string bezier = NetJson(7, 4, 0);
  const std::string spline = NetJson(5, 6, 1);
  const std::string text = R"({"units": "mm", "surfaces": [{"basis": "bezier", "net": )" + bezier +
                           R"(}, {"basis": "bspline", "net": )" + spline + "}]}";
  const PatchSet set = ParseJson(text, "n.json");
  EXPECT_EQ(set.units, "mm");
  ASSERT_EQ(set.patches.size(), 2u + 6u);
  EXPECT_EQ(set.patches[1].g[0][0], (Point3{3, 0, 0}));  // rows 3..6
  EXPECT_EQ(set.patches[1].basis, Basis::kBezier);
  // B-spline patch (a,b) = (1,2) is number 2 + 1·3 + 2 and starts at net[1][2].
  EXPECT_EQ(set.patches[7].g[0][0], (Point3{1, 2, 1}));
  EXPECT_EQ(set.patches[7].basis, Basis::kBSpline);
  EXPECT_EQ(set.patches[7].origin, "n.json: surfaces[1] patch (1,2)");
}

TEST(Json, RefusesMalformedInputNamingTheField) {
  const std::string net4 =
      "[[[0,0,0],[1,0,0],[2,0,0],[3,0,0]],[[0,1,0],[1,1,0],[2,1,0],[3,1,0]],"
      "[[0,2,0],[1,2,0],[2,2,0],[3,2,0]],[[0,3,0],[1,3,0],[2,3,0],[3,3,0]]]";
  const auto doc = [&](const std::string& basis, const std::string& net) {
    return R"({"units": "mm", "surfaces": [{"basis": ")" + basis + R"(", "net": )" + net + "}]}";
  };
  EXPECT_EQ(ErrorOf([&] { ParseJson(doc("nurbs", net4), "f.json"); }),
            "f.json: surfaces[0].basis: unknown basis 'nurbs' (expected bezier, hermite, bspline, "
            "catmull-rom or power)");
  EXPECT_EQ(ErrorOf([&] { ParseJson(doc("hermite", "[[[0,0,0]]]"), "f.json"); }),
            "f.json: surfaces[0].net: a hermite net must be exactly 4x4, got 1x1");
  EXPECT_EQ(ErrorOf([&] { ParseJson(doc("bezier", "[[[0,0,0],[0,0,0]],[[0,0,0]]]"), "f.json"); }),
            "f.json: surfaces[0].net[1]: has 1 points but row 0 has 2");
  std::string bad_point = net4;
  bad_point.replace(bad_point.find("[2,1,0]"), 7, "[2,\"1\",0]");
  EXPECT_EQ(ErrorOf([&] { ParseJson(doc("bezier", bad_point), "f.json"); }),
            "f.json: surfaces[0].net[1][2][1]: must be a number");
  std::string short_point = net4;
  short_point.replace(short_point.find("[2,1,0]"), 7, "[2,1]");
  EXPECT_EQ(ErrorOf([&] { ParseJson(doc("bezier", short_point), "f.json"); }),
            "f.json: surfaces[0].net[1][2]: must be a point [x, y, z]");
  EXPECT_EQ(ErrorOf([&] { ParseJson(doc("bezier", "[[[1e999,0,0]]]"), "f.json"); }),
            "f.json: invalid JSON: number overflow parsing '1e999'");
  EXPECT_EQ(ErrorOf([&] { ParseJson("{\"surfaces\":\n [1,,2]}", "f.json"); }).substr(0, 28),
            "f.json:2:5: invalid JSON: sy");
  EXPECT_EQ(ErrorOf([&] { ParseJson(R"({"units": "mm"})", "f.json"); }),
            "f.json: missing \"surfaces\"");
  EXPECT_EQ(ErrorOf([&] { ParseJson(R"({"units": "furlong", "surfaces": []})", "f.json"); }),
            "f.json: units: must be \"mm\" or \"in\"");
  EXPECT_EQ(
      ErrorOf([&] { ParseJson(R"({"surface": []})", "f.json"); }),
      "f.json: unknown field \"surface\" (expected \"units\", \"surfaces\", \"construct\" and "
      "\"curves\")");
  EXPECT_EQ(
      ErrorOf([&] { ParseJson(R"({"surfaces": [{"basis": "bezier", "nett": []}]})", "f.json"); }),
      "f.json: surfaces[0]: unknown field \"nett\" (expected \"basis\" and \"net\")");
  EXPECT_EQ(ErrorOf([&] { ReadPatchFile("/nonexistent/x.bpt"); }),
            "/nonexistent/x.bpt: cannot open: No such file or directory");
}

TEST(Quantum, ParsesAndPrintsExactDecimals) {
  const Quantum q = Quantum::Parse("0.001");
  EXPECT_EQ(q.mantissa(), 1);
  EXPECT_EQ(q.decimals(), 3);
  EXPECT_EQ(q.Format(1400), "1.400");
  EXPECT_EQ(q.Format(-5), "-0.005");
  EXPECT_EQ(q.Format(0), "0.000");
  EXPECT_EQ(q.Format(-2147483647), "-2147483.647");
  const Quantum q25 = Quantum::Parse("0.0250");
  EXPECT_EQ(q25.mantissa(), 25);
  EXPECT_EQ(q25.decimals(), 3);
  EXPECT_EQ(q25.Format(3), "0.075");
  EXPECT_EQ(Quantum::Parse("2").Format(-7), "-14");
  EXPECT_EQ(Quantum::Parse("2.5").Format(3), "7.5");
  EXPECT_DOUBLE_EQ(Quantum::Parse("0.001").ToQuanta(1.4), 1400.0);
  EXPECT_EQ(ErrorOf([] { Quantum::Parse("0"); }), "quantum: '0' must be greater than zero");
  EXPECT_EQ(ErrorOf([] { Quantum::Parse("-1"); }),
            "quantum: '-1' is not a positive decimal number (like 0.001)");
  EXPECT_EQ(ErrorOf([] { Quantum::Parse("1e-3"); }),
            "quantum: '1e-3' is not a positive decimal number (like 0.001)");
  EXPECT_EQ(ErrorOf([] { Quantum::Parse("0.0000000001"); }),
            "quantum: '0.0000000001' has more than 9 decimals");
  EXPECT_EQ(ErrorOf([] { Quantum::Parse("1.2.3"); }), "quantum: '1.2.3' is not a decimal number");
}

}  // namespace
}  // namespace fdsurf::host
