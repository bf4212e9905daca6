// SPDX-License-Identifier: MIT
// Machine profiles through the tool (docs/machines.md): stream and plot with
// --machine do what the same settings as flags do, the command line beats
// the profile, `machine show` names where each setting came from, a profile
// is found by name under XDG_CONFIG_HOME, and a bad one stops the command
// with exit 2 before anything is drawn.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "tool_run.h"

namespace fdsurf::test_support {
namespace {

const std::string kTeapot = std::string(FDSURF_EXAMPLES_DIR) + "/teapot.bpt";
const std::string kMachines = std::string(FDSURF_EXAMPLES_DIR) + "/machines";

class MachineCli : public ToolTest {
 protected:
  MachineCli() : ToolTest("fdsurf_machine_cli_") {}

  // `text` with every occurrence of `from` replaced by `to`.
  static std::string Replace(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at)) {
      text.replace(at, from.size(), to);
      at += to.size();
    }
    return text;
  }
};

// Sets (or, for nullptr, unsets) an environment variable the tool inherits,
// until the end of the scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    const char* before = std::getenv(name);
    had_ = before != nullptr;
    if (had_) before_ = before;
    if (value != nullptr) ::setenv(name, value, 1);
    if (value == nullptr) ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (had_) ::setenv(name_.c_str(), before_.c_str(), 1);
    if (!had_) ::unsetenv(name_.c_str());
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::string name_;
  std::string before_;
  bool had_ = false;
};

// sim.toml's settings, as flags.
const char* const kSimFlags =
    " --device sim --dims 2 --step 0.0125 --travel 300x200 --speed 80 --accel 1500"
    " --pen-delay 50 --tick-hz 40000";

TEST_F(MachineCli, StreamWithTheSimProfileDrawsWhatTheSameFlagsDraw) {
  const std::string drawing = "stream '" + kTeapot + "' --fit 240x160 --lines 3 --svg ";
  const std::string a = (dir_ / "profile.svg").string();
  const std::string b = (dir_ / "flags.svg").string();
  const std::string c = (dir_ / "defaults.svg").string();
  const RunResult profile = Run(drawing + "'" + a + "' --machine '" + kMachines + "/sim.toml'");
  const RunResult flags = Run(drawing + "'" + b + "'" + kSimFlags);
  const RunResult defaults = Run(drawing + "'" + c + "'");
  ASSERT_EQ(profile.exit_code, 0) << profile.err;
  ASSERT_EQ(flags.exit_code, 0) << flags.err;
  EXPECT_EQ(Replace(profile.err, a, b), flags.err);
  EXPECT_EQ(Slurp(a), Slurp(b));
  EXPECT_NE(
      profile.err.find(
          "motion limits (80 mm/s, 1500 mm/s² on the path, 3000 mm/s² per axis, pen delay 50 ms)"),
      std::string::npos)
      << profile.err;
  // Without the profile the report differs: the comparison above can fail.
  EXPECT_NE(Replace(defaults.err, c, b), flags.err);
}

// steps_per_mm and accel_x/accel_y draw what --step and --accel-x/-y draw,
// and the summary names each axis's limit.
TEST_F(MachineCli, StepsPerMmAndAxisLimitsAreTheFlagsOfTheSameName) {
  const std::string profile =
      Write("axes.toml", "steps_per_mm = [100, 100]\naccel_x = 5000\naccel_y = 3000\n");
  const std::string drawing = "stream '" + kTeapot + "' --fit 120x80 --lines 2 --waveform ";
  const std::string a = (dir_ / "profile.wave").string();
  const std::string b = (dir_ / "flags.wave").string();
  const RunResult from_profile = Run(drawing + "'" + a + "' --machine '" + profile + "'");
  const RunResult from_flags =
      Run(drawing + "'" + b + "' --step 0.01 --accel-x 5000 --accel-y 3000");
  ASSERT_EQ(from_profile.exit_code, 0) << from_profile.err;
  ASSERT_EQ(from_flags.exit_code, 0) << from_flags.err;
  EXPECT_EQ(Replace(from_profile.err, a, b), from_flags.err);
  EXPECT_EQ(Slurp(a), Slurp(b));
  EXPECT_NE(from_flags.err.find("2000 mm/s² on the path, X 5000, Y 3000 mm/s² per axis"),
            std::string::npos)
      << from_flags.err;
  // Another step draws another waveform: the comparison above can fail.
  const std::string c = (dir_ / "other.wave").string();
  ASSERT_EQ(Run(drawing + "'" + c + "' --step 0.0125 --accel-x 5000 --accel-y 3000").exit_code, 0);
  EXPECT_NE(Slurp(c), Slurp(b));
}

