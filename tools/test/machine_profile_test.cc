// SPDX-License-Identifier: MIT
// Machine profiles (machine/profile.h) from hand-written TOML: what a good
// file gives, each kind of refusal with its file:line:column and key,
// built-in default < profile < command line, the conversion between the
// profile's units and the command's, the XDG lookup under a temporary HOME,
// and that docs/machines.md and the example profiles follow the schema.
#include "../fdsurf/machine/profile.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fdsurf/host/errors.h"

namespace fdsurf::host {
namespace {

namespace fs = std::filesystem;

// The message ParseMachineProfile refuses `toml` with ("" when it takes it).
std::string RefusalOf(const std::string& toml) {
  try {
    (void)ParseMachineProfile(toml, "m.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(MachineProfile, GoodFileGivesItsValuesWithTheirLines) {
  const MachineProfile p = ParseMachineProfile(
      "# a plotter\n"
      "units = \"in\"\n"
      "device = \"sim\"\n"
      "step = 0.0005\n"
      "travel = [11.81, 8.58]\n"
      "speed = 4\n"
      "pen_delay = 150\n",
      "m.toml");
  EXPECT_EQ(p.units, "in");
  ASSERT_EQ(p.values.size(), 5U);
  EXPECT_STREQ(p.values[0].key->name, "device");
  EXPECT_EQ(p.values[0].text, "sim");
  EXPECT_EQ(p.values[0].line, 3);
  ASSERT_NE(p.Find("travel"), nullptr);
  EXPECT_EQ(p.Find("travel")->line, 5);
  EXPECT_EQ(OptionText(p, *p.Find("travel"), "in"), "11.81x8.58");
  EXPECT_EQ(OptionText(p, *p.Find("pen_delay"), "mm"), "150");  // ms: not a length
  EXPECT_EQ(SourceOf(p, *p.Find("speed")), "m.toml:6");
  EXPECT_EQ(p.Find("accel"), nullptr);
}

TEST(MachineProfile, LengthsConvertToTheCommandsUnits) {
  const MachineProfile in = ParseMachineProfile("units = \"in\"\nspeed = 2\ndwell = 0.5\n", "a");
  EXPECT_EQ(OptionText(in, *in.Find("speed"), "mm"), "50.8");  // 2 × 25.4
  EXPECT_EQ(OptionText(in, *in.Find("speed"), "in"), "2");
  EXPECT_EQ(OptionText(in, *in.Find("dwell"), "mm"), "0.5");  // seconds stay seconds
  const MachineProfile mm = ParseMachineProfile("travel = [254, 127, 25.4]\n", "b");
  EXPECT_EQ(mm.units, "mm");
  EXPECT_EQ(OptionText(mm, *mm.Find("travel"), "in"), "10x5x1");
}

TEST(MachineProfile, SyntaxErrorNamesFileLineAndColumn) {
  const std::string e = RefusalOf("device = \"sim\"\nspeed = = 3\n");
  EXPECT_EQ(e.rfind("m.toml:2:", 0), 0U) << e;
}

TEST(MachineProfile, UnknownKeyIsRefusedWithTheNearestKnownOne) {
  EXPECT_EQ(RefusalOf("\n  sped = 3\n"),
            "m.toml:2:3: key 'sped': not a machine setting (did you mean 'speed'? "
            "docs/machines.md lists them)");
  EXPECT_NE(RefusalOf("pen_dealy = 3\n").find("did you mean 'pen_delay'"), std::string::npos);
  EXPECT_NE(RefusalOf("[servo]\nup = 3\n").find("key 'servo'"), std::string::npos);
  EXPECT_EQ(NearestMachineKey("travle"), "travel");
  EXPECT_EQ(NearestMachineKey("tick_rate"), "tick_hz");
}

TEST(MachineProfile, KeysOfFeaturesToComeSaySo) {
  EXPECT_NE(RefusalOf("home = true\n").find("key 'home': the key is 'homing', a table"),
            std::string::npos);
}

TEST(MachineProfile, OriginIsACornerOfThePage) {
  const MachineProfile p = ParseMachineProfile("origin = \"top-left\"\n", "m.toml");
  ASSERT_NE(p.Find("origin"), nullptr);
  EXPECT_STREQ(p.Find("origin")->key->option, "--machine-origin");
  EXPECT_EQ(RefusalOf("origin = [0, 0]\n"),
            "m.toml:1:10: key 'origin': must be a string, not array");
}

TEST(MachineProfile, AxisLimitsAreKeysOfTheirOwn) {
  const MachineProfile p =
      ParseMachineProfile("units = \"in\"\naccel_x = 100\naccel_y = 80\n", "m.toml");
  ASSERT_NE(p.Find("accel_x"), nullptr);
  EXPECT_STREQ(p.Find("accel_x")->key->option, "--accel-x");
  EXPECT_EQ(OptionText(p, *p.Find("accel_y"), "mm"), "2032");  // 80 in/s², a length per s²
  EXPECT_EQ(p.Find("accel_z"), nullptr);
  EXPECT_EQ(RefusalOf("accel_z = 0\n"), "m.toml:1:11: key 'accel_z': must be above 0, not 0");
}

TEST(MachineProfile, WrongTypeIsRefused) {
  EXPECT_EQ(RefusalOf("speed = \"fast\"\n"),
            "m.toml:1:9: key 'speed': must be a number, not string");
  EXPECT_EQ(RefusalOf("device = 3\n"), "m.toml:1:10: key 'device': must be a string, not integer");
  EXPECT_NE(RefusalOf("pen_delay = 1.5\n").find("must be an integer, not floating-point"),
            std::string::npos);
  EXPECT_NE(RefusalOf("travel = [1, 2, 3, 4]\n").find("must be an array of 2 or 3"),
            std::string::npos);
  EXPECT_NE(RefusalOf("travel = [1, \"2\"]\n").find("must be an array of 2 or 3"),
            std::string::npos);
}

TEST(MachineProfile, OutOfRangeIsRefused) {
  EXPECT_EQ(RefusalOf("accel = -5\n"), "m.toml:1:9: key 'accel': must be above 0, not -5");
  EXPECT_NE(RefusalOf("travel = [300, 0]\n").find("must be above 0, not 0"), std::string::npos);
  EXPECT_EQ(RefusalOf("units = \"cm\"\n"),
            "m.toml:1:9: key 'units': must be \"mm\" or \"in\", not \"cm\"");
  EXPECT_EQ(RefusalOf("speed = 100\nfeed = 1200\n"), "");
}

TEST(MachineProfile, HomingTableGivesItsKeysWithTheirLines) {
  const MachineProfile p = ParseMachineProfile(
      "speed = 20\n[homing]\naxes = \"xy\"\ntoward = [\"min\", \"max\"]\nrate = 4\n"
      "backoff = 0\nrequired = true\n",
      "m.toml");
  ASSERT_EQ(p.values.size(), 6U);
  const ProfileValue* toward = p.Find("homing.toward");
  ASSERT_NE(toward, nullptr);
  EXPECT_EQ(toward->text, "min,max");
  EXPECT_EQ(toward->line, 4);
  EXPECT_EQ(OptionText(p, *p.Find("homing.rate"), "mm"), "4");
  EXPECT_EQ(OptionText(p, *p.Find("homing.backoff"), "mm"), "0");
  EXPECT_EQ(OptionText(p, *p.Find("homing.required"), "mm"), "true");
  EXPECT_EQ(p.Find("homing.axes")->text, "xy");
  EXPECT_EQ(ParseMachineProfile("[homing]\ntoward = \"max\"\n", "m.toml").values[0].text, "max");
  // In inches the lengths convert as the others do.
  const MachineProfile in = ParseMachineProfile("units = \"in\"\n[homing]\nrate = 0.5\n", "m");
  EXPECT_EQ(OptionText(in, in.values[0], "mm"), "12.7");
}

TEST(MachineProfile, HomingTableRefusesWithFileLineAndKey) {
  EXPECT_EQ(RefusalOf("[homing]\n rat = 3\n"),
            "m.toml:2:2: key 'homing.rat': not a machine setting (did you mean 'rate'? "
            "docs/machines.md lists them)");
  EXPECT_NE(RefusalOf("[homing]\nbakoff = 3\n").find("did you mean 'backoff'"), std::string::npos);
  EXPECT_EQ(RefusalOf("[homing]\ntoward = \"up\"\n"),
            "m.toml:2:10: key 'homing.toward': must be \"min\" or \"max\", not \"up\"");
  EXPECT_NE(RefusalOf("[homing]\ntoward = [\"min\", 3]\n").find("must be a string or an array"),
            std::string::npos);
  EXPECT_NE(RefusalOf("[homing]\naxes = \"xq\"\n").find("key 'homing.axes': must name the axes"),
            std::string::npos);
  EXPECT_NE(RefusalOf("[homing]\naxes = \"xx\"\n").find("distinct letters"), std::string::npos);
  EXPECT_EQ(RefusalOf("[homing]\nbackoff = -1\n"),
            "m.toml:2:11: key 'homing.backoff': must be 0 or more, not -1");
  EXPECT_EQ(RefusalOf("[homing]\nrate = 0\n"),
            "m.toml:2:8: key 'homing.rate': must be above 0, not 0");
  EXPECT_EQ(RefusalOf("[homing]\nrequired = \"yes\"\n"),
            "m.toml:2:12: key 'homing.required': must be true or false, not string");
  EXPECT_NE(RefusalOf("homing = true\n").find("key 'homing': must be a table"), std::string::npos);
  // The table's keys are not top-level keys.
  EXPECT_NE(RefusalOf("backoff = 1\n").find("not a machine setting"), std::string::npos);
  EXPECT_NE(RefusalOf("\"homing.rate\" = 1\n").find("not a machine setting"), std::string::npos);
}

TEST(MachineProfile, HomingRequiredSetsTheFlagUnlessTheCommandLineGaveIt) {
  CLI::App app;
  bool required = false;
  app.add_flag("--require-homing", required);
  app.parse(std::vector<std::string>{});
  ApplyMachineProfile(ParseMachineProfile("[homing]\nrequired = true\n", "m.toml"), &app);
  EXPECT_TRUE(required);
  CLI::App given;
  bool given_required = false;
  given.add_flag("--require-homing", given_required);
  given.parse(std::vector<std::string>{"--require-homing"});
  ApplyMachineProfile(ParseMachineProfile("[homing]\nrequired = false\n", "m.toml"), &given);
  EXPECT_TRUE(given_required);
}

// A command with a few of stream's and plot's options, as they declare them.
struct Command {
  CLI::App app;
  std::string units = "mm";
  double speed = 100;
  double accel = 2000;
  int dims = 2;
  std::string step;

  Command() {
    app.add_option("--units", units)->check(CLI::IsMember({"mm", "in"}))->capture_default_str();
    app.add_option("--speed", speed)->capture_default_str();
    app.add_option("--accel", accel)->capture_default_str();
    app.add_option("--dims", dims)->check(CLI::IsMember({2, 3}))->capture_default_str();
    app.add_option("--step", step);
  }
  void Parse(std::vector<std::string> args) {
    std::reverse(args.begin(), args.end());  // CLI11 takes them last first
    app.parse(args);
  }
};

TEST(MachineProfile, CommandLineBeatsProfileBeatsDefault) {
  Command c;
  c.Parse({"--speed", "50"});
  const MachineProfile p = ParseMachineProfile("speed = 200\ndims = 3\n", "m.toml");
  ApplyMachineProfile(p, &c.app);
  EXPECT_EQ(c.speed, 50);    // command line
  EXPECT_EQ(c.dims, 3);      // profile
  EXPECT_EQ(c.accel, 2000);  // default
}

TEST(MachineProfile, AppliedInTheCommandsUnits) {
  Command c;
  c.Parse({"--units", "in"});
  ApplyMachineProfile(ParseMachineProfile("speed = 50.8\naccel = 254\n", "m.toml"), &c.app);
  EXPECT_DOUBLE_EQ(c.speed, 2);
  EXPECT_DOUBLE_EQ(c.accel, 10);
}

std::string ApplyRefusal(const std::string& toml, std::vector<std::string> args = {}) {
  Command c;
  c.Parse(std::move(args));
  try {
    ApplyMachineProfile(ParseMachineProfile(toml, "m.toml"), &c.app);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(MachineProfile, TheOptionsOwnChecksApplyWithThePosition) {
  const std::string dims = ApplyRefusal("\ndims = 4\n");
  EXPECT_EQ(dims.rfind("m.toml:2:8: key 'dims' (4 for --dims): ", 0), 0U) << dims;
  // 0.0125 mm is 0.000492125984... in: not a step of at most 9 decimals.
  const std::string step = ApplyRefusal("step = 0.0125\n", {"--units", "in"});
  EXPECT_EQ(step.rfind("m.toml:1:8: key 'step' (0.000492125984", 0), 0U) << step;
  EXPECT_NE(step.find("more than 9"), std::string::npos) << step;
  // Given on the command line, the profile's value is not even looked at.
  EXPECT_EQ(ApplyRefusal("dims = 4\n", {"--dims", "2"}), "");
}

TEST(MachineProfile, StepsPerUnitGiveTheStep) {
  const MachineProfile mm = ParseMachineProfile("steps_per_mm = 80\n", "m.toml");
  EXPECT_EQ(OptionText(mm, *mm.Find("steps_per_mm"), "mm"), "0.0125");
  // One per axis: --step SX,SY,SZ (a leadscrew Z of 400 steps/mm).
  const MachineProfile axes = ParseMachineProfile("steps_per_mm = [80, 100, 400]\n", "m.toml");
  EXPECT_EQ(OptionText(axes, *axes.Find("steps_per_mm"), "mm"), "0.0125,0.01,0.0025");
  // Steps per inch are per inch whatever the profile's units say.
  const MachineProfile in = ParseMachineProfile("units = \"mm\"\nsteps_per_in = 2000\n", "m.toml");
  EXPECT_EQ(OptionText(in, *in.Find("steps_per_in"), "in"), "0.0005");
  EXPECT_EQ(OptionText(in, *in.Find("steps_per_in"), "mm"), "0.0127");
  Command c;
  c.Parse({});
  ApplyMachineProfile(mm, &c.app);
  EXPECT_EQ(c.step, "0.0125");
}

TEST(MachineProfile, StepsPerUnitThatRepeatTheStepOrAreNoDecimalAreRefused) {
  EXPECT_EQ(RefusalOf("step = 0.01\nsteps_per_mm = 80\n"),
            "m.toml:2:16: key 'steps_per_mm': the step is already given by 'step' on line 1; give "
            "one of step, steps_per_mm, steps_per_in");
  EXPECT_EQ(RefusalOf("steps_per_mm = [80]\n"),
            "m.toml:1:16: key 'steps_per_mm': must be a number, or an array of 2 or 3 numbers "
            "(one per axis), not array");
  EXPECT_EQ(RefusalOf("steps_per_mm = -80\n"),
            "m.toml:1:16: key 'steps_per_mm': must be above 0, not -80");
  // 1/2032 in is no step of 9 decimals: refused with the figure, not rounded.
  const std::string inexact = ApplyRefusal("steps_per_in = 2032\n", {"--units", "in"});
  EXPECT_EQ(inexact.rfind("m.toml:1:16: key 'steps_per_in' (0.000492125984", 0), 0U) << inexact;
  EXPECT_NE(inexact.find("a step of 1/N in for N = 2032 (0.000492125984"), std::string::npos)
      << inexact;
  EXPECT_NE(inexact.find("give 'step' in in"), std::string::npos) << inexact;
}

TEST(MachineProfile, LengthsAreRefusedWhileTheCommandsUnitsAreUnknown) {
  CLI::App app;
  std::string units;  // no default: the units would come from the drawing
  double speed = 100;
  int pen_delay = 100;
  app.add_option("--units", units);
  app.add_option("--speed", speed);
  app.add_option("--pen-delay", pen_delay);
  app.parse(std::vector<std::string>{});
  EXPECT_THROW(ApplyMachineProfile(ParseMachineProfile("speed = 3\n", "m.toml"), &app), InputError);
  ApplyMachineProfile(ParseMachineProfile("pen_delay = 30\n", "m.toml"), &app);
  EXPECT_EQ(pen_delay, 30);  // not a length: nothing to convert
}

// HOME and XDG_CONFIG_HOME pointed at a scratch folder for one test.
class MachineLookup : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("fdsurf_machine_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    for (const char* name : {"HOME", "XDG_CONFIG_HOME"}) {
      const char* v = std::getenv(name);
      saved_.emplace_back(name, v == nullptr ? std::optional<std::string>() : v);
    }
    ::setenv("HOME", dir_.c_str(), 1);
    ::unsetenv("XDG_CONFIG_HOME");
  }
  void TearDown() override {
    for (const auto& [name, value] : saved_) {
      if (value) ::setenv(name.c_str(), value->c_str(), 1);
      if (!value) ::unsetenv(name.c_str());
    }
    fs::remove_all(dir_);
  }
  std::string Put(const fs::path& relative) {
    const fs::path path = dir_ / relative;
    fs::create_directories(path.parent_path());
    std::ofstream(path) << "speed = 1\n";
    return path.string();
  }
  fs::path dir_;
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

TEST_F(MachineLookup, NameIsFoundUnderXdgConfigHomeElseHomeConfig) {
  const std::string home = Put(".config/fdsurf/machines/axi.toml");
  EXPECT_EQ(FindMachineProfile("axi"), home);
  const std::string xdg = Put("xdg/fdsurf/machines/axi.toml");
  ::setenv("XDG_CONFIG_HOME", (dir_ / "xdg").c_str(), 1);
  EXPECT_EQ(FindMachineProfile("axi"), xdg);
  // The spec: a relative XDG_CONFIG_HOME is ignored.
  ::setenv("XDG_CONFIG_HOME", "xdg", 1);
  EXPECT_EQ(FindMachineProfile("axi"), home);
  ::setenv("XDG_CONFIG_HOME", "", 1);
  EXPECT_EQ(FindMachineProfile("axi"), home);
}

TEST_F(MachineLookup, FileIsTakenAsGivenAndMissingOnesAreNamed) {
  const std::string file = Put("elsewhere/my.toml");
  EXPECT_EQ(FindMachineProfile(file), file);
  try {
    (void)FindMachineProfile("ramps");
    FAIL() << "no profile ramps, yet found";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "--machine ramps: no profile " + dir_.string() +
                                         "/.config/fdsurf/machines/ramps.toml");
  }
  EXPECT_THROW((void)FindMachineProfile("nothere.toml"), InputError);
  EXPECT_EQ(LoadMachineProfile(file).Find("speed")->numbers[0], 1);
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(MachineProfile, DocsListEveryKeyOfTheSchema) {
  const std::string docs = ReadText(fs::path(FDSURF_SOURCE_DIR) / "docs" / "machines.md");
  ASSERT_FALSE(docs.empty());
  for (const MachineKey& key : MachineKeys()) {
    EXPECT_NE(docs.find(std::string("| `") + key.name + "` |"), std::string::npos) << key.name;
  }
}

TEST(MachineProfile, ExampleProfilesParse) {
  int seen = 0;
  for (const auto& entry :
       fs::directory_iterator(fs::path(FDSURF_SOURCE_DIR) / "examples" / "machines")) {
    if (entry.path().extension() != ".toml") continue;
    EXPECT_NO_THROW((void)LoadMachineProfile(entry.path().string())) << entry.path();
    ++seen;
  }
  EXPECT_EQ(seen, 3);
}

}  // namespace
}  // namespace fdsurf::host
