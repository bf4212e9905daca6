// SPDX-License-Identifier: MIT
// `fdsurf stream --device serial:LINK` and `fdsurf ports --probe LINK`
// against the pty device fixture (tests/support/pty_device.cc): the
// firmware on the master side of a real kernel pseudo-terminal, behaving as
// boards do (silent after a reset, hanging up and coming back, never
// answering), and pausing between layers with stdin a terminal (a second
// pty). Every process here runs under a timeout.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tool_run.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using fdsurf::test_support::SecondsSince;
using fdsurf::test_support::Slurp;
using fdsurf::test_support::WaitForExit;

// One PATCH per patch (`--plan patches`): the link's tests count the job's
// commands as CONFIG and the 4 patches.
const std::string kJob =
    std::string("'") + FDSURF_EXAMPLES_DIR + "/bezier-bump.json' --lines 3 --plan patches";

struct Result {
  int exit_code;
  std::string out;
  std::string err;
  double seconds;
};

class SerialCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fdsurf_serial_cli_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    link_ = (dir_ / "ttyFD0").string();
  }
  void TearDown() override {
    StopDevice();
    fs::remove_all(dir_);
  }

  // Starts the fixture with `options` and waits for its "ready".
  // `binary`: the fixture built as the Arduino Uno's firmware is
  // (FDSURF_PTY_DEVICE_NARROW), or as a full device.
  void StartDevice(const std::string& options, const char* binary = FDSURF_PTY_DEVICE) {
    const std::string ready = (dir_ / "ready").string();
    // A second fixture in one test: the first one's "ready" must not count.
    std::filesystem::remove(ready);
    const std::string command = std::string("exec '") + binary + "' --link '" + link_ +
                                "' --report '" + (dir_ / "report").string() +
                                "' --time-limit-s 40 " + options + " >'" + ready + "'";
    device_ = fork();
    if (device_ == 0) {
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    const auto start = Clock::now();
    while (Slurp(ready).find("ready") == std::string::npos && SecondsSince(start) < 10) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_NE(Slurp(ready).find("ready"), std::string::npos) << "the fixture did not start";
  }

  // Stops the fixture; its report as key -> value.
  std::map<std::string, std::string> StopDevice() {
    std::map<std::string, std::string> report;
    if (device_ <= 0) return report;
    kill(device_, SIGTERM);
    EXPECT_EQ(WaitForExit(device_, 10), 0);
    device_ = -1;
    std::istringstream lines(Slurp(dir_ / "report"));
    for (std::string key, value; lines >> key >> value;) report[key] = value;
    return report;
  }

  // The fixture's report as it is now (SIGUSR1), while it goes on.
  std::map<std::string, std::string> Snapshot() {
    std::map<std::string, std::string> report;
    const fs::path path = dir_ / "report";
    fs::remove(path);
    kill(device_, SIGUSR1);
    const auto start = Clock::now();
    while (!fs::exists(path) && SecondsSince(start) < 5) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::istringstream lines(Slurp(path));
    for (std::string key, value; lines >> key >> value;) report[key] = value;
    return report;
  }

  // Starts fdsurf with `args` (its outputs to files, stdin `stdin_fd` or
  // else /dev/null); returns its pid.
  pid_t Spawn(const std::string& args, int stdin_fd = -1) {
    const std::string command = std::string("exec '") + FDSURF_BINARY + "' " + args + " >'" +
                                (dir_ / "stdout").string() + "' 2>'" + (dir_ / "stderr").string() +
                                "'" + (stdin_fd < 0 ? " </dev/null" : "");
    // A second run in one test: the first one's stderr must not count.
    fs::remove(dir_ / "stderr");
    const pid_t pid = fork();
    if (pid == 0) {
      if (stdin_fd >= 0) dup2(stdin_fd, STDIN_FILENO);
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    return pid;
  }

  Result Finish(pid_t pid, Clock::time_point start, double timeout_s = 30) {
    const int code = WaitForExit(pid, timeout_s);
    return {code, Slurp(dir_ / "stdout"), Slurp(dir_ / "stderr"), SecondsSince(start)};
  }

  Result Run(const std::string& args, double timeout_s = 30) {
    const auto start = Clock::now();
    return Finish(Spawn(args), start, timeout_s);
  }

  Result Stream(const std::string& extra = "") {
    return Run("stream " + kJob + " --device 'serial:" + link_ + "' " + extra);
  }

  // Waits (at most `timeout_s`) until fdsurf's stderr contains `text`.
  bool WaitForStderr(const std::string& text, double timeout_s = 20) {
    const auto start = Clock::now();
    while (Slurp(dir_ / "stderr").find(text) == std::string::npos) {
      if (SecondsSince(start) > timeout_s) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return true;
  }

  fs::path dir_;
  std::string link_;
  pid_t device_ = -1;
};

// A terminal for fdsurf's stdin: the slave of a second pty, so that
// isatty(0) holds; the test types on the master.
struct Terminal {
  int master = -1;
  int slave = -1;
  Terminal() {
    master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) return;
    slave = open(ptsname(master), O_RDWR | O_NOCTTY);
  }
  ~Terminal() {
    if (slave >= 0) close(slave);
    if (master >= 0) close(master);
  }
  Terminal(const Terminal&) = delete;
  Terminal& operator=(const Terminal&) = delete;
  void Type(const std::string& text) const {
    ASSERT_EQ(write(master, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
};

// Two layers (tool changes) of straight lines. By the order stream sends a
// file's curves (docs/protocol.md, MOVE): CONFIG, then layer T1 = travel
// MOVE, pen down, 2 line MOVEs; pen up; layer T2 = travel MOVE, pen down, 1
// line MOVE, pen up. So layer 2 starts at command 6, of 10 in all.
const char* const kTwoLayers =
    "G21 G90\n"
    "T1 M6\n"
    "G0 X0 Y0\nM3\nG1 X20 Y0\nG1 X20 Y20\nM5\n"
    "T2 M6\n"
    "G0 X30 Y0\nM3\nG1 X50 Y0\nM5\n";
constexpr int kBeforeLayer2 = 6;
constexpr int kLayeredCommands = 10;

class SerialPause : public SerialCli {
 protected:
  // fdsurf started with `args` on a fresh terminal (the fixture device is
  // started first with `device_options`).
  struct TerminalRun {
    Terminal terminal;
    Clock::time_point start = Clock::now();
    pid_t pid = -1;
  };
  std::unique_ptr<TerminalRun> SpawnOnTerminal(const std::string& device_options,
                                               const std::string& args) {
    StartDevice(device_options);
    auto run = std::make_unique<TerminalRun>();
    EXPECT_GE(run->terminal.slave, 0);
    if (run->terminal.slave < 0) return nullptr;
    run->start = Clock::now();
    run->pid = Spawn(args, run->terminal.slave);
    return run;
  }

  std::string LayeredStream(const std::string& extra = "") {
    const fs::path path = dir_ / "layers.gcode";
    std::ofstream(path) << kTwoLayers;
    return "stream '" + path.string() + "' --view top --fit none --device 'serial:" + link_ + "' " +
           extra;
  }
  const std::string prompt_ = "fdsurf: layer 2/2 'T2': change the pen, then press Enter\n";
};

// With stdin a terminal the job waits at the layer boundary with exactly
// layer 1 executed, the device at rest with the pen up and nothing moving,
// and after Enter runs layer 2: every command once, the same steps in the
// same order as a run that does not pause.
TEST_F(SerialPause, WaitsForEnterWithNothingOfLayer2Executed) {
  StartDevice("--speedup 20");
  ASSERT_EQ(Run(LayeredStream("--no-pause")).exit_code, 0);
  auto clean = StopDevice();
  ASSERT_EQ(clean["executed"], std::to_string(kLayeredCommands));

  const auto run = SpawnOnTerminal("--speedup 20", LayeredStream());
  ASSERT_TRUE(run);
  ASSERT_TRUE(WaitForStderr(prompt_)) << Slurp(dir_ / "stderr");
  auto paused = Snapshot();
  EXPECT_EQ(paused["executed"], std::to_string(kBeforeLayer2));
  EXPECT_EQ(paused["idle"], "1");
  EXPECT_EQ(paused["pen_down"], "0");
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // still waiting, nothing moves
  auto later = Snapshot();
  EXPECT_EQ(later["executed"], std::to_string(kBeforeLayer2));
  EXPECT_EQ(later["digest"], paused["digest"]);
  EXPECT_EQ(Slurp(dir_ / "stderr").find("going on"), std::string::npos);
  run->terminal.Type("\n");
  const Result r = Finish(run->pid, run->start);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(prompt_ + "fdsurf: layer 2/2 'T2': going on\n"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("3 curves in 2 layers drawn by serial " + link_), std::string::npos)
      << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["executed"], std::to_string(kLayeredCommands));
  EXPECT_EQ(report["accepted"], std::to_string(kLayeredCommands));
  EXPECT_EQ(report["duplicates"], "0");
  EXPECT_EQ(report["hellos"], "2");  // the new session, then the resume after the pause
  EXPECT_EQ(report["digest"], clean["digest"]);
  EXPECT_EQ(report["pen_down"], "0");
}

TEST_F(SerialPause, GoesOnWithoutWaitingWhenStdinIsNotATerminal) {
  StartDevice("--speedup 20");
  const Result r = Run(LayeredStream());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(prompt_ + "fdsurf: going on without waiting (stdin is not a terminal); " +
                       std::to_string(kBeforeLayer2) + " of " + std::to_string(kLayeredCommands) +
                       " commands executed\n"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(StopDevice()["executed"], std::to_string(kLayeredCommands));
}

TEST_F(SerialPause, CtrlCDuringThePauseStopsAndExits130) {
  const auto run = SpawnOnTerminal("--speedup 20", LayeredStream());
  ASSERT_TRUE(run);
  ASSERT_TRUE(WaitForStderr(prompt_)) << Slurp(dir_ / "stderr");
  kill(run->pid, SIGINT);
  const Result r = Finish(run->pid, run->start, 20);
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_NE(r.err.find("fdsurf: stopped: serial " + link_ + " is at rest (idle, pen up) after " +
                       std::to_string(kBeforeLayer2) + " of " + std::to_string(kLayeredCommands) +
                       " commands executed"),
            std::string::npos)
      << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["executed"], std::to_string(kBeforeLayer2));
  EXPECT_EQ(report["stops"], "1");
  EXPECT_EQ(report["pen_down"], "0");
}

// Space pauses: the device comes to rest with the pen up and holds (state
// kPaused, nothing moves); space again resumes, and the job ends with the
// same steps in the same order as a run without a pause. The terminal is
// back in canonical mode with echo afterwards.
TEST_F(SerialPause, SpacePausesAndResumesWithNoStepLostOrRepeated) {
  StartDevice("--speedup 20");
  ASSERT_EQ(Stream().exit_code, 0);
  auto clean = StopDevice();
  ASSERT_EQ(clean["executed"], "5");

  const auto run = SpawnOnTerminal("--speedup 2",
                                   "stream " + kJob + " --device 'serial:" + link_ + "'");  // ~10 s
  ASSERT_TRUE(run);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  run->terminal.Type(" ");
  ASSERT_TRUE(WaitForStderr("fdsurf: paused: space to resume\n")) << Slurp(dir_ / "stderr");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // decelerated, pen lifted
  auto paused = Snapshot();
  EXPECT_EQ(paused["state"], "4");  // kPaused
  EXPECT_EQ(paused["pen_down"], "0");
  EXPECT_EQ(paused["pauses"], "1");
  EXPECT_NE(paused["executed"], "5");
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  auto later = Snapshot();
  EXPECT_EQ(later["step_digest"], paused["step_digest"]);  // holding
  EXPECT_EQ(later["state"], "4");
  run->terminal.Type("p");
  const Result r = Finish(run->pid, run->start);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("fdsurf: paused: space to resume\nfdsurf: resumed\n"), std::string::npos)
      << r.err;
  termios settings{};
  ASSERT_EQ(tcgetattr(run->terminal.slave, &settings), 0);
  EXPECT_NE(settings.c_lflag & ICANON, 0u);
  EXPECT_NE(settings.c_lflag & ECHO, 0u);
  auto report = StopDevice();
  EXPECT_EQ(report["executed"], "5");
  EXPECT_EQ(report["resumes"], "1");
  EXPECT_EQ(report["step_digest"], clean["step_digest"]);
  EXPECT_EQ(report["pen_down"], "0");
}

// The second Ctrl-C, while the first one's STOP is still decelerating the
// device, sends HALT: it stops at once with the pen up and the drivers off,
// the tool says so and exits 130.
TEST_F(SerialCli, ASecondCtrlCHaltsTheDeviceAndExits130) {
  StartDevice("--speedup 1");
  const auto start = Clock::now();
  // A slow deceleration (5 mm/s² from 20 mm/s: 4 s) leaves time for the second.
  const pid_t pid =
      Spawn("stream " + kJob + " --device 'serial:" + link_ + "' --speed 20 --accel 5");
  std::this_thread::sleep_for(std::chrono::milliseconds(3000));
  kill(pid, SIGINT);
  ASSERT_TRUE(WaitForStderr("fdsurf: interrupted: stopping the device")) << Slurp(dir_ / "stderr");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  kill(pid, SIGINT);
  const Result r = Finish(pid, start, 20);
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_NE(r.err.find("fdsurf: halted: serial " + link_ +
                       " stopped at once with the pen lifted and the motors disabled"),
            std::string::npos)
      << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["halts"], "1");
  EXPECT_EQ(report["pen_down"], "0");
  EXPECT_EQ(report["enabled"], "0");
  EXPECT_EQ(report["idle"], "1");
}

// A zigzag of 30 pen-down lines: CONFIG, travel, pen down, 30 MOVEs, pen
// up: more commands than the device queues (8).
std::string Zigzag() {
  std::string g = "G21 G90\nG0 X0 Y0\nM3\n";
  for (int i = 1; i <= 30; ++i) {
    g += "G1 X" + std::to_string(i * 2) + " Y" + std::to_string(i % 2 == 0 ? 0 : 10) + "\n";
  }
  return g + "M5\n";
}

// The tool killed mid-job (SIGKILL: no STOP, no last journal write) and
// `--resume` with the same arguments: the device finishes what it had
// accepted, the rest follows from the first command it had not executed,
// and the union of the two runs steps exactly the steps of one
// uninterrupted run, in order: nothing drawn twice, nothing left out.
TEST_F(SerialCli, AJobKilledMidwayIsResumedFromItsJournalDrawingNothingTwice) {
  const fs::path gcode = dir_ / "zigzag.gcode";
  std::ofstream(gcode) << Zigzag();
  const std::string job = "stream '" + gcode.string() +
                          "' --view top --fit none --device 'serial:" + link_ + "' --speed 40";
  StartDevice("--speedup 20");
  ASSERT_EQ(Run(job).exit_code, 0);
  auto clean = StopDevice();
  ASSERT_EQ(clean["executed"], "34");

  StartDevice("--speedup 1");
  const std::string journal = (dir_ / "job.journal").string();
  const pid_t pid = Spawn(job + " --journal '" + journal + "'");
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  const std::string written = Slurp(journal);
  ASSERT_NE(written.find("fdsurf-journal 1\n"), std::string::npos) << written;
  ASSERT_EQ(written.find("executed 34\n"), std::string::npos) << "the job ended before the kill";
  auto killed = Snapshot();
  EXPECT_NE(killed["idle"], "1");  // the device goes on with what it had accepted

  const Result r = Run(job + " --resume '" + journal + "'", 60);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("commands executed (as the device reports it)"), std::string::npos) << r.err;
  EXPECT_NE(Slurp(journal).find("executed 34\n"), std::string::npos) << Slurp(journal);
  auto report = StopDevice();
  EXPECT_EQ(report["step_digest"], clean["step_digest"]);
  EXPECT_EQ(report["steps_x"], clean["steps_x"]);
  EXPECT_EQ(report["pen_down"], "0");

  // Another job under the same journal is refused before anything is sent.
  StartDevice("--speedup 20");
  const Result other = Run(job + " --pen-delay 50 --resume '" + journal + "'");
  EXPECT_EQ(other.exit_code, 2) << other.err;
  EXPECT_NE(other.err.find(journal + ": the journal is of another job"), std::string::npos)
      << other.err;
  EXPECT_EQ(StopDevice()["hellos"], "0");
}

