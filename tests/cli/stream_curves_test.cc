// SPDX-License-Identifier: MIT
// `fdsurf stream` with a file's curves: straight curves sent as pen-down
// MOVEs, chains ordered by nearest neighbour (a program's order kept), and
// the pause between layers. The job is inspected through the library
// (BuildStreamJob) and the whole command run on the simulated plotter, whose
// check against the exact curves must say "within".
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"
#include "tool_run.h"

namespace fdsurf::host {
namespace {

using fdsurf::test_support::RunResult;

class StreamCurves : public fdsurf::test_support::ToolTest {
 protected:
  StreamCurves() : ToolTest("fdsurf_stream_curves_") {}

  // The job as `fdsurf stream FILE --view top --fit none` builds it
  // (0.0125 mm steps, 5 mm margin).
  static StreamJob JobFor(const std::string& path) {
    const PatchSet set = ReadPatchFile(path);
    ToolpathOptions t;
    t.view = *NamedView("top");
    t.margin = 5;
    t.mode = StepMode::kStepExact;
    return BuildStreamJob(set, t, MachineOptions{}, "mm");
  }
};

// Two lines, a half circle (G2) and a G5 cubic, the pen down by M3.
const char* const kProgram =
    "G21 G90\n"
    "G0 X10 Y10\n"
    "M3\n"
    "G1 X40 Y10\n"
    "G1 X40 Y30\n"
    "G2 X20 Y30 I-10 J0\n"
    "G5 I0 J-5 P5 Q5 X10 Y10\n"
    "M5\n";

std::size_t Count(const std::string& text, const std::string& part) {
  std::size_t n = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

TEST_F(StreamCurves, ProgramLinesAreSentAsPenDownMovesEndingAtTheRoundedEnd) {
  const std::string path = Write("shape.gcode", kProgram);
  const PatchSet set = ReadPatchFile(path);
  const StreamJob job = JobFor(path);
  std::size_t straight = 0;
  for (const Curve& c : set.curves) straight += c.straight ? 1 : 0;
  ASSERT_EQ(straight, 2u);
  ASSERT_EQ(job.curves.size(), set.curves.size());
  bool pen_down = false;
  std::size_t lines = 0;
  std::size_t cubics = 0;
  std::size_t drawn = 0;  // index into job.curves
  for (std::size_t k = 0; k < job.commands.size(); ++k) {
    const protocol::Command& command = job.commands[k];
    if (command.type == protocol::MessageType::kPen) pen_down = command.body.pen.down;
    if (command.type == protocol::MessageType::kCurve) {
      ++cubics;
      EXPECT_FALSE(set.curves[job.curves[drawn++]].straight) << job.labels[k];
    }
    if (command.type != protocol::MessageType::kMove || !pen_down) continue;
    ++lines;
    const Curve& curve = set.curves[job.curves[drawn++]];
    EXPECT_TRUE(curve.straight) << job.labels[k];
    EXPECT_EQ(job.labels[k].rfind("line ", 0), 0u) << job.labels[k];
    // The target is the curve's end in whole steps: the file's end point
    // (the last Bézier control point) through the page map, rounded.
    const Point3 end = job.page.map.Apply(curve.g[3]);
    for (int a = 0; a < 2; ++a) {
      const double exact = end[static_cast<std::size_t>(a)] / job.page.quantum.value();
      EXPECT_LE(std::fabs(command.body.move.target[a] - exact), 0.5 + 1e-9) << job.labels[k];
    }
  }
  EXPECT_EQ(lines, 2u);
  EXPECT_EQ(cubics, set.curves.size() - 2);
  EXPECT_EQ(drawn, set.curves.size());

  const RunResult r = Run("stream '" + path + "' --device sim --view top");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(": within"), std::string::npos) << r.err;
}

// Pen-up travel of a job of one-curve Bézier strokes, in steps, from the
// origin: each pen-up MOVE from where the last stroke ended. A stroke's end
// is taken from the file (not from the device's arithmetic): the end of its
// curve's control polygon away from where the stroke began.
double PenUpTravelSteps(const PatchSet& set, const StreamJob& job) {
  const auto steps = [&](const Point3& p) {
    const Point3 m = job.page.map.Apply(p);
    return std::array<double, 2>{m[0] / job.page.quantum.value(), m[1] / job.page.quantum.value()};
  };
  const auto distance = [](const std::array<double, 2>& a, const std::array<double, 2>& b) {
    return std::hypot(a[0] - b[0], a[1] - b[1]);
  };
  bool pen_down = false;
  std::array<double, 2> at{0, 0};
  std::size_t drawn = 0;
  double travel = 0;
  for (const protocol::Command& command : job.commands) {
    if (command.type == protocol::MessageType::kPen) pen_down = command.body.pen.down;
    if (command.type == protocol::MessageType::kCurve ||
        (command.type == protocol::MessageType::kMove && pen_down)) {
      const Curve& curve = set.curves[job.curves[drawn++]];
      const auto first = steps(curve.g[0]);
      const auto last = steps(curve.g[3]);
      at = distance(at, first) > distance(at, last) ? first : last;
      continue;
    }
    if (command.type != protocol::MessageType::kMove) continue;
    const std::array<double, 2> to{static_cast<double>(command.body.move.target[0]),
                                   static_cast<double>(command.body.move.target[1])};
    travel += distance(at, to);
    at = to;
  }
  return travel;
}

// Four short Bézier strokes far apart, given in a bad order (0, 100, 10, 90
// along X); the second is best entered at its end.
const char* const kScattered = R"({"units": "mm", "curves": [
  {"type": "cubic", "basis": "bezier", "points": [[0,0],[1,2],[2,2],[3,0]]},
  {"type": "cubic", "basis": "bezier", "points": [[103,0],[102,2],[101,2],[100,0]]},
  {"type": "cubic", "basis": "bezier", "points": [[10,0],[11,2],[12,2],[13,0]]},
  {"type": "cubic", "basis": "bezier", "points": [[90,0],[91,2],[92,2],[93,0]]}
]})";

