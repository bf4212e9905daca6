// SPDX-License-Identifier: MIT
// --units in against --units mm (issue 15): every option of plot, render and
// stream whose value carries a length, a speed or an acceleration means the
// same physical thing in both, typed or left to its default. The reference is
// the other unit's run and 25.4 mm per inch, never the code's own conversion.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tool_run.h"

namespace fdsurf::host {
namespace {

using fdsurf::test_support::RunResult;
using fdsurf::test_support::Slurp;

constexpr double kMmPerInch = 25.4;

// Every option whose help says its value is in --units, per command, and the
// test that covers it. A new such option is refused by HelpNamesOnlyCoveredOptions
// until it is listed here with a case.
const std::map<std::string, std::set<std::string>> kCovered = {
    // PlotOptionsAgreeInBothUnits (and PlotDefaultsAgreeInBothUnits).
    {"plot",
     {"--fit", "--margin", "--tolerance", "--quantum", "--pen-up", "--pen-down", "--feed",
      "--plunge-feed", "--travel-rate", "--accel", "--accel-x", "--accel-y", "--accel-z",
      "--junction-deviation"}},
    // render draws with plot's DrawingOptions and PlacePage: the plot cases
    // cover these; RenderDefaultsAgreeInBothUnits checks the defaults.
    {"render", {"--fit", "--margin", "--tolerance", "--quantum"}},
    // StreamOptionsAgreeInBothUnits (and StreamDefaultsInInchesWork).
    {"stream",
     {"--fit", "--margin", "--tolerance", "--step", "--travel", "--speed", "--travel-speed",
      "--accel", "--axis-accel", "--accel-x", "--accel-y", "--accel-z"}},
};

// One G-code program's physical content, in mm.
struct Program {
  std::vector<std::array<double, 2>> points;  // every X Y position, travel too
  // Every G1 segment in the plane: from the position before to the one after.
  std::vector<std::array<std::array<double, 2>, 2>> segments;
  std::set<double> z;      // every Z word
  std::set<double> feeds;  // every F word, mm/min
  double quantum = 0;      // from the header, mm
  double tolerance = 0;    // from the header, mm
  int seconds = -1;        // the header's estimated time
};

// The header's "NAME VALUE UNIT", in mm.
double HeaderMm(const std::string& line, const std::string& name) {
  const std::size_t at = line.find(name + " ");
  if (at == std::string::npos) return 0;
  std::size_t used = 0;
  const double value = std::stod(line.substr(at + name.size() + 1), &used);
  const bool inch = line.compare(at + name.size() + 1 + used, 3, " in") == 0;
  return inch ? value * kMmPerInch : value;
}

double Word(const std::string& line, char letter, bool* found) {
  const std::size_t at = line.find(std::string(" ") + letter);
  *found = at != std::string::npos;
  return *found ? std::stod(line.substr(at + 2)) : 0;
}

Program ReadProgram(const std::string& text) {
  Program p;
  std::istringstream in(text);
  std::string line;
  double scale = 0;
  while (std::getline(in, line)) {
    if (line.rfind("G21", 0) == 0) scale = 1;
    if (line.rfind("G20", 0) == 0) scale = kMmPerInch;
    if (line.rfind("(view ", 0) == 0) {
      p.quantum = HeaderMm(line, "quantum");
      p.tolerance = HeaderMm(line, "tolerance");
    }
    if (const std::size_t t = line.find("(estimated time "); t != std::string::npos) {
      int h = 0;
      int m = 0;
      int s = 0;
      if (std::sscanf(line.c_str() + t + 16, "%d:%d:%d", &h, &m, &s) == 3) {
        p.seconds = h * 3600 + m * 60 + s;
      }
    }
    if (line.rfind("G0", 0) != 0 && line.rfind("G1", 0) != 0) continue;
    bool has_x = false;
    bool has_y = false;
    bool has_z = false;
    bool has_f = false;
    const double x = Word(line, 'X', &has_x);
    const double y = Word(line, 'Y', &has_y);
    const double z = Word(line, 'Z', &has_z);
    const double f = Word(line, 'F', &has_f);
    if (has_x && has_y) {
      const std::array<double, 2> at{x * scale, y * scale};
      if (line.rfind("G1", 0) == 0 && !p.points.empty())
        p.segments.push_back({p.points.back(), at});
      p.points.push_back(at);
    }
    if (has_z) p.z.insert(z * scale);
    if (has_f) p.feeds.insert(f * scale);
  }
  EXPECT_GT(scale, 0) << "no G20/G21 in the program";
  return p;
}

// Printed numbers have 6 significant digits (FormatNumber).
bool SameNumber(double a, double b) { return std::fabs(a - b) <= 1e-5 * std::fabs(b) + 1e-9; }

void ExpectSameNumbers(const std::set<double>& inch, const std::set<double>& mm,
                       const std::string& what) {
  ASSERT_EQ(inch.size(), mm.size()) << what;
  auto i = inch.begin();
  for (auto m = mm.begin(); m != mm.end(); ++m, ++i) {
    EXPECT_TRUE(SameNumber(*i, *m)) << what << ": " << *i << " mm (from inches) vs " << *m;
  }
}

double DistanceToSegment(const std::array<double, 2>& p,
                         const std::array<std::array<double, 2>, 2>& s) {
  const double dx = s[1][0] - s[0][0];
  const double dy = s[1][1] - s[0][1];
  const double length2 = dx * dx + dy * dy;
  const double t =
      length2 == 0
          ? 0
          : std::clamp(((p[0] - s[0][0]) * dx + (p[1] - s[0][1]) * dy) / length2, 0.0, 1.0);
  return std::hypot(p[0] - s[0][0] - t * dx, p[1] - s[0][1] - t * dy);
}

// Every drawn point of `a` (both ends of its G1 segments) lies within
// `slack` of the polyline of `b`.
void ExpectPointsNear(const Program& a, const Program& b, double slack, const std::string& what) {
  ASSERT_FALSE(a.segments.empty()) << what;
  ASSERT_FALSE(b.segments.empty()) << what;
  double worst = 0;
  for (const auto& drawn : a.segments) {
    for (const auto& p : drawn) {
      double nearest = INFINITY;
      for (const auto& s : b.segments) nearest = std::min(nearest, DistanceToSegment(p, s));
      worst = std::max(worst, nearest);
    }
  }
  EXPECT_LE(worst, slack) << what;
}

// The inch and the mm program draw the same: each one's points lie on the
// other's polyline within the other's tolerance plus both quanta's rounding
// (the two sample the curves differently), the same Z heights and feeds, the
// same estimated time within a second (the paths differ by that rounding).
void ExpectSamePhysically(const Program& inch, const Program& mm, const std::string& what) {
  ASSERT_GT(inch.quantum * mm.quantum * inch.tolerance * mm.tolerance, 0) << what;
  const double rounding = std::sqrt(2.0) * 0.51 * (inch.quantum + mm.quantum) + 1e-9;
  ExpectPointsNear(inch, mm, mm.tolerance + rounding, what + ", inch points");
  ExpectPointsNear(mm, inch, inch.tolerance + rounding, what + ", mm points");
  ExpectSameNumbers(inch.z, mm.z, what + ", Z");
  ExpectSameNumbers(inch.feeds, mm.feeds, what + ", F");
  ASSERT_GE(mm.seconds, 0) << what;
  EXPECT_LE(std::abs(inch.seconds - mm.seconds), 1) << what << ": estimated time";
}

class Units : public fdsurf::test_support::ToolTest {
 protected:
  Units() : ToolTest("fdsurf_units_") {}