// A power cut mid-job (the pty device's SIGUSR2: its session, position and
// homing gone, the carriage where it stood): the tool, with a journal, says
// how to go on and exits 3; the user homes the machine and resumes. The
// points drawn over both runs are exactly those of one uninterrupted run
// (nothing left out, nothing off the drawing: the homing found the same
// origin), and what is drawn twice is bounded by what the device executed
// after the journal's last report (docs/protocol.md, "Power loss").
TEST_F(SerialCli, APowerCutMidJobIsResumedFromItsJournalAfterHoming) {
  const fs::path gcode = dir_ / "zigzag.gcode";
  std::ofstream(gcode) << Zigzag();
  const std::string device = " --device 'serial:" + link_ + "'";
  const std::string job = "stream '" + gcode.string() + "' --view top --fit none --speed 40" +
                          device + " --require-homing";
  const std::string home = "machine home --rate 40 --backoff 1 --travel 100x80" + device;
  StartDevice("--speedup 20 --endstops 800,400");
  ASSERT_EQ(Run(home).exit_code, 0);
  ASSERT_EQ(Run(job).exit_code, 0);
  auto clean = StopDevice();
  ASSERT_NE(clean["drawn_points"], "0");

  StartDevice("--speedup 1 --endstops 800,400 --back-after-ms 300");
  ASSERT_EQ(Run(home).exit_code, 0);
  const std::string journal = (dir_ / "job.journal").string();
  const auto start = Clock::now();
  const pid_t pid = Spawn(job + " --journal '" + journal + "' --reconnect-timeout 5");
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  kill(device_, SIGUSR2);
  const Result cut = Finish(pid, start, 30);
  EXPECT_EQ(cut.exit_code, 3) << cut.err;
  EXPECT_NE(cut.err.find("device lost the session on resume"), std::string::npos) << cut.err;
  EXPECT_NE(cut.err.find("fdsurf: the journal " + journal + " records "), std::string::npos)
      << cut.err;
  EXPECT_NE(cut.err.find("home it (fdsurf machine home), then run the same command with "
                         "--resume " +
                         journal),
            std::string::npos)
      << cut.err;
  const std::string written = Slurp(journal);
  ASSERT_EQ(written.find("executed 34\n"), std::string::npos) << "the job ended before the cut";
  const std::size_t at = written.find("executed ");
  ASSERT_NE(at, std::string::npos) << written;
  const int journal_executed = std::stoi(written.substr(at + 9));

  // Without homing the fresh device refuses to move (the job requires it).
  Result r = Run(job + " --resume '" + journal + "'");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("not homed"), std::string::npos) << r.err;
  ASSERT_EQ(Run(home).exit_code, 0);
  r = Run(job + " --resume '" + journal + "'", 60);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("resuming " + journal + ": " + std::to_string(journal_executed) +
                       " of 34 commands executed (as the journal says"),
            std::string::npos)
      << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["power_cuts"], "1");
  EXPECT_EQ(report["drawn_digest"], clean["drawn_digest"]);
  EXPECT_EQ(report["drawn_points"], clean["drawn_points"]);
  EXPECT_EQ(report["pen_down"], "0");
  // Drawn twice: the pen-down steps beyond the clean run's, at most two of
  // the zigzag's strokes (2 by 10 mm, at most 160 + 800 step events at
  // 80 steps/mm: the stroke cut short, and one the device finished after
  // the journal's last write, which comes at most 200 ms after each).
  const long again = std::stol(report["pen_down_steps"]) - std::stol(clean["pen_down_steps"]);
  RecordProperty("pen_down_steps_drawn_twice", static_cast<int>(again));  // 635..664 measured
  EXPECT_GE(again, 0);
  EXPECT_LE(again, 2 * 960) << "pen-down steps drawn twice";
}

