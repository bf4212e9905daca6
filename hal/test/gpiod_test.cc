// SPDX-License-Identifier: MIT
// GpiodOutputs against a fake libgpiod (fake_gpiod.cc, linked with
// -Wl,--wrap): the exact line values after each call and every error message.
#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "fake_gpiod.h"
#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/gpiod_outputs.h"

namespace fdsurf::hal {
namespace {

using testing::FakeGpio;
using testing::g_fake_gpio;
using Log = std::vector<std::string>;

class GpiodTest : public ::testing::Test {
 protected:
  GpiodTest() {
    g_fake_gpio = &fake_;
    chip_ = &fake_.AddChip("gpiochip0", 32);
  }
  ~GpiodTest() override { g_fake_gpio = nullptr; }

  // Parses `spec` and opens it; the log then starts after the requests.
  std::unique_ptr<GpiodOutputs> OpenSpec(const std::string& spec, GpiodConfig config = {}) {
    std::string error;
    EXPECT_TRUE(ParseGpioDevice(spec, &config, &error)) << error;
    std::unique_ptr<GpiodOutputs> outputs;
    EXPECT_EQ(GpiodOutputs::Open(config, &outputs, &error), IoStatus::kOk) << error;
    fake_.log.clear();
    fake_.set_times_us.clear();
    return outputs;
  }

  IoStatus OpenFails(const std::string& spec, std::string* error, GpiodConfig config = {}) {
    EXPECT_TRUE(ParseGpioDevice(spec, &config, error)) << *error;
    std::unique_ptr<GpiodOutputs> outputs;
    const IoStatus status = GpiodOutputs::Open(config, &outputs, error);
    EXPECT_EQ(outputs, nullptr);
    return status;
  }

  FDSURF_NODISCARD int Value(unsigned offset) const { return chip_->lines[offset].value; }