  static std::string Drawing() { return std::string(FDSURF_EXAMPLES_DIR) + "/bezier-bump.json"; }

  // `fdsurf plot` of the drawing as grbl G-code (which states the time).
  Program Plot(const std::string& units, const std::string& flags) {
    const std::string out = (dir_ / ("plot-" + units + ".gcode")).string();
    const RunResult r = Run("plot '" + Drawing() + "' -q --flavor grbl --mode fixed -o '" + out +
                            "' --units " + units + " " + flags);
    EXPECT_EQ(r.exit_code, 0) << flags << "\n" << r.err;
    return ReadProgram(Slurp(out));
  }

  // The option names of `fdsurf COMMAND --help` whose text says --units.
  std::set<std::string> OptionsInUnits(const std::string& command) {
    const RunResult r = Run(command + " --help");
    EXPECT_EQ(r.exit_code, 0);
    std::map<std::string, std::string> help;
    std::string option;
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);) {
      const std::size_t dash = line.find_first_not_of(' ');
      if (dash == 2 && line.compare(2, 1, "-") == 0) {
        option = line.substr(2, line.find(' ', 2) - 2);
        if (const std::size_t comma = option.find(','); comma != std::string::npos) {
          option = option.substr(comma + 1);
        }
      }
      if (!option.empty()) help[option] += line;
    }
    std::set<std::string> in_units;
    for (const auto& [name, text] : help) {
      if (name != "--units" && text.find("--units") != std::string::npos) in_units.insert(name);
    }
    return in_units;
  }
};