// `fdsurf machine` against the pty device with min endstops 800 and 400
// steps (10 and 5 mm) from where the carriage starts: the device keeps its
// position and homing between invocations, as a powered board does.
TEST_F(SerialCli, MachineCommandsHomeJogAndForgetHomingWithTheMotorsOff) {
  StartDevice("--speedup 20 --endstops 800,400");
  const std::string machine = " --device 'serial:" + link_ + "' --travel 100x80";
  Result r = Run("machine where" + machine);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out,
            "position x 0, y 0 mm (steps 0, 0); pen up; motors off; homed none; endstops "
            "triggered none\n");
  r = Run("machine goto 10 10 --require-homing" + machine);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("not homed (run `fdsurf machine home` first)"), std::string::npos) << r.err;
  r = Run("machine home --rate 40 --backoff 1" + machine);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("position x 0, y 0 mm (steps 0, 0); pen up; motors on; homed xy;"),
            std::string::npos)
      << r.out;
  r = Run("machine goto 20 10 --require-homing" + machine);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("position x 20, y 10 mm (steps 1600, 800)"), std::string::npos) << r.out;
  r = Run("machine jog -5 2 --require-homing" + machine);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("position x 15, y 12 mm (steps 1200, 960)"), std::string::npos) << r.out;
  r = Run("machine jog 90 0" + machine);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("machine jog: the target x 105 mm is outside the travel 0..100 mm"),
            std::string::npos)
      << r.err;
  r = Run("machine motors off" + machine);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("motors off; homed none"), std::string::npos) << r.out;
  r = Run("machine goto 20 10 --require-homing" + machine);
  EXPECT_EQ(r.exit_code, 3) << r.out;
  // The search (10, 5 mm), the back-off (1 mm each), then 20, 10 and 5, 2 mm of moves.
  auto report = StopDevice();
  EXPECT_EQ(report["steps_x"], std::to_string(800 + 80 + 1600 + 400));
  EXPECT_EQ(report["steps_y"], std::to_string(400 + 80 + 800 + 160));
}