// steps_per_mm = [80, 100]: each axis in its own steps. The dry run's page
// extent is the one-step machine's, the manual commands count each axis in
// its own steps, and a --step list that is not one is refused.
TEST_F(MachineCli, StepsPerMmPerAxisDriveEachAxisInItsOwnSteps) {
  const std::string axes =
      Write("axes.toml", "device = \"sim\"\nsteps_per_mm = [80, 100]\ntravel = [300, 200]\n");
  const std::string one = Write("one.toml", "device = \"sim\"\nsteps_per_mm = 80\n");
  const std::string drawing = "stream '" + kTeapot + "' --fit 120x80 --lines 2 --dry-run ";
  const RunResult per_axis = Run(drawing + "--machine '" + axes + "'");
  const RunResult uniform = Run(drawing + "--machine '" + one + "'");
  ASSERT_EQ(per_axis.exit_code, 0) << per_axis.err;
  ASSERT_EQ(uniform.exit_code, 0) << uniform.err;
  const auto extent = [](const std::string& out) {
    const std::size_t at = out.find("page extent drawn:");
    return out.substr(at, out.find('\n', at) - at);
  };
  EXPECT_EQ(extent(per_axis.out), extent(uniform.out));
  const RunResult where = Run("machine goto 100 50 --machine '" + axes + "' -q");
  ASSERT_EQ(where.exit_code, 0) << where.err;
  EXPECT_EQ(where.out,
            "position x 100, y 50 mm (steps 8000, 5000); pen up; motors on; homed none; "
            "endstops triggered none\n");
  const RunResult bad = Run("stream '" + kTeapot + "' --step 0.0125,0.01,0.0025,1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--step: '0.0125,0.01,0.0025,1' is not S or SX,SY[,SZ]"),
            std::string::npos)
      << bad.err;
}

TEST_F(MachineCli, CommandLineBeatsTheProfile) {
  const RunResult r = Run("stream '" + kTeapot + "' --fit 240x160 --lines 2 --machine '" +
                          kMachines + "/sim.toml' --speed 60 --pen-delay 20");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      r.err.find(
          "motion limits (60 mm/s, 1500 mm/s² on the path, 3000 mm/s² per axis, pen delay 20 ms)"),
      std::string::npos)
      << r.err;
}

TEST_F(MachineCli, PlotGcodeWithTheRampsProfileIsWhatTheSameFlagsWrite) {
  const std::string plot = "plot '" + kTeapot + "' --fit 150x100 --lines 3 --format gcode -q";
  const RunResult profile = Run(plot + " --machine '" + kMachines + "/ramps.toml'");
  const RunResult flags =
      Run(plot +
          " --flavor marlin --pen servo --servo-up 90 --servo-down 30 --servo-index 0"
          " --feed 1500 --travel-rate 3000 --dwell 0.2 --accel 500");
  ASSERT_EQ(profile.exit_code, 0) << profile.err;
  EXPECT_EQ(profile.out, flags.out);
  EXPECT_NE(profile.out.find("M280 P0 S30"), std::string::npos);
}

TEST_F(MachineCli, MachineShowNamesWhereEachSettingCameFrom) {
  const std::string sim = kMachines + "/sim.toml";
  const RunResult r = Run("machine show --machine '" + sim + "' --speed 60");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("profile " + sim + " (its lengths in mm)"), std::string::npos) << r.out;
  EXPECT_NE(
      r.out.find(
          "speed              60                   mm/s       --speed              command line"),
      std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find(
                "accel              1500                 mm/s²      --accel              profile " +
                sim + ":10"),
            std::string::npos)
      << r.out;
  EXPECT_NE(
      r.out.find("feed               1500                 mm/min     --feed               default"),
      std::string::npos)
      << r.out;
  // In inches: the profile's millimetres converted (254 mm = 10 in). A step
  // of 0.0125 mm would be refused: 0.000492... in is no short decimal.
  const std::string mm = Write("mm.toml", "units = \"mm\"\ntravel = [254, 127]\n");
  const RunResult in = Run("machine show --machine '" + mm + "' --units in");
  ASSERT_EQ(in.exit_code, 0) << in.err;
  EXPECT_NE(in.out.find("travel             10x5                 in"), std::string::npos) << in.out;
  EXPECT_EQ(Run("machine show --machine '" + sim + "' --units in").exit_code, 2);
  // The built-in defaults as the commands convert them (1500 mm/min, 100 mm/s).
  const RunResult defaults = Run("machine show --units in");
  ASSERT_EQ(defaults.exit_code, 0) << defaults.err;
  EXPECT_NE(defaults.out.find(
                "feed               59.0551              in/min     --feed               default"),
            std::string::npos)
      << defaults.out;
  EXPECT_NE(defaults.out.find(
                "speed              3.93701              in/s       --speed              default"),
            std::string::npos)
      << defaults.out;
}