TEST_F(Units, HelpNamesOnlyCoveredOptions) {
  for (const auto& [command, covered] : kCovered) {
    EXPECT_EQ(OptionsInUnits(command), covered) << command;
  }
}

TEST_F(Units, HelpShowsDefaultsAsMillimetresConverted) {
  const RunResult plot = Run("plot --help");
  for (const char* text :
       {"(default 5 mm; converted for --units in)", "(default 1500 mm/min; converted",
        "(default 300 mm/min; converted", "(default 3000 mm/min; converted",
        "(default 0.05 mm; converted", "0.00001 in"}) {
    EXPECT_NE(plot.out.find(text), std::string::npos) << text;
  }
  const RunResult stream = Run("stream --help");
  for (const char* text : {"(default 100 mm/s; converted for --units in)",
                           "(default 2000 mm/s²; converted", "0.000492126 in"}) {
    EXPECT_NE(stream.out.find(text), std::string::npos) << text;
  }
}

TEST_F(Units, PlotDefaultsAgreeInBothUnits) {
  // Page, margin, tolerance, Z heights and feeds all left to their defaults.
  const Program mm = Plot("mm", "");
  const Program inch = Plot("in", "");
  ExpectSamePhysically(inch, mm, "defaults");
  // The defaults are the mm ones: 5 mm up, 1500 mm/min drawing feed.
  EXPECT_TRUE(mm.z.count(5) == 1 && mm.feeds.count(1500) == 1);
}

TEST_F(Units, PlotOptionsAgreeInBothUnits) {
  struct Case {
    const char* option;
    const char* mm;
    const char* inch;
  };
  const Case cases[] = {
      {"--pen-up", "2.54", "0.1"},
      {"--pen-down", "-1.27", "-0.05"},
      {"--feed", "1270", "50"},
      {"--plunge-feed", "254", "10"},
      {"--travel-rate", "254", "10"},
      {"--margin", "25.4", "1"},
      {"--fit", "254x203.2", "10x8"},
      {"--tolerance", "0.0254", "0.001"},
      {"--quantum", "0.00254", "0.0001"},
      {"--accel", "254", "10"},
      {"--junction-deviation", "0.0254", "0.001"},
      {"--accel-x", "127", "5"},
      {"--accel-y", "127", "5"},
      {"--accel-z", "127", "5"},
  };
  for (const Case& c : cases) {
    const Program mm = Plot("mm", std::string(c.option) + " " + c.mm);
    const Program inch = Plot("in", std::string(c.option) + " " + c.inch);
    ExpectSamePhysically(inch, mm, c.option);
  }
}

TEST_F(Units, HpglIsTheSameFileInBothUnits) {
  // HPGL is always plotter units of 0.025 mm: with the defaults (page,
  // margin, tolerance) converted, --units in must write the very same file.
  std::string files[2];
  const char* units[2] = {"mm", "in"};
  for (int k = 0; k < 2; ++k) {
    const std::string out = (dir_ / (std::string("plot-") + units[k] + ".hpgl")).string();
    const RunResult r = Run("plot '" + Drawing() + "' -q -o '" + out + "' --units " + units[k]);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    files[k] = Slurp(out);
  }
  EXPECT_FALSE(files[0].empty());
  EXPECT_TRUE(files[0] == files[1]);
}