  FakeGpio fake_;
  testing::FakeGpioChip* chip_;
};

TEST_F(GpiodTest, OpenRequestsEveryLineInactive) {
  GpiodConfig config;
  std::string error;
  ASSERT_TRUE(ParseGpioDevice("gpio:gpiochip0:17,27,22,23,24,25", &config, &error)) << error;
  std::unique_ptr<GpiodOutputs> outputs;
  ASSERT_EQ(GpiodOutputs::Open(config, &outputs, &error), IoStatus::kOk) << error;
  // STEP low, DIR low (positive), ~EN high (motors off), pen low (up).
  // The STEP lines in one request, so that one call sets them all.
  EXPECT_EQ(fake_.log,
            (Log{"lookup gpiochip0", "request 27 fdsurf 0", "request 23 fdsurf 0",
                 "request 24 fdsurf 1", "request 25 fdsurf 0", "request 17,22 fdsurf 0,0"}));
  EXPECT_EQ(static_cast<StepDirOutputs&>(*outputs).axes(), 2);
  EXPECT_STREQ(outputs->LastError(), "");
}

// PEN as pwmN.M: a servo on a PWM channel, which the caller drives; no pen
// line is requested, and SetPen() here changes no line.
TEST_F(GpiodTest, APwmPenRequestsNoPenLine) {
  GpiodConfig config;
  std::string error;
  ASSERT_TRUE(ParseGpioDevice("gpio:gpiochip0:17,27,22,23,24,pwm2.1", &config, &error)) << error;
  EXPECT_FALSE(config.has_pen_line);
  EXPECT_EQ(config.pen_pwm_chip, 2u);
  EXPECT_EQ(config.pen_pwm_channel, 1u);
  std::unique_ptr<GpiodOutputs> outputs;
  ASSERT_EQ(GpiodOutputs::Open(config, &outputs, &error), IoStatus::kOk) << error;
  // The STEP lines (17, 22) last, as one request.
  EXPECT_EQ(fake_.log, (Log{"lookup gpiochip0", "request 27 fdsurf 0", "request 23 fdsurf 0",
                            "request 24 fdsurf 1", "request 17,22 fdsurf 0,0"}));
  fake_.log.clear();
  EXPECT_EQ(static_cast<PenOutput&>(*outputs).SetPen(true), IoStatus::kOk);
  EXPECT_TRUE(fake_.log.empty());
  for (const char* bad :
       {"gpio:gpiochip0:17,27,22,23,24,pwm0", "gpio:gpiochip0:17,27,22,23,24,pwmx.1",
        "gpio:gpiochip0:17,27,22,23,24,pwm0."}) {
    EXPECT_FALSE(ParseGpioDevice(bad, &config, &error)) << bad;
    EXPECT_NE(error.find("is not a PWM channel (pwmCHIP.CHANNEL"), std::string::npos) << error;
  }
}

TEST_F(GpiodTest, StepGoesHighThenLowForAtLeastThePulseWidth) {
  GpiodConfig config;
  config.min_pulse_us = 50;
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25", config);
  StepDirOutputs& steps = *outputs;
  ASSERT_EQ(steps.Step(0b01), IoStatus::kOk);
  EXPECT_EQ(fake_.log, (Log{"set 17=1,22=0", "set 17=0,22=0"}));
  ASSERT_EQ(fake_.set_times_us.size(), 2u);
  EXPECT_GE(fake_.set_times_us[1] - fake_.set_times_us[0], 50u);
  EXPECT_EQ(Value(17), 0);

  fake_.log.clear();
  ASSERT_EQ(steps.Step(0b11), IoStatus::kOk);
  // A diagonal step: both edges of both axes in one call each.
  EXPECT_EQ(fake_.log, (Log{"set 17=1,22=1", "set 17=0,22=0"}));
  ASSERT_EQ(fake_.set_times_us.size(), 4u);
  EXPECT_GE(fake_.set_times_us[2] - fake_.set_times_us[1], 50u);  // low time between pulses
  fake_.log.clear();
  ASSERT_EQ(steps.Step(0), IoStatus::kOk);
  EXPECT_TRUE(fake_.log.empty());
}

TEST_F(GpiodTest, DirectionIsSetBeforeTheStepAndOnlyWhenItChanges) {
  GpiodConfig config;
  config.dir_setup_us = 40;
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25", config);
  StepDirOutputs& steps = *outputs;
  ASSERT_EQ(steps.SetDirections(0b10), IoStatus::kOk);
  ASSERT_EQ(steps.Step(0b10), IoStatus::kOk);
  EXPECT_EQ(fake_.log, (Log{"set 23=1", "set 17=0,22=1", "set 17=0,22=0"}));
  EXPECT_GE(fake_.set_times_us[1] - fake_.set_times_us[0], 40u);  // DIR set-up time
  EXPECT_EQ(Value(23), 1);

  fake_.log.clear();
  ASSERT_EQ(steps.SetDirections(0b10), IoStatus::kOk);  // unchanged: nothing written
  ASSERT_EQ(steps.SetDirections(0b01), IoStatus::kOk);
  EXPECT_EQ(fake_.log, (Log{"set 27=1", "set 23=0"}));
  EXPECT_EQ(Value(27), 1);
  EXPECT_EQ(Value(23), 0);
}

TEST_F(GpiodTest, EnableIsActiveLowByDefault) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25");
  StepDirOutputs& steps = *outputs;
  ASSERT_EQ(steps.SetEnabled(true), IoStatus::kOk);
  EXPECT_EQ(Value(24), 0);
  ASSERT_EQ(steps.SetEnabled(false), IoStatus::kOk);
  EXPECT_EQ(Value(24), 1);
  EXPECT_EQ(fake_.log, (Log{"set 24=0", "set 24=1"}));
}

TEST_F(GpiodTest, PolarityPrefixesInvertLines) {
  GpiodConfig config;
  std::string error;
  ASSERT_TRUE(ParseGpioDevice("gpio:gpiochip0:17,!27,22,23,+24,!25", &config, &error)) << error;
  std::unique_ptr<GpiodOutputs> outputs;
  ASSERT_EQ(GpiodOutputs::Open(config, &outputs, &error), IoStatus::kOk) << error;
  EXPECT_EQ(fake_.log,
            (Log{"lookup gpiochip0", "request 27 fdsurf 1", "request 23 fdsurf 0",
                 "request 24 fdsurf 0", "request 25 fdsurf 1", "request 17,22 fdsurf 0,0"}));
  fake_.log.clear();
  StepDirOutputs& steps = *outputs;
  PenOutput& pen = *outputs;
  ASSERT_EQ(steps.SetEnabled(true), IoStatus::kOk);
  ASSERT_EQ(steps.SetDirections(0b01), IoStatus::kOk);
  ASSERT_EQ(pen.SetPen(true), IoStatus::kOk);
  ASSERT_EQ(pen.SetPen(false), IoStatus::kOk);
  EXPECT_EQ(fake_.log, (Log{"set 24=1", "set 27=0", "set 25=0", "set 25=1"}));
}

TEST_F(GpiodTest, PenDownIsHigh) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25");
  PenOutput& pen = *outputs;
  ASSERT_EQ(pen.SetPen(true), IoStatus::kOk);
  EXPECT_EQ(Value(25), 1);
  ASSERT_EQ(pen.SetPen(false), IoStatus::kOk);
  EXPECT_EQ(Value(25), 0);
}