TEST_F(MachineCli, ProfileIsFoundByNameUnderXdgConfigHome) {
  Write("mine.toml", "speed = 42\n");
  std::filesystem::create_directories(dir_ / "config" / "fdsurf" / "machines");
  std::filesystem::rename(dir_ / "mine.toml", dir_ / "config/fdsurf/machines/mine.toml");
  const ScopedEnv xdg("XDG_CONFIG_HOME", (dir_ / "config").c_str());
  const RunResult r = Run("machine show --machine mine");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("profile " + (dir_ / "config/fdsurf/machines/mine.toml").string() + ":1"),
            std::string::npos)
      << r.out;
}

TEST_F(MachineCli, ProfileUnderHomeConfigIsShownWithATilde) {
  std::filesystem::create_directories(dir_ / ".config" / "fdsurf" / "machines");
  std::ofstream(dir_ / ".config/fdsurf/machines/mine.toml") << "\nspeed = 42\n";
  const ScopedEnv home("HOME", dir_.string().c_str());
  const ScopedEnv xdg("XDG_CONFIG_HOME", nullptr);
  const RunResult r = Run("machine show --machine mine");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("42                   mm/s       --speed              profile "
                       "~/.config/fdsurf/machines/mine.toml:2"),
            std::string::npos)
      << r.out;
}

TEST_F(MachineCli, BadProfileStopsTheCommandBeforeAnythingIsDrawn) {
  const std::string bad = Write("bad.toml", "speed = 80\nacel = 1500\n");
  const std::string svg = (dir_ / "never.svg").string();
  const RunResult r = Run("stream '" + kTeapot + "' --machine '" + bad + "' --svg '" + svg + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "fdsurf: error: " + bad +
                       ":2:1: key 'acel': not a machine setting (did you mean 'accel'? "
                       "docs/machines.md lists them)\n");
  EXPECT_FALSE(std::filesystem::exists(svg));
  const RunResult missing = Run("plot '" + kTeapot + "' --machine '" + dir_.string() + "/no.toml'");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("no profile file"), std::string::npos) << missing.err;
}