TEST_F(Units, RenderDefaultsAgreeInBothUnits) {
  std::string pictures[2];
  const char* units[2] = {"mm", "in"};
  for (int k = 0; k < 2; ++k) {
    const std::string out = (dir_ / (std::string("render-") + units[k] + ".png")).string();
    const RunResult r = Run("render '" + Drawing() + "' -q -o '" + out + "' --units " + units[k]);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    pictures[k] = Slurp(out);
  }
  EXPECT_FALSE(pictures[0].empty());
  // The same page and margin in both: the pictures are the same size (the
  // height within a pixel: 150/25.4 over 200/25.4 is not exactly 0.75).
  const auto be32 = [](const std::string& png, std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) v = v << 8 | static_cast<unsigned char>(png[at + k]);
    return static_cast<long>(v);
  };
  EXPECT_EQ(be32(pictures[1], 16), be32(pictures[0], 16)) << "PNG width";
  EXPECT_LE(std::labs(be32(pictures[1], 20) - be32(pictures[0], 20)), 1) << "PNG height";
}

// The "machine: S s, N moves" and "bound B steps" parts of stream's summary.
std::string MachineSummary(const std::string& err) {
  const std::size_t at = err.find("machine: ");
  const std::size_t moves = err.find(" moves", at);
  const std::size_t bound = err.find("bound ");
  if (at == std::string::npos || moves == std::string::npos || bound == std::string::npos) {
    return "(no summary)";
  }
  return err.substr(at, moves - at) + "; " + err.substr(bound, err.find(' ', bound + 6) - bound);
}

TEST_F(Units, StreamDefaultsInInchesWork) {
  // Before issue 15, 100 in/s was more steps per second than the sim ticks.
  const RunResult inch = Run("stream '" + Drawing() + "' --units in");
  ASSERT_EQ(inch.exit_code, 0) << inch.err;
  EXPECT_NE(inch.err.find(": within"), std::string::npos) << inch.err;
  EXPECT_NE(inch.err.find("): kept"), std::string::npos) << inch.err;
  const RunResult mm = Run("stream '" + Drawing() + "' --units mm");
  ASSERT_EQ(mm.exit_code, 0) << mm.err;
  // The same speed and acceleration, so the same machine time (the inch step
  // is 3.3e-8 from 0.0125 mm: a move or so more or less, not a second).
  const auto seconds = [](const std::string& err) {
    return std::stod(err.substr(err.find("machine: ") + 9));
  };
  EXPECT_NEAR(seconds(inch.err), seconds(mm.err), 0.1);
}

TEST_F(Units, StreamOptionsAgreeInBothUnits) {
  // The same machine and page in both units (each value exactly 25.4x the
  // other): the plotter makes the very same steps, pin for pin.
  const std::string mm_flags =
      "--step 0.0127 --speed 50.8 --travel-speed 101.6 --accel 2540 --axis-accel 3810 --accel-x "
      "3302 --accel-y 3048 --accel-z 4064 --margin 12.7 "
      "--fit 254x203.2 --tolerance 0.127 --travel 254x203.2";
  const std::string inch_flags =
      "--step 0.0005 --speed 2 --travel-speed 4 --accel 100 --axis-accel 150 --accel-x 130 "
      "--accel-y 120 --accel-z 160 --margin 0.5 --fit 10x8 "
      "--tolerance 0.005 --travel 10x8";
  std::string waves[2];
  std::string summaries[2];
  const std::string units[2] = {"mm", "in"};
  const std::string flags[2] = {mm_flags, inch_flags};
  for (int k = 0; k < 2; ++k) {
    const std::string wave = (dir_ / ("wave-" + units[k] + ".txt")).string();
    const RunResult r = Run("stream '" + Drawing() + "' --units " + units[k] + " " + flags[k] +
                            " --waveform '" + wave + "'");
    ASSERT_EQ(r.exit_code, 0) << flags[k] << "\n" << r.err;
    waves[k] = Slurp(wave);
    summaries[k] = MachineSummary(r.err);
  }
  EXPECT_EQ(summaries[1], summaries[0]);
  EXPECT_FALSE(waves[0].empty());
  EXPECT_TRUE(waves[0] == waves[1])
      << "the waveforms differ (" << waves[0].size() << " vs " << waves[1].size() << " bytes)";
}

}  // namespace
}  // namespace fdsurf::host