TEST_F(GpiodTest, WithoutEnableLineSetEnabledDoesNothing) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,-,25");
  ASSERT_EQ(static_cast<StepDirOutputs&>(*outputs).SetEnabled(true), IoStatus::kOk);
  EXPECT_TRUE(fake_.log.empty());
  outputs.reset();
  EXPECT_EQ(fake_.log, (Log{"set 25=0", "release 17", "release 27", "release 22", "release 23",
                            "release 25", "close"}));
}

TEST_F(GpiodTest, ThreeAxes) {
  auto outputs = OpenSpec("gpio:gpiochip0:1,2,3,4,5,6,7,8");
  StepDirOutputs& steps = *outputs;
  EXPECT_EQ(steps.axes(), 3);
  ASSERT_EQ(steps.SetDirections(0b100), IoStatus::kOk);
  ASSERT_EQ(steps.Step(0b101), IoStatus::kOk);
  EXPECT_EQ(fake_.log, (Log{"set 6=1", "set 1=1,3=0,5=1", "set 1=0,3=0,5=0"}));
}

TEST_F(GpiodTest, MasksBeyondTheAxesAreRefused) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25");
  StepDirOutputs& steps = *outputs;
  EXPECT_EQ(steps.Step(0b100), IoStatus::kInvalidArgument);
  EXPECT_STREQ(steps.LastError(), "gpio gpiochip0: step mask 4 has bits beyond 2 axes");
  EXPECT_EQ(steps.SetDirections(0b1001), IoStatus::kInvalidArgument);
  EXPECT_STREQ(steps.LastError(), "gpio gpiochip0: direction mask 9 has bits beyond 2 axes");
  EXPECT_TRUE(fake_.log.empty());
}

TEST_F(GpiodTest, DestructorLiftsPenDisablesAndReleases) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25");
  ASSERT_EQ(static_cast<PenOutput&>(*outputs).SetPen(true), IoStatus::kOk);
  ASSERT_EQ(static_cast<StepDirOutputs&>(*outputs).SetEnabled(true), IoStatus::kOk);
  fake_.log.clear();
  outputs.reset();
  EXPECT_EQ(fake_.log, (Log{"set 25=0", "set 24=1", "release 17", "release 27", "release 22",
                            "release 23", "release 24", "release 25", "close"}));
  EXPECT_FALSE(chip_->open);
}