TEST_F(StreamCurves, ScatteredCurvesTravelLessThanInFileOrderAndStayWithinTheBound) {
  const std::string path = Write("scattered.json", kScattered);
  const StreamJob job = JobFor(path);
  // File order by hand, in mm from the origin of the page: with the 5 mm
  // margin the drawing's lower left (0, 0) is at (5, 5); travel to 0, then
  // 3 -> 103, 100 -> 10, 13 -> 90 along X.
  const double first = std::hypot(5.0, 5.0);
  const double file_order_mm = first + 100 + 90 + 77;
  const double travel_mm = PenUpTravelSteps(ReadPatchFile(path), job) * job.page.quantum.value();
  // Nearest neighbour: 0, 10, 90, then the second entered at its 100 end:
  // 3 -> 10, 13 -> 90, 93 -> 100.
  EXPECT_NEAR(travel_mm, first + 7 + 77 + 7, 0.05);
  EXPECT_LT(travel_mm, file_order_mm);
  EXPECT_EQ(job.curves, (std::vector<std::size_t>{0, 2, 3, 1}));

  const RunResult r = Run("stream '" + path + "' --device sim --view top");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(": within"), std::string::npos) << r.err;
}

TEST_F(StreamCurves, HermiteChainsAreReversedExactly) {
  // The second chain is nearer by its end: drawn reversed, it must still
  // be within the bound of the exact curves.
  const std::string path = Write("hermite.json", R"({"units": "mm", "curves": [
    {"type": "hermite-chain", "points": [[0,0],[5,0]], "vectors": [[0,5],[0,-5]]},
    {"type": "hermite-chain", "points": [[60,0],[40,3],[10,0]],
     "vectors": [[0,10],[-5,5],[-3,-10]]}]})");
  const StreamJob job = JobFor(path);
  ASSERT_EQ(job.curves.size(), 3u);
  EXPECT_EQ(job.curves, (std::vector<std::size_t>{0, 2, 1}));
  const RunResult r = Run("stream '" + path + "' --device sim --view top");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(": within"), std::string::npos) << r.err;
}