TEST_F(SerialCli, StreamsAJobThatTheDeviceExecutesOnce) {
  StartDevice("--speedup 20");
  const Result r = Stream();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("4 patches drawn by serial " + link_ + " (115200 baud, 20000 Hz ticks)"),
            std::string::npos)
      << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["executed"], "5");  // CONFIG and 4 patches
  EXPECT_EQ(report["accepted"], "5");
  EXPECT_EQ(report["hellos"], "1");
  EXPECT_EQ(report["idle"], "1");
  EXPECT_EQ(report["pen_down"], "0");
  EXPECT_NE(report["steps_x"], "0");
}

// A device built as the Arduino Uno's firmware (no planner, 64-bit tables
// only) takes the job planned on the host once the lines its tables cannot
// hold are sent in pieces: every command accepted and executed, more of them
// than a full device is sent, and about the same points drawn.
TEST_F(SerialCli, ADeviceOfSixtyFourBitTablesIsSentLongLinesInPieces) {
  StartDevice("--speedup 20");
  const Result full = Stream("--prepare-on-host");
  ASSERT_EQ(full.exit_code, 0) << full.err;
  auto whole = StopDevice();
  StartDevice("--speedup 20", FDSURF_PTY_DEVICE_NARROW);
  const Result narrow = Stream("--prepare-on-host");
  ASSERT_EQ(narrow.exit_code, 0) << narrow.err;
  auto pieces = StopDevice();
  const int more = std::stoi(pieces["executed"]) - std::stoi(whole["executed"]);
  EXPECT_GT(more, 0);
  EXPECT_NE(narrow.err.find("steps 64-bit tables only: " + std::to_string(more) +
                            " more commands send the lines it could not hold in pieces"),
            std::string::npos)
      << narrow.err;
  // The Uno's firmware has no turn caps either: the host says how fast it
  // will run (the speeds themselves: NoTurnCaps.* in the device tests).
  const std::regex capped(
      "has no turn caps: it keeps every axis within its acceleration limit "
      "on any turn by running at ([0-9]+) steps/s at most \\(the job's "
      "limits: ([0-9]+) drawing");
  std::smatch note;
  ASSERT_TRUE(std::regex_search(narrow.err, note, capped)) << narrow.err;
  EXPECT_LT(std::stoul(note[1]), std::stoul(note[2]));
  EXPECT_EQ(full.err.find("turn caps"), std::string::npos) << full.err;
  EXPECT_EQ(pieces["accepted"], pieces["executed"]);
  EXPECT_EQ(pieces["idle"], "1");
  EXPECT_EQ(pieces["pen_down"], "0");
  const double drawn = std::stod(pieces["drawn_points"]);
  EXPECT_NEAR(drawn, std::stod(whole["drawn_points"]), 0.01 * drawn);
  // Without the host's planning the same device says what it needs.
  StartDevice("--speedup 20", FDSURF_PTY_DEVICE_NARROW);
  const Result patches = Stream();
  EXPECT_EQ(patches.exit_code, 3) << patches.err;
  EXPECT_NE(patches.err.find("--prepare-on-host"), std::string::npos) << patches.err;
}

