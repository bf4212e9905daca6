// SPDX-License-Identifier: MIT
// `fdsurf serve` (a machine on this host's GPIO lines, served on a pty) and
// the tool's commands reaching it as `--device serial:LINK`, one process
// after another, as a user with a Raspberry Pi plotter would: homing, jogs
// and the pen holding between commands, a killed job resumed from its
// journal, the server stopped mid-job, an output failing. The lines are a
// fake libgpiod with a simulated carriage and min switches
// (tests/support/gpio_serve_fake.cc); the server, its pty, its clock and the
// clients are the real ones. Every process here runs under a timeout.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <thread>

#include "tool_run.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using fdsurf::test_support::RunResult;
using fdsurf::test_support::SecondsSince;
using fdsurf::test_support::Slurp;
using fdsurf::test_support::WaitForExit;

// The lines gpio_serve_fake.cc serves, as its --device.
const std::string kLines = "gpio:gpiochip0:0,1,2,3,4,5:xmin=!6,ymin=!7";
const std::string kLinesArg = "'" + kLines + "'";  // for the shell

// A zigzag of 30 pen-down lines of 10 mm or so (more commands than the
// device queues), as tests/cli/serial_cli_test.cc's.
std::string Zigzag() {
  std::string g = "G21 G90\nG0 X0 Y0\nM3\n";
  for (int i = 1; i <= 30; ++i) {
    g += "G1 X" + std::to_string(i * 2) + " Y" + std::to_string(i % 2 == 0 ? 0 : 10) + "\n";
  }
  return g + "M5\n";
}

class GpioServe : public fdsurf::test_support::ToolTest {
 protected:
  GpioServe() : ToolTest("fdsurf_gpio_serve_") {}

  void SetUp() override {
    ToolTest::SetUp();
    link_ = (dir_ / "fdsurf-gpio").string();
    device_ = " --device 'serial:" + link_ + "' --travel 100x80";
  }
  void TearDown() override {
    if (server_ > 0) StopServer();
    ToolTest::TearDown();
  }