TEST_F(GpiodTest, FailedSetNamesTheLineAndStillEndsThePulse) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25");
  chip_->lines[22].set_errno = EIO;
  StepDirOutputs& steps = *outputs;
  EXPECT_EQ(steps.Step(0b11), IoStatus::kIoError);
  EXPECT_STREQ(steps.LastError(),
               "gpio gpiochip0: cannot set step lines 17 (STEPX), 22 (STEPY) to STEPX=1, STEPY=1: "
               "Input/output error");
  EXPECT_EQ(fake_.log, (Log{"set 17=1,22=1 (fails)", "set 17=0,22=0 (fails)"}));
  EXPECT_EQ(Value(17), 0);
}

TEST_F(GpiodTest, FailedLowEdgeIsReportedAndOldErrorsAreNot) {
  auto outputs = OpenSpec("gpio:gpiochip0:17,27,22,23,24,25");
  StepDirOutputs& steps = *outputs;
  chip_->lines[24].set_errno = EIO;
  EXPECT_EQ(steps.SetEnabled(true), IoStatus::kIoError);
  EXPECT_STREQ(steps.LastError(),
               "gpio gpiochip0: cannot set line 24 (EN) to 0: Input/output error");
  chip_->lines[17].set_errno = EBUSY;
  chip_->lines[17].set_fails_for = 0;
  fake_.log.clear();
  EXPECT_EQ(steps.Step(0b11), IoStatus::kIoError);
  EXPECT_STREQ(steps.LastError(),
               "gpio gpiochip0: cannot set step lines 17 (STEPX), 22 (STEPY) to STEPX=0, STEPY=0: "
               "Device or resource busy");
  EXPECT_EQ(fake_.log, (Log{"set 17=1,22=1", "set 17=0,22=0 (fails)"}));
}

TEST_F(GpiodTest, MissingChipListsTheChipsPresent) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("fdsurf_gpio_dev_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  for (const char* name : {"gpiochip10", "gpiochip0", "gpiochip2", "ttyS0"}) {
    std::ofstream(dir / name).put('x');
  }
  GpiodConfig config;
  config.dev_dir = dir.string();
  std::string error;
  EXPECT_EQ(OpenFails("gpio:gpiochip9:17,27,22,23,24,25", &error, config), IoStatus::kNotFound);
  EXPECT_EQ(error,
            "gpio: no GPIO chip 'gpiochip9' (chips present: gpiochip0, gpiochip2, gpiochip10)");
  std::filesystem::remove_all(dir);

  config.dev_dir = dir.string();  // now gone: nothing to list
  EXPECT_EQ(OpenFails("gpio:/dev/gpiochip9:17,27,22,23,24,25", &error, config),
            IoStatus::kNotFound);
  EXPECT_EQ(error, "gpio: no GPIO chip '/dev/gpiochip9' (no GPIO chips in " + dir.string() + ")");
}

TEST_F(GpiodTest, ChipPermissionDenied) {
  fake_.missing_errno = EACCES;
  std::string error;
  EXPECT_EQ(OpenFails("gpio:gpiochip1:17,27,22,23,24,25", &error), IoStatus::kPermissionDenied);
  EXPECT_EQ(error,
            "gpio: permission denied opening GPIO chip 'gpiochip1' (add your user to the group "
            "owning /dev/gpiochip*, e.g. gpio, or add a udev rule; see hal/README.md)");
}

TEST_F(GpiodTest, NotAGpioChip) {
  fake_.missing_errno = ENOTTY;
  std::string error;
  EXPECT_EQ(OpenFails("gpio:/dev/null:17,27,22,23,24,25", &error), IoStatus::kInvalidArgument);
  EXPECT_EQ(error, "gpio: '/dev/null' is not a GPIO chip (Inappropriate ioctl for device)");
}

TEST_F(GpiodTest, OtherChipErrorsGiveTheErrnoText) {
  fake_.missing_errno = EIO;
  std::string error;
  EXPECT_EQ(OpenFails("gpio:gpiochip1:17,27,22,23,24,25", &error), IoStatus::kIoError);
  EXPECT_EQ(error, "gpio: cannot open GPIO chip 'gpiochip1': Input/output error");
}