// Opening a Mega's port resets it; the bootloader ignores the line 1-2 s.
TEST_F(SerialCli, ABoardSilentForItsBootloaderIsWaitedFor) {
  StartDevice("--speedup 20 --silent-ms 1500");
  const Result r = Stream();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GE(r.seconds, 1.5);
  auto report = StopDevice();
  EXPECT_EQ(report["executed"], "5");
  EXPECT_EQ(report["hellos"], "1");  // the HELLOs before it were ignored
}

// Unplugged mid-job and back on another pty: resumed, each command once,
// the same steps in the same order as without the unplug.
TEST_F(SerialCli, AHangUpMidJobIsResumedWithEachCommandOnce) {
  StartDevice("--speedup 20");
  ASSERT_EQ(Stream().exit_code, 0);
  auto clean = StopDevice();
  StartDevice("--speedup 20 --hangup-after-bytes 300 --back-after-ms 600");
  const Result r = Stream();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("serial " + link_ + ": hung up"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 reconnects"), std::string::npos) << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["executed"], "5");
  EXPECT_EQ(report["accepted"], "5");
  EXPECT_EQ(report["hellos"], "2");  // the new session, then the resume
  EXPECT_EQ(report["digest"], clean["digest"]);
  EXPECT_EQ(report["steps_x"], clean["steps_x"]);
  EXPECT_EQ(report["steps_y"], clean["steps_y"]);
}

TEST_F(SerialCli, APortLostAndNotBackInTimeIsExit3NamingIt) {
  StartDevice("--speedup 20 --hangup-after-bytes 300 --back-after-ms 100000");
  const Result r = Stream("--reconnect-timeout 1");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_LT(r.seconds, 10);
  EXPECT_NE(
      r.err.find("fdsurf: error: serial " + link_ + ": lost and not back within 1.0 s; gave up"),
      std::string::npos)
      << r.err;
}

TEST_F(SerialCli, ADeviceThatNeverAnswersIsExit3WithinTheConnectTimeout) {
  StartDevice("--never-answer");
  const Result r = Stream("--connect-timeout 1.5");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_GE(r.seconds, 1.5);
  EXPECT_LT(r.seconds, 6);
  EXPECT_NE(r.err.find("fdsurf: error: serial " + link_ + ": no answer to HELLO within 1."),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");
}

TEST_F(SerialCli, AMissingPortIsExit3NamingIt) {
  const Result r = Stream();
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("fdsurf: error: serial " + link_ + ": no such port"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");
}

TEST_F(SerialCli, ABusyPortIsExit3NamingIt) {
  StartDevice("");
  // Another program holding the port the way picocom or pyserial do.
  const int other = open(link_.c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(other, 0);
  ASSERT_EQ(flock(other, LOCK_EX | LOCK_NB), 0);
  const Result r = Stream();
  close(other);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("fdsurf: error: serial " + link_ + ": busy (another program has it open)"),
            std::string::npos)
      << r.err;
}

TEST_F(SerialCli, CtrlCStopsTheDeviceAndExits130) {
  StartDevice("--speedup 1");  // the job takes ~20 s in real time
  const auto start = Clock::now();
  const pid_t pid = Spawn("stream " + kJob + " --device 'serial:" + link_ + "'");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  kill(pid, SIGINT);
  const Result r = Finish(pid, start, 20);
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_LT(r.seconds, 12);
  EXPECT_NE(r.err.find("fdsurf: stopped: serial " + link_ + " is at rest (idle, pen up) after "),
            std::string::npos)
      << r.err;
  auto report = StopDevice();
  EXPECT_EQ(report["stops"], "1");
  EXPECT_EQ(report["idle"], "1");
  EXPECT_EQ(report["pen_down"], "0");
  EXPECT_NE(report["executed"], "5");  // stopped before the end
}

// The device ticks slower than the job's speed needs: the speed is lowered
// to its tick rate, said on stderr, and the job runs.
TEST_F(SerialCli, ASlowDeviceGetsTheSpeedLoweredToItsTickRate) {
  StartDevice("--speedup 20 --tick-hz 5000");
  const Result r = Stream("--speed 100");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: serial " + link_ +
                       " ticks at 5000 Hz, one step per tick at most: "
                       "the speed limit is lowered from 8000 to 5000 steps/s (--speed 100 mm/s "
                       "becomes 62.5 mm/s)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(StopDevice()["executed"], "5");
}

TEST_F(SerialCli, PortsProbeShowsWhatAnswered) {
  StartDevice("");
  const Result r = Run("ports --probe --timeout 1 '" + link_ + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("PORT"), std::string::npos) << r.out;
  const size_t line = r.out.find(link_);
  ASSERT_NE(line, std::string::npos) << r.out;
  const std::string row = r.out.substr(line, r.out.find('\n', line) - line);
  EXPECT_NE(row.find(" pty "), std::string::npos) << row;
  EXPECT_NE(row.find("fdsurf protocol 4, 2 axes, 20000 Hz ticks, queue 8"), std::string::npos)
      << row;
  // The machine's own ports (if any are listed) are shown, not opened.
  std::istringstream rows(r.out);
  for (std::string other; std::getline(rows, other);) {
    if (other.rfind("PORT", 0) == 0 || other.find(link_) != std::string::npos) continue;
    EXPECT_NE(other.find("(not probed)"), std::string::npos) << other;
  }
}

TEST_F(SerialCli, PortsProbeOfASilentPortSaysSoAndExits3) {
  StartDevice("--never-answer");
  const Result r = Run("ports --probe --timeout 0.5 '" + link_ + "'");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("serial " + link_ + ": no answer to HELLO"), std::string::npos) << r.out;
  const Result missing = Run("ports '" + (dir_ / "nope").string() + "'");
  EXPECT_EQ(missing.exit_code, 3);
  EXPECT_EQ(missing.out, "");
  EXPECT_NE(missing.err.find("serial " + (dir_ / "nope").string() + ": no such port"),
            std::string::npos);
}

// ptys are never listed, so no listed port here runs the firmware: the
// error says what was tried (or that nothing is listed).
TEST_F(SerialCli, AutoWithoutAnAnsweringBoardIsExit3SayingWhatWasTried) {
  const Result r = Run("stream " + kJob + " --device serial:auto --connect-timeout 0.5");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_LT(r.seconds, 20);
  const bool tried = r.err.find("serial:auto: no port answered HELLO (tried ") != std::string::npos;
  const bool none = r.err.find("serial:auto: no serial ports listed") != std::string::npos;
  EXPECT_TRUE(tried || none) << r.err;
}

TEST_F(SerialCli, ABadDeviceStringIsExit2) {
  const Result r = Run("stream " + kJob + " --device serial:/dev/ttyACM0:fast");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("baud 'fast' is not a number"), std::string::npos) << r.err;
}

}  // namespace
