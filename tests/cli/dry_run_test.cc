// SPDX-License-Identifier: MIT
// `fdsurf stream --dry-run` (issue 15, "Knowing before starting"): the job
// through the simulated plotter, nothing opened. Its machine time is the
// figure a real `--device sim` run reports, its distances are the drawing's
// (checked on a square whose length is known by hand), and the progress
// line's machine time left comes from the schedule.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "machine_schedule.h"
#include "tool_run.h"

namespace fdsurf {
namespace {

using test_support::RunResult;
using test_support::ToolTest;

const std::string kTeapot = std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt";
const std::string kTeapotOptions = " --lines 4 --fit 200x150";

class DryRunTest : public ToolTest {
 protected:
  DryRunTest() : ToolTest("fdsurf_dry_run_") {}
};

// The first capture of `pattern` in `text`, or "" (and a failure) when absent.
std::string Find(const std::string& text, const std::string& pattern) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(pattern))) {
    ADD_FAILURE() << "no '" << pattern << "' in:\n" << text;
    return "";
  }
  return m[1].str();
}

TEST_F(DryRunTest, TeapotMachineTimeIsTheSimulatedRunsFigure) {
  const RunResult real = Run("stream '" + kTeapot + "' --device sim" + kTeapotOptions);
  ASSERT_EQ(real.exit_code, 0) << real.err;
  const RunResult dry = Run("stream '" + kTeapot + "' --device sim --dry-run" + kTeapotOptions);
  ASSERT_EQ(dry.exit_code, 0) << dry.err;
  EXPECT_EQ(Find(dry.out, "machine time: ([0-9.]+) s"),
            Find(real.err, "machine: ([0-9.]+) s, [0-9]+ moves"));
  // Pen down and pen up together are the summary's path length (to its
  // rounding to the unit: each figure is rounded to 0.05 mm).
  const double down = std::stod(Find(dry.out, "pen down: ([0-9.]+) mm"));
  const double up = std::stod(Find(dry.out, "pen up \\(travel\\): ([0-9.]+) mm"));
  const double path = std::stod(Find(real.err, "s, [0-9]+ moves, ([0-9]+) mm of path"));
  EXPECT_NEAR(down + up, path, 0.6);
  EXPECT_GT(up, 0);
  // The teapot fitted to 200x150 mm lies on that page.
  const std::string extent = Find(dry.out, "page extent drawn: (.*) mm");
  EXPECT_NE(extent.find("x "), std::string::npos);
  // The same job: as many commands as the real run sent.
  EXPECT_EQ(Find(dry.out, "commands: ([0-9]+);"),
            Find(real.err, "frames sent \\(([0-9]+) commands"));
  // Each pen-down stroke ends in a lift: the simulated run's stroke count.
  EXPECT_EQ(Find(dry.out, "([0-9]+) pen lifts"),
            Find(real.err, "mm of path \\(([0-9]+) pen-down strokes"));
}

// A 100 x 50 mm rectangle drawn along the axes: the step path is exact there
// (no diagonal staircase), so the pen-down distance is the plan's, 300 mm,
// with one pen lift, and the extent is the rectangle's.
TEST_F(DryRunTest, RectanglePenDownIsItsPerimeter) {
  const std::string svg =
      Write("rect.svg",
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"200mm\" height=\"100mm\" "
            "viewBox=\"0 0 200 100\"><path d=\"M 10 20 H 110 V 70 H 10 Z\" "
            "fill=\"none\" stroke=\"black\"/></svg>");
  const RunResult dry = Run("stream '" + svg + "' --origin keep --dry-run");
  ASSERT_EQ(dry.exit_code, 0) << dry.err;
  EXPECT_EQ(Find(dry.out, "pen down: ([0-9.]+) mm"), "300.0");
  EXPECT_EQ(Find(dry.out, "([0-9]+) pen lift"), "1");
  EXPECT_EQ(Find(dry.out, "page extent drawn: x ([0-9.]+\\.\\.[0-9.]+),"), "10..110");
}

