// SPDX-License-Identifier: MIT
// GpiodOutputs against the real libgpiod 1.6 (no --wrap): a chip that does
// not exist must give the clear message through the library's own errno path.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "fdsurf/hal/gpiod_outputs.h"

namespace fdsurf::hal {
namespace {

IoStatus OpenChip(const std::string& chip, std::string* error) {
  GpiodConfig config;
  EXPECT_TRUE(ParseGpioDevice("gpio:" + chip + ":1,2,3,4,5,6", &config, error)) << *error;
  config.dev_dir = "/nonexistent-fdsurf-dev";  // a fixed "chips present" part on any machine
  std::unique_ptr<GpiodOutputs> outputs;
  return GpiodOutputs::Open(config, &outputs, error);
}

TEST(GpiodReal, MissingChipByNamePathAndNumber) {
  for (const char* chip : {"gpiochip987", "/dev/gpiochip987", "987", "no-such-label"}) {
    std::string error;
    EXPECT_EQ(OpenChip(chip, &error), IoStatus::kNotFound) << chip;
    EXPECT_EQ(error, std::string("gpio: no GPIO chip '") + chip +
                         "' (no GPIO chips in /nonexistent-fdsurf-dev)");
  }
}

TEST(GpiodReal, DevNullIsNotAGpioChip) {
  std::string error;
  EXPECT_EQ(OpenChip("/dev/null", &error), IoStatus::kInvalidArgument);
  EXPECT_EQ(error, "gpio: '/dev/null' is not a GPIO chip (Inappropriate ioctl for device)");
}

}  // namespace
}  // namespace fdsurf::hal
