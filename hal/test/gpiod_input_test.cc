// SPDX-License-Identifier: MIT
// The libgpiod endstop inputs (gpiod_inputs.h) against the fake libgpiod
// (fake_gpiod.h): the ENDSTOPS part of the device string, the lines
// requested as inputs, each switch's polarity in Read(), and errors that
// name the chip, the line and the switch.
#include "fdsurf/hal/gpiod_inputs.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <memory>
#include <string>

#include "fake_gpiod.h"

namespace fdsurf::hal {
namespace {

using testing::FakeGpio;

class GpiodInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    fake_.AddChip("gpiochip0", 32);
    testing::g_fake_gpio = &fake_;
  }
  void TearDown() override { testing::g_fake_gpio = nullptr; }

  // `spec` parsed as the gpio runner does: LINES, then ENDSTOPS.
  static bool Parse(const std::string& spec, GpioEndstopConfig* endstops, std::string* error) {
    GpiodConfig outputs;
    if (!ParseGpioDevice(spec, &outputs, error)) return false;
    endstops->chip = outputs.chip;
    return ParseGpioEndstops(outputs.endstops, outputs, endstops, error);
  }
  static std::string Refusal(const std::string& spec) {
    GpioEndstopConfig endstops;
    std::string error;
    return Parse(spec, &endstops, &error) ? "" : error;
  }

  FakeGpio fake_;
};

TEST_F(GpiodInputs, EndstopsPartGivesEachSwitchItsLineAndPolarity) {
  GpioEndstopConfig c;
  std::string error;
  ASSERT_TRUE(Parse("gpio:gpiochip0:17,27,22,23,24,25:xmin=!5,ymax=6", &c, &error)) << error;
  EXPECT_TRUE(c.has_min[0]);
  EXPECT_EQ(c.min[0].offset, 5U);
  EXPECT_TRUE(c.min[0].active_low);
  EXPECT_TRUE(c.has_max[1]);
  EXPECT_EQ(c.max[1].offset, 6U);
  EXPECT_FALSE(c.max[1].active_low);
  EXPECT_FALSE(c.has_min[1]);
  EXPECT_FALSE(c.has_max[0]);
  // Without ENDSTOPS the outputs parse as before and no switch is given.
  GpiodConfig outputs;
  ASSERT_TRUE(ParseGpioDevice("gpio:gpiochip0:17,27,22,23,24,25", &outputs, &error)) << error;
  EXPECT_EQ(outputs.endstops, "");
  EXPECT_EQ(outputs.pen.offset, 25U);
}

TEST_F(GpiodInputs, BadEndstopsAreRefusedNamingTheField) {
  EXPECT_EQ(Refusal("gpio:gpiochip0:17,27,22,23,24,25:xmin=5x"),
            "endstop 'xmin=5x' is not AXISEND=[!|+]OFFSET with AXISEND xmin, xmax, ymin, ymax, "
            "zmin or zmax (like xmin=!5)");
  EXPECT_NE(Refusal("gpio:gpiochip0:17,27,22,23,24,25:wmin=5").find("'wmin=5' is not"),
            std::string::npos);
  EXPECT_EQ(Refusal("gpio:gpiochip0:17,27,22,23,24,25:xmin=5,xmin=6"), "endstop xmin given twice");
  EXPECT_EQ(Refusal("gpio:gpiochip0:17,27,22,23,24,25:zmin=5"),
            "endstop zmin: the machine has 2 axes");
  EXPECT_EQ(Refusal("gpio:gpiochip0:17,27,22,23,24,25:ymin=24"),
            "endstop ymin: line 24 is also an output in LINES");
  EXPECT_EQ(Refusal("gpio:gpiochip0:17,27,22,23,24,25:xmin=5,ymin=5"),
            "endstop ymin: line 5 used twice");
  EXPECT_EQ(Refusal("gpio:gpiochip0:17,27,22,23,5,6,24,25:zmax=!9"), "");
}

TEST_F(GpiodInputs, ReadAppliesEachLinesPolarity) {
  GpioEndstopConfig c;
  std::string error;
  ASSERT_TRUE(Parse("gpio:gpiochip0:17,27,22,23,24,25:xmin=!5,ymin=6,xmax=7", &c, &error));
  std::unique_ptr<GpiodEndstops> inputs;
  ASSERT_EQ(GpiodEndstops::Open(c, &inputs, &error), IoStatus::kOk) << error;
  EXPECT_EQ(fake_.log[1], "input 5 fdsurf");
  EXPECT_EQ(inputs->fitted().min_mask, 0b11);
  EXPECT_EQ(inputs->fitted().max_mask, 0b01);
  auto& lines = fake_.chips["gpiochip0"].lines;
  lines[5].value = 1;  // active-low X min: released
  lines[6].value = 0;
  lines[7].value = 0;
  EndstopState state{9, 9};
  ASSERT_EQ(inputs->Read(&state), IoStatus::kOk);
  EXPECT_EQ(state.min_mask, 0);
  EXPECT_EQ(state.max_mask, 0);
  lines[5].value = 0;  // X min pulled to ground: triggered
  lines[6].value = 1;  // Y min active-high: triggered
  lines[7].value = 1;  // X max: triggered
  ASSERT_EQ(inputs->Read(&state), IoStatus::kOk);
  EXPECT_EQ(state.min_mask, 0b11);
  EXPECT_EQ(state.max_mask, 0b01);
  inputs.reset();
  EXPECT_FALSE(lines[5].requested);
  EXPECT_EQ(fake_.log.back(), "close");
}

TEST_F(GpiodInputs, ErrorsNameTheChipLineAndSwitch) {
  GpioEndstopConfig c;
  std::string error;
  ASSERT_TRUE(Parse("gpio:gpiochip0:17,27,22,23,24,25:xmin=5,ymin=6", &c, &error));
  auto& lines = fake_.chips["gpiochip0"].lines;
  lines[6].used = true;
  lines[6].consumer = "spi0";
  std::unique_ptr<GpiodEndstops> inputs;
  EXPECT_EQ(GpiodEndstops::Open(c, &inputs, &error), IoStatus::kBusy);
  EXPECT_EQ(error, "gpio gpiochip0: line 6 (endstop ymin) is busy: used by 'spi0'");
  EXPECT_EQ(inputs, nullptr);
  EXPECT_FALSE(lines[5].requested);  // the one already requested was released
  lines[6].used = false;
  ASSERT_EQ(GpiodEndstops::Open(c, &inputs, &error), IoStatus::kOk) << error;
  lines[6].get_errno = EIO;
  EndstopState state{};
  EXPECT_EQ(inputs->Read(&state), IoStatus::kIoError);
  EXPECT_EQ(std::string(inputs->LastError()),
            "gpio gpiochip0: line 6 (endstop ymin) cannot be read: Input/output error");
  EXPECT_EQ(state.min_mask, 0);
  c.min[1].offset = 40;
  inputs.reset();
  EXPECT_EQ(GpiodEndstops::Open(c, &inputs, &error), IoStatus::kNotFound);
  EXPECT_EQ(error, "gpio gpiochip0: line 40 (endstop ymin) is beyond the chip's 32 lines");
  GpioEndstopConfig missing = c;
  missing.chip = "gpiochip9";
  EXPECT_EQ(GpiodEndstops::Open(missing, &inputs, &error), IoStatus::kNotFound);
  EXPECT_NE(error.find("gpiochip9"), std::string::npos);
}

}  // namespace
}  // namespace fdsurf::hal
