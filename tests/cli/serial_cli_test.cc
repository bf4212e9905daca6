// SPDX-License-Identifier: MIT
// `fdsurf stream --device serial:LINK` and `fdsurf ports --probe LINK`
// against the pty device fixture (tests/support/pty_device.cc): the
// firmware on the master side of a real kernel pseudo-terminal, behaving as
// boards do (silent after a reset, hanging up and coming back, never
// answering). Every process here runs under a timeout.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const std::string kJob = std::string("'") + FDSURF_EXAMPLES_DIR + "/bezier-bump.json' --lines 3";

std::string Slurp(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

double SecondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Waits for `pid` at most `timeout_s`, then kills it; its exit code, or -1.
int WaitFor(pid_t pid, double timeout_s) {
  const auto start = Clock::now();
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (SecondsSince(start) > timeout_s) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

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
  void StartDevice(const std::string& options) {
    const std::string ready = (dir_ / "ready").string();
    // A second fixture in one test: the first one's "ready" must not count.
    std::filesystem::remove(ready);
    const std::string command = std::string("exec '") + FDSURF_PTY_DEVICE + "' --link '" + link_ +
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
    EXPECT_EQ(WaitFor(device_, 10), 0);
    device_ = -1;
    std::istringstream lines(Slurp(dir_ / "report"));
    for (std::string key, value; lines >> key >> value;) report[key] = value;
    return report;
  }

  // Starts fdsurf with `args` (its outputs to files); returns its pid.
  pid_t Spawn(const std::string& args) {
    const std::string command = std::string("exec '") + FDSURF_BINARY + "' " + args + " >'" +
                                (dir_ / "stdout").string() + "' 2>'" + (dir_ / "stderr").string() +
                                "' </dev/null";
    const pid_t pid = fork();
    if (pid == 0) {
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    return pid;
  }

  Result Finish(pid_t pid, Clock::time_point start, double timeout_s = 30) {
    const int code = WaitFor(pid, timeout_s);
    return {code, Slurp(dir_ / "stdout"), Slurp(dir_ / "stderr"), SecondsSince(start)};
  }

  Result Run(const std::string& args, double timeout_s = 30) {
    const auto start = Clock::now();
    return Finish(Spawn(args), start, timeout_s);
  }

  Result Stream(const std::string& extra = "") {
    return Run("stream " + kJob + " --device 'serial:" + link_ + "' " + extra);
  }

  fs::path dir_;
  std::string link_;
  pid_t device_ = -1;
};

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
  EXPECT_NE(row.find("fdsurf protocol 2, 2 axes, 20000 Hz ticks, queue 8"), std::string::npos)
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