// The profile's [homing] table drives `machine home`; its flags override it.
TEST_F(MachineCli, MachineHomeTakesTheProfilesHomingTable) {
  const std::string p = Write("h.toml",
                              "travel = [100, 80]\n[homing]\naxes = \"x\"\nrate = 4\n"
                              "backoff = 2\n");
  const RunResult r = Run("machine home --machine '" + p + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The sim carriage stops `backoff` from the switch it homed against; Y
  // (not homed) stays a quarter of the travel away.
  EXPECT_NE(r.out.find("the carriage stands x 2, y 20 mm from its min switches"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("homed x;"), std::string::npos) << r.out;
  const RunResult flags = Run("machine home --machine '" + p + "' --axes xy --backoff 1.5");
  ASSERT_EQ(flags.exit_code, 0) << flags.err;
  EXPECT_NE(flags.out.find("stands x 1.5, y 1.5 mm"), std::string::npos) << flags.out;
  EXPECT_NE(flags.out.find("homed xy;"), std::string::npos) << flags.out;
  // A rate the device cannot step names the profile's key and line.
  const std::string fast = Write("fast.toml", "travel = [100, 80]\n[homing]\nrate = 900\n");
  const RunResult refused = Run("machine home --machine '" + fast + "'");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("homing.rate (" + fast + ":3): 900 mm/s is not between"),
            std::string::npos)
      << refused.err;
  // One direction per axis: two for a 2-axis machine, not three.
  const RunResult three = Run("machine home --machine '" + p + "' --toward min,min,max");
  EXPECT_EQ(three.exit_code, 2);
  EXPECT_NE(three.err.find("--toward: 'min,min,max' gives 3 directions for 2 axes"),
            std::string::npos)
      << three.err;
}

TEST_F(MachineCli, BadHomingTableStopsMachineHome) {
  const std::string p = Write("h.toml", "travel = [100, 80]\n[homing]\ntoward = \"left\"\n");
  const RunResult r = Run("machine home --machine '" + p + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "fdsurf: error: " + p +
                       ":3:10: key 'homing.toward': must be \"min\" or \"max\", not \"left\"\n");
}

// homing.required puts CONFIG's flag on the stream: the simulated device,
// never homed, refuses the first motion and the message says what to do.
TEST_F(MachineCli, StreamOnAMachineThatRequiresHomingSaysToHome) {
  const std::string p = Write("h.toml", "[homing]\nrequired = true\n");
  const RunResult r = Run("stream '" + kTeapot + "' --lines 2 --quiet --machine '" + p + "'");
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("not homed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("run `fdsurf machine home`"), std::string::npos) << r.err;
  const RunResult plain = Run("stream '" + kTeapot + "' --lines 2 --quiet");
  EXPECT_EQ(plain.exit_code, 0) << plain.err;
  const RunResult flag = Run("stream '" + kTeapot + "' --lines 2 --quiet --require-homing");
  EXPECT_EQ(flag.exit_code, 3) << flag.err;
}

TEST_F(MachineCli, MachineShowPrintsTheHomingSettingsAndTheirSource) {
  const RunResult r = Run("machine show --machine '" + kMachines + "/ramps.toml' --rate 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      r.out.find(
          "homing.rate        3                    mm/s       --rate               command line"),
      std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("homing.toward      min"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("false                -          --require-homing     profile " + kMachines +
                       "/ramps.toml:"),
            std::string::npos)
      << r.out;
  const RunResult defaults = Run("machine show");
  ASSERT_EQ(defaults.exit_code, 0) << defaults.err;
  EXPECT_NE(defaults.out.find("homing.backoff     1 "), std::string::npos) << defaults.out;
  EXPECT_NE(defaults.out.find("homing.axes        all"), std::string::npos) << defaults.out;
}

// The gpio device's ENDSTOPS part is checked before any line is opened:
// a bad one is bad input (exit 2) naming the switch, a good one gets as far
// as opening the chip (none on this machine: exit 3).
TEST_F(MachineCli, GpioEndstopsAreCheckedBeforeAnyLineIsOpened) {
  const std::string stream = "stream '" + kTeapot + "' --lines 2 --quiet --device ";
  const RunResult reused = Run(stream + "'gpio:gpiochip0:17,27,22,23,24,25:xmin=24'");
  EXPECT_EQ(reused.exit_code, 2);
  EXPECT_EQ(reused.err,
            "fdsurf: error: --device: endstop xmin: line 24 is also an output in LINES\n");
  const RunResult unknown = Run(stream + "'gpio:gpiochip0:17,27,22,23,24,25:xmin=!5,xlim=6'");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("endstop 'xlim=6' is not AXISEND"), std::string::npos) << unknown.err;
  const RunResult good = Run(stream + "'gpio:fdsurf-no-chip:17,27,22,23,24,25:xmin=!5,ymin=!6'");
  EXPECT_EQ(good.exit_code, 3) << good.err;
  EXPECT_NE(good.err.find("fdsurf-no-chip"), std::string::npos) << good.err;
}

// Machine commands on a gpio device with no `fdsurf serve` holding it are
// refused before any line is opened (nothing would hold the position
// between invocations) and say what to start; a usb device that is not
// there is a device error naming it.
TEST_F(MachineCli, MachineCommandsRefuseGpioAndNameAMissingUsbDevice) {
  const RunResult gpio = Run("machine where --travel 100x80 --device gpio:gpiochip0:1,2,3,4,5,6");
  EXPECT_EQ(gpio.exit_code, 2);
  EXPECT_NE(gpio.err.find("nothing holds this machine's position between commands: start "
                          "`fdsurf serve --device gpio:gpiochip0:1,2,3,4,5,6`"),
            std::string::npos)
      << gpio.err;
  const RunResult usb = Run("machine where --travel 100x80 --device usb:1209:fd5f");
  EXPECT_EQ(usb.exit_code, 3) << usb.err;
  EXPECT_NE(usb.err.find("usb 1209:fd5f: no such device"), std::string::npos) << usb.err;
}

}  // namespace
}  // namespace fdsurf::test_support