TEST_F(DryRunTest, RealDeviceIsNotOpened) {
  const RunResult dry = Run("stream '" + kTeapot +
                            "' --device serial:/dev/does-not-exist --dry-run" + kTeapotOptions);
  ASSERT_EQ(dry.exit_code, 0) << dry.err;
  EXPECT_NE(dry.out.find("nothing sent to serial:/dev/does-not-exist"), std::string::npos)
      << dry.out;
  // The device's tick rate is unknown without HELLO: the assumption is said.
  EXPECT_NE(dry.out.find("40000 Hz ticks, assumed"), std::string::npos) << dry.out;
  const RunResult real = Run("stream '" + kTeapot + "' --device serial:/dev/does-not-exist" +
                             kTeapotOptions + " --connect-timeout 0.1");
  EXPECT_NE(real.exit_code, 0);  // without --dry-run it is opened, and fails
}

TEST_F(DryRunTest, SvgOfTheDrawingWithARealDevice) {
  const std::string svg = (dir_ / "drawn.svg").string();
  const RunResult dry = Run("stream '" + kTeapot + "' --device usb --dry-run" + kTeapotOptions +
                            " --svg '" + svg + "'");
  ASSERT_EQ(dry.exit_code, 0) << dry.err;
  EXPECT_NE(test_support::Slurp(svg).find("<svg"), std::string::npos);
}

// The schedule: commands done by 1, 2, 10, 83 and 379 s of machine time.
host::MachineSchedule FiveCommands() {
  host::MachineSchedule schedule;
  schedule.executed_s = {1, 2, 10, 83, 379};
  return schedule;
}

TEST(TimeLeft, FromTheScheduleAndTheExecutedCount) {
  const host::MachineSchedule schedule = FiveCommands();
  EXPECT_EQ(host::DescribeTimeLeft(schedule, 4), "elapsed 1:23, about 4:56 left");
  const host::TimeLeft start = host::TimeLeftAt(schedule, 0);
  EXPECT_EQ(start.elapsed_s, 0);
  EXPECT_EQ(start.left_s, 379);
  const host::TimeLeft one = host::TimeLeftAt(schedule, 1);
  EXPECT_EQ(one.elapsed_s, 1);
  EXPECT_EQ(one.left_s, 378);
  // More executed than scheduled (a job refitted to the device): the end.
  const host::TimeLeft beyond = host::TimeLeftAt(schedule, 9);
  EXPECT_EQ(beyond.elapsed_s, 379);
  EXPECT_EQ(beyond.left_s, 0);
  EXPECT_EQ(host::DescribeTimeLeft(host::MachineSchedule{}, 3), "elapsed 0:00, about 0:00 left");
}

// Time spent on the command running counts, up to its scheduled length.
TEST(TimeLeft, IntoTheCommandRunning) {
  const host::MachineSchedule schedule = FiveCommands();
  EXPECT_EQ(host::TimeLeftAt(schedule, 3, 30).elapsed_s, 40);  // 10 s + 30 s into the 4th
  EXPECT_EQ(host::TimeLeftAt(schedule, 3, 30).left_s, 339);
  EXPECT_EQ(host::TimeLeftAt(schedule, 3, 500).elapsed_s, 83);  // no further than its end
  EXPECT_EQ(host::TimeLeftAt(schedule, 0, 0.5).elapsed_s, 0.5);
  EXPECT_EQ(host::TimeLeftAt(schedule, 5, 9).elapsed_s, 379);  // nothing after the last
  EXPECT_EQ(host::DescribeTimeLeft(schedule, 4, 60), "elapsed 2:23, about 3:56 left");
}

TEST(TimeLeft, ClockReadings) {
  EXPECT_EQ(host::FormatClock(7.4), "0:07");
  EXPECT_EQ(host::FormatClock(59.6), "1:00");
  EXPECT_EQ(host::FormatClock(3723), "1:02:03");
  EXPECT_EQ(host::FormatClock(-1), "0:00");
}

}  // namespace
}  // namespace fdsurf