TEST_F(StreamCurves, AProgramKeepsItsOrder) {
  // The same scattered strokes as G-code lines: a program's order is the user's.
  const std::string path = Write("scattered.gcode",
                                 "G21 G90\nG0 X0 Y0\nM3\nG1 X3 Y0\nM5\n"
                                 "G0 X103 Y0\nM3\nG1 X100 Y0\nM5\n"
                                 "G0 X10 Y0\nM3\nG1 X13 Y0\nM5\n"
                                 "G0 X90 Y0\nM3\nG1 X93 Y0\nM5\n");
  const StreamJob job = JobFor(path);
  EXPECT_EQ(job.curves, (std::vector<std::size_t>{0, 1, 2, 3}));
  const double file_order_mm = std::hypot(5.0, 5.0) + 100 + 90 + 77;
  EXPECT_NEAR(PenUpTravelSteps(ReadPatchFile(path), job) * job.page.quantum.value(), file_order_mm,
              0.05);
}

const char* const kTwoLayers =
    "G21 G90\n"
    "T1 M6\n"
    "G0 X0 Y0\nM3\nG1 X20 Y0\nG1 X20 Y20\nM5\n"
    "T2 M6\n"
    "G0 X30 Y0\nM3\nG2 X50 Y0 I10 J0\nM5\n";

TEST_F(StreamCurves, TwoLayersPauseOnceAfterTheFirstLayerHasRun) {
  const std::string path = Write("layers.gcode", kTwoLayers);
  const StreamJob job = JobFor(path);
  ASSERT_EQ(job.layers.size(), 2u);
  EXPECT_EQ(job.layers[0].name, "T1");
  EXPECT_EQ(job.layers[1].name, "T2");
  // The pen is up when layer 2 begins, and its first command travels.
  const std::size_t boundary = job.layers[1].command;
  ASSERT_LT(boundary, job.commands.size());
  EXPECT_EQ(job.commands[boundary - 1].type, protocol::MessageType::kPen);
  EXPECT_FALSE(job.commands[boundary - 1].body.pen.down);
  EXPECT_EQ(job.commands[boundary].type, protocol::MessageType::kMove);

  // stdin is /dev/null: the message once, then on without waiting, with
  // exactly the commands before layer 2 executed at that moment.
  const RunResult r = Run("stream '" + path + "' --device sim --view top --fit none");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.err, "change the pen"), 1u) << r.err;
  EXPECT_NE(r.err.find("fdsurf: layer 2/2 'T2': change the pen, then press Enter\n"
                       "fdsurf: going on without waiting (stdin is not a terminal); " +
                       std::to_string(boundary) + " of " + std::to_string(job.commands.size()) +
                       " commands executed\n"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(": within"), std::string::npos) << r.err;

  const RunResult no_pause =
      Run("stream '" + path + "' --device sim --view top --fit none --no-pause");
  EXPECT_EQ(no_pause.exit_code, 0) << no_pause.err;
  EXPECT_NE(no_pause.err.find("going on without waiting (--no-pause)"), std::string::npos)
      << no_pause.err;
}

TEST_F(StreamCurves, ASingleLayerDoesNotPause) {
  const RunResult r =
      Run("stream '" + Write("shape.gcode", kProgram) + "' --device sim --view top");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.err, "change the pen"), 0u) << r.err;
}

}  // namespace
// With no --travel the device's travel is the page's, rounded up to whole
// steps: the torus of closed-nets.json reaches 3818.66 steps of depth on a
// 60x60 page, a point at 3819, which a travel rounded down refused.
TEST_F(StreamCurves, TheDefaultTravelHoldsADepthOfNoWholeSteps) {
  const PatchSet set = ReadPatchFile(std::string(FDSURF_EXAMPLES_DIR) + "/closed-nets.json");
  ToolpathOptions t;
  t.view = *NamedView("iso");
  t.fit = std::array<double, 2>{60, 60};
  t.origin = PageOrigin::kCenter;
  t.margin = 5;
  t.dims = 3;
  t.mode = StepMode::kStepExact;
  const MachineOptions machine;
  const StreamJob job = BuildStreamJob(set, t, machine, "mm");
  const double depth_steps = job.page.depth / machine.step.value();
  EXPECT_NE(depth_steps, std::floor(depth_steps));  // the case this is about
  EXPECT_EQ(job.config.travel_steps[2], static_cast<std::int32_t>(std::ceil(depth_steps)));
}

}  // namespace fdsurf::host