TEST_F(GpiodTest, OffsetBeyondTheChipReleasesWhatWasRequested) {
  fake_.AddChip("pinctrl-small", 24);
  std::string error;
  EXPECT_EQ(OpenFails("gpio:pinctrl-small:17,20,22,23,24,25", &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "gpio pinctrl-small: line 24 (EN) does not exist: the chip has 24 lines (0-23)");
  EXPECT_EQ(fake_.log, (Log{"lookup pinctrl-small", "request 20 fdsurf 0", "request 23 fdsurf 0",
                            "release 20", "release 23", "close"}));
}

TEST_F(GpiodTest, BusyLineNamesItsConsumer) {
  chip_->lines[22].used = true;
  chip_->lines[22].consumer = "spi0 CS0";
  std::string error;
  EXPECT_EQ(OpenFails("gpio:gpiochip0:17,27,22,23,24,25", &error), IoStatus::kBusy);
  EXPECT_EQ(error, "gpio gpiochip0: line 22 (STEPY) is busy: used by 'spi0 CS0'");
  EXPECT_EQ(fake_.log, (Log{"lookup gpiochip0", "request 27 fdsurf 0", "release 27", "close"}));
}

TEST_F(GpiodTest, BusyOnRequestWithoutConsumerName) {
  chip_->lines[17].request_errno = EBUSY;  // taken between is_used and the request
  std::string error;
  EXPECT_EQ(OpenFails("gpio:gpiochip0:17,27,22,23,24,25", &error), IoStatus::kBusy);
  EXPECT_EQ(error,
            "gpio gpiochip0: step lines 17 (STEPX), 22 (STEPY) are busy: used by another program "
            "or driver");
  // The other lines were granted and are given back, left safe.
  EXPECT_EQ(fake_.log.back(), "close");
  EXPECT_FALSE(chip_->lines[27].requested);
  chip_->lines[17].request_errno = EACCES;
  EXPECT_EQ(OpenFails("gpio:gpiochip0:17,27,22,23,24,25", &error), IoStatus::kPermissionDenied);
  EXPECT_EQ(error,
            "gpio gpiochip0: permission denied requesting step lines 17 (STEPX), 22 (STEPY)");
  chip_->lines[17].request_errno = EINVAL;
  EXPECT_EQ(OpenFails("gpio:gpiochip0:17,27,22,23,24,25", &error), IoStatus::kIoError);
  EXPECT_EQ(error,
            "gpio gpiochip0: cannot request step lines 17 (STEPX), 22 (STEPY) as outputs: Invalid "
            "argument");
}

TEST_F(GpiodTest, RequestPermissionDeniedAndOtherErrors) {
  chip_->lines[25].request_errno = EPERM;
  std::string error;
  EXPECT_EQ(OpenFails("gpio:gpiochip0:17,27,22,23,24,25", &error), IoStatus::kPermissionDenied);
  EXPECT_EQ(error, "gpio gpiochip0: permission denied requesting line 25 (PEN)");
  chip_->lines[25].request_errno = EINVAL;
  EXPECT_EQ(OpenFails("gpio:gpiochip0:17,27,22,23,24,25", &error), IoStatus::kIoError);
  EXPECT_EQ(error, "gpio gpiochip0: cannot request line 25 (PEN) as an output: Invalid argument");
}

TEST_F(GpiodTest, ConfigErrorsBeforeTouchingTheChip) {
  GpiodConfig config;
  config.axes = 4;
  std::unique_ptr<GpiodOutputs> outputs;
  std::string error;
  EXPECT_EQ(GpiodOutputs::Open(config, &outputs, &error), IoStatus::kInvalidArgument);
  EXPECT_EQ(error, "gpio gpiochip0: 4 axes (2 or 3 supported)");
  config.axes = 2;
  config.step[0].offset = 3;
  config.dir[1].offset = 3;
  config.pen.offset = 9;
  config.dir[0].offset = 1;
  config.step[1].offset = 2;
  EXPECT_EQ(GpiodOutputs::Open(config, &outputs, &error), IoStatus::kInvalidArgument);
  EXPECT_EQ(error, "gpio gpiochip0: line 3 (DIRY) is also STEPX");
}

TEST(ParseGpioDevice, AcceptsTheDocumentedForms) {
  GpiodConfig config;
  config.min_pulse_us = 7;
  std::string error;
  ASSERT_TRUE(ParseGpioDevice("gpio:/dev/gpiochip0:17,!27,22,23,5,6,+24,25", &config, &error));
  EXPECT_EQ(config.chip, "/dev/gpiochip0");
  EXPECT_EQ(config.axes, 3);
  EXPECT_EQ(config.step[0].offset, 17u);
  EXPECT_TRUE(config.dir[0].active_low);
  EXPECT_EQ(config.step[2].offset, 5u);
  EXPECT_EQ(config.dir[2].offset, 6u);
  EXPECT_TRUE(config.has_enable);
  EXPECT_EQ(config.enable.offset, 24u);
  EXPECT_FALSE(config.enable.active_low);
  EXPECT_EQ(config.pen.offset, 25u);
  EXPECT_EQ(config.min_pulse_us, 7u);  // kept

  ASSERT_TRUE(ParseGpioDevice("gpio:0:1,2,3,4,-,5", &config, &error));
  EXPECT_EQ(config.chip, "0");
  EXPECT_EQ(config.axes, 2);
  EXPECT_FALSE(config.has_enable);
  ASSERT_TRUE(ParseGpioDevice("gpio:gpiochip0:1,2,3,4,7,5", &config, &error));
  EXPECT_TRUE(config.enable.active_low);  // EN defaults to active-low
}

TEST(ParseGpioDevice, ExplainsEveryMistake) {
  const char* usage =
      "expected gpio:CHIP:STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN (e.g. "
      "gpio:gpiochip0:17,27,22,23,24,25)";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"gpiochip0:1,2,3,4,5,6",
       std::string("gpio device 'gpiochip0:1,2,3,4,5,6' must start with 'gpio:'; ") + usage},
      {"gpio:gpiochip0", std::string("gpio device 'gpio:gpiochip0' has no LINES; ") + usage},
      {"gpio::1,2,3,4,5,6", std::string("gpio device 'gpio::1,2,3,4,5,6' has no CHIP; ") + usage},
      {"gpio:gpiochip0:17,27,22",
       "gpio device 'gpio:gpiochip0:17,27,22': 3 lines given; expected "
       "STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN (6 lines for 2 axes, 8 for 3)"},
      {"gpio:gpiochip0:17,x,22,23,24,25",
       "gpio device 'gpio:gpiochip0:17,x,22,23,24,25': DIRX 'x' is not a line offset "
       "([!|+]NUMBER)"},
      {"gpio:gpiochip0:17,27,22,23,24,-",
       "gpio device 'gpio:gpiochip0:17,27,22,23,24,-': PEN '-' is not a line offset "
       "([!|+]NUMBER)"},
      {"gpio:gpiochip0:17,27,22,23,e,25",
       "gpio device 'gpio:gpiochip0:17,27,22,23,e,25': EN 'e' is not a line offset "
       "([!|+]NUMBER, or - for none)"},
      {"gpio:gpiochip0:17,27,22,,24,25",
       "gpio device 'gpio:gpiochip0:17,27,22,,24,25': DIRY '' is not a line offset "
       "([!|+]NUMBER)"},
      {"gpio:gpiochip0:17,27,22,17,24,25",
       "gpio device 'gpio:gpiochip0:17,27,22,17,24,25': line 17 used twice (STEPX and DIRY)"},
  };
  for (const auto& [spec, message] : cases) {
    GpiodConfig config;
    std::string error;
    EXPECT_FALSE(ParseGpioDevice(spec, &config, &error)) << spec;
    EXPECT_EQ(error, message) << spec;
    EXPECT_EQ(config.chip, "gpiochip0") << spec;  // untouched on failure
  }
}

}  // namespace
}  // namespace fdsurf::hal