  // Starts the server with the carriage `start` steps from the min
  // switches and waits for its link.
  void StartServer(const std::string& start, const std::string& extra = "") {
    fs::remove(dir_ / "report");
    const std::string command = std::string("exec '") + FDSURF_GPIO_SERVE_FAKE + "' --link '" +
                                link_ + "' --report '" + (dir_ / "report").string() + "' --start " +
                                start + " " + extra + " 2>'" + (dir_ / "server.err").string() + "'";
    server_ = fork();
    if (server_ == 0) {
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    const auto begin = Clock::now();
    while (!fs::exists(link_) && SecondsSince(begin) < 10) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_TRUE(fs::exists(link_))
        << "the server did not publish its link: " << Slurp(dir_ / "server.err");
  }

  // Waits for the server to end (after `signal`, 0: none sent); its exit
  // code in report["exit_code"], and its report.
  std::map<std::string, std::string> StopServer(int signal = SIGTERM) {
    if (signal != 0) kill(server_, signal);
    std::map<std::string, std::string> report;
    report["exit_code"] = std::to_string(WaitForExit(server_, 20));
    server_ = -1;
    std::istringstream lines(Slurp(dir_ / "report"));
    for (std::string key, value; lines >> key >> value;) report[key] = value;
    return report;
  }

  std::string ServerErr() { return Slurp(dir_ / "server.err"); }

  // fdsurf ARGS in the background, its outputs to files; its pid.
  pid_t Spawn(const std::string& args) {
    const std::string command = std::string("exec '") + FDSURF_BINARY + "' " + args + " >'" +
                                (dir_ / "bg.out").string() + "' 2>'" + (dir_ / "bg.err").string() +
                                "' </dev/null";
    const pid_t pid = fork();
    if (pid == 0) {
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    return pid;
  }

  std::string ZigzagJob() {
    const std::string gcode = Write("zigzag.gcode", Zigzag());
    return "stream '" + gcode + "' --view top --fit none --speed 80" + device_;
  }

  std::string link_;
  std::string device_;
  pid_t server_ = -1;
};

// Each command is its own process and its own protocol session; the server
// holds the position, the homing and the motors in between, and on SIGTERM
// leaves the lines safe: pen up, drivers off.
TEST_F(GpioServe, MachineCommandsKeepThePositionHomingAndPenBetweenProcesses) {
  StartServer("800,400");
  RunResult r = Run("machine where" + device_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out,
            "position x 0, y 0 mm (steps 0, 0); pen up; motors off; homed none; endstops "
            "triggered none\n");
  r = Run("machine goto 10 10 --require-homing" + device_);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("not homed (run `fdsurf machine home` first)"), std::string::npos) << r.err;
  r = Run("machine home --rate 40 --backoff 1" + device_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("position x 0, y 0 mm (steps 0, 0); pen up; motors on; homed xy;"),
            std::string::npos)
      << r.out;
  r = Run("machine goto 20 10 --require-homing" + device_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Run("machine jog -5 2 --require-homing" + device_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Run("machine pen down" + device_);
  EXPECT_NE(r.out.find("pen down"), std::string::npos) << r.out;
  // A new session starts with the pen up (as on every device: a session
  // begins with STOP, docs/protocol.md), and the rest as it was.
  r = Run("machine where" + device_);
  EXPECT_EQ(r.out,
            "position x 15, y 12 mm (steps 1200, 960); pen up; motors on; homed xy; endstops "
            "triggered none\n");
  auto report = StopServer();
  EXPECT_EQ(report["exit_code"], "0") << ServerErr();
  // The search (800, 400 steps), the back-off (80 each), then 20, 10 and
  // 5, 2 mm of moves: the carriage stands 80 steps beyond the machine's 0.
  EXPECT_EQ(report["steps_x"], std::to_string(800 + 80 + 1600 + 400));
  EXPECT_EQ(report["steps_y"], std::to_string(400 + 80 + 800 + 160));
  EXPECT_EQ(report["position_x"], std::to_string(80 + 1200));
  EXPECT_EQ(report["position_y"], std::to_string(80 + 960));
  EXPECT_EQ(report["pen_changes"], "2");
  EXPECT_EQ(report["pen_level"], "0");
  EXPECT_EQ(report["enable_level"], "1") << "the drivers were left on (~EN low)";
  EXPECT_NE(ServerErr().find(", at rest, pen lifted, drivers disabled;"), std::string::npos)
      << ServerErr();
}

// A job whose tool is killed (SIGKILL: no STOP, no last journal write) goes
// on from its journal: the points the pen was down on over both runs are
// exactly those of one uninterrupted run on a fresh server.
TEST_F(GpioServe, AKilledJobIsResumedFromItsJournalDrawingTheSamePoints) {
  const std::string job = ZigzagJob();
  StartServer("0,0");
  ASSERT_EQ(Run(job).exit_code, 0);
  auto clean = StopServer();
  ASSERT_NE(clean["drawn_points"], "0");

  StartServer("0,0");
  const std::string journal = (dir_ / "job.journal").string();
  const pid_t pid = Spawn(job + " --journal '" + journal + "'");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  ASSERT_EQ(Slurp(journal).find("executed 34\n"), std::string::npos) << "ended before the kill";
  const RunResult r = Run(job + " --resume '" + journal + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(Slurp(journal).find("executed 34\n"), std::string::npos) << Slurp(journal);
  auto report = StopServer();
  EXPECT_EQ(report["drawn_digest"], clean["drawn_digest"]);
  EXPECT_EQ(report["drawn_points"], clean["drawn_points"]);
  EXPECT_EQ(report["steps_x"], clean["steps_x"]);
  EXPECT_EQ(report["pen_level"], "0");
}

// SIGTERM to the server mid-job: the device decelerates along its path and
// lifts the pen (STOP), the drivers go off, the link goes away, exit 0; the
// client loses its port and says so (exit 3).
TEST_F(GpioServe, StoppingTheServerMidJobLeavesThePenUpAndTheDriversOff) {
  StartServer("0,0");
  const auto start = Clock::now();
  const std::string journal = (dir_ / "stop.journal").string();
  const pid_t pid = Spawn(ZigzagJob() + " --reconnect-timeout 1 --journal '" + journal + "'");
  // Stop once the carriage has left 0, 0 (the journal records the device's
  // position from its status replies), not after a fixed time: under the
  // sanitizers on a loaded machine the client took more than 1.5 s to start.
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  for (std::string text = Slurp(journal); text.find("position ") == std::string::npos ||
                                          text.find("position 0 0 0") != std::string::npos;
       text = Slurp(journal)) {
    ASSERT_LT(Clock::now(), deadline)
        << "the carriage did not move within 20 s: " << Slurp(dir_ / "bg.err");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  auto report = StopServer();
  EXPECT_EQ(report["exit_code"], "0") << ServerErr();
  EXPECT_NE(ServerErr().find("fdsurf serve: stopping the device"), std::string::npos)
      << ServerErr();
  EXPECT_NE(ServerErr().find(", at rest, pen lifted, drivers disabled;"), std::string::npos)
      << ServerErr();
  EXPECT_EQ(report["pen_level"], "0");
  EXPECT_EQ(report["enable_level"], "1");
  EXPECT_NE(report["steps_x"], "0");
  EXPECT_FALSE(fs::exists(link_)) << "the link outlived the server";
  EXPECT_EQ(WaitForExit(pid, 20), 3) << Slurp(dir_ / "bg.err");
  EXPECT_LT(SecondsSince(start), 20);
}

// A pen line that fails mid-job: the server faults, makes the lines safe
// as far as they let it (the pen line still fails: "NOT lifted", said so),
// names the line and exits 3.
TEST_F(GpioServe, AFailingOutputIsExit3NamingTheLineWithTheDriversOff) {
  StartServer("0,0", "--fail-pen-after-steps 200");
  const pid_t pid = Spawn(ZigzagJob() + " --reconnect-timeout 1");
  auto report = StopServer(0);
  EXPECT_EQ(report["exit_code"], "3") << ServerErr();
  EXPECT_NE(ServerErr().find("cannot set line 5 (PEN)"), std::string::npos) << ServerErr();
  EXPECT_NE(ServerErr().find("(pen NOT lifted, drivers disabled)"), std::string::npos)
      << ServerErr();
  EXPECT_EQ(report["enable_level"], "1");
  EXPECT_NE(WaitForExit(pid, 20), 0);
}

TEST_F(GpioServe, BadDevicesAndLinksAreRefusedBeforeAnythingOpens) {
  RunResult r = Run("serve --device serial:/dev/ttyACM0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("serve drives gpio:CHIP:LINES"), std::string::npos) << r.err;
  r = Run("serve --device gpio:gpiochip0:1,2,3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--device: "), std::string::npos) << r.err;
  // A link in a folder that does not exist: nothing is served, exit 2.
  const std::string bad = (dir_ / "no-such-dir" / "tty").string();
  const int status =
      std::system((std::string("'") + FDSURF_GPIO_SERVE_FAKE + "' --link '" + bad + "' --report '" +
                   (dir_ / "report").string() + "' 2>'" + (dir_ / "server.err").string() + "'")
                      .c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 2);
  EXPECT_NE(ServerErr().find(" as " + bad + ": No such file or directory"), std::string::npos)
      << ServerErr();
  EXPECT_NE(ServerErr().find("fdsurf: error: --link: pty: publishing /dev/pts/"), std::string::npos)
      << ServerErr();
}

// Without a server, the machine commands name the way to a gpio machine
// instead of guessing a position that nothing held.
TEST_F(GpioServe, MachineCommandsOnGpioWithoutAServerPointAtServe) {
  setenv("XDG_RUNTIME_DIR", dir_.c_str(), 1);
  const RunResult r = Run("machine where --travel 100x80 --device " + kLinesArg);
  unsetenv("XDG_RUNTIME_DIR");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("start `fdsurf serve --device " + kLines + "`"), std::string::npos) << r.err;
}

// With a server publishing those lines at the default link
// ($XDG_RUNTIME_DIR/fdsurf-gpio), `--device gpio:…` (as a profile would
// give it) goes through the server: machine commands and a journalled job.
TEST_F(GpioServe, GpioDevicesGoThroughTheServerThatHoldsThem) {
  setenv("XDG_RUNTIME_DIR", dir_.c_str(), 1);
  StartServer("800,400");
  EXPECT_EQ(Slurp(link_ + ".device"), kLines + "\n");
  const std::string gpio = " --travel 100x80 --device " + kLinesArg;
  RunResult r = Run("machine home --rate 40 --backoff 1" + gpio);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("fdsurf: " + kLines + " is served at " + link_), std::string::npos) << r.err;
  const std::string gcode = Write("zigzag.gcode", Zigzag());
  const std::string journal = (dir_ / "job.journal").string();
  r = Run("stream '" + gcode + "' --view top --fit none --speed 80 --require-homing --journal '" +
          journal + "'" + gpio);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(Slurp(journal).find("executed 34\n"), std::string::npos) << Slurp(journal);
  r = Run("machine where" + gpio);
  EXPECT_NE(r.out.find("homed xy"), std::string::npos) << r.out;
  auto report = StopServer();
  unsetenv("XDG_RUNTIME_DIR");
  EXPECT_EQ(report["exit_code"], "0") << ServerErr();
  EXPECT_NE(report["drawn_points"], "0");
  EXPECT_FALSE(fs::exists(link_ + ".device")) << "the note outlived the server";
}

}  // namespace
