// SPDX-License-Identifier: MIT
// The PWM interface (hal/pwm.h): the sim channel, the servo pen on it, and
// the Linux sysfs backend against a temporary tree shaped like
// /sys/class/pwm.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "fdsurf/hal/pwm.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/hal/sysfs_pwm.h"

namespace fdsurf::hal {
namespace {

namespace fs = std::filesystem;

TEST(SimPwm, RecordsEveryChangeWithItsTime) {
  SimClock clock(100);
  SimPwm pwm(clock);
  EXPECT_EQ(pwm.SetPeriodMicros(20000), IoStatus::kOk);
  clock.Advance(5);
  EXPECT_EQ(pwm.SetPulseMicros(1500), IoStatus::kOk);
  EXPECT_EQ(pwm.SetPulseMicros(1500), IoStatus::kOk);  // no change: not recorded
  clock.Advance(7);
  EXPECT_EQ(pwm.SetEnabled(true), IoStatus::kOk);
  const std::vector<PwmEvent> expected = {
      {100, 20000, 0, false}, {105, 20000, 1500, false}, {112, 20000, 1500, true}};
  EXPECT_EQ(pwm.events(), expected);
}

TEST(SimPwm, RefusesWhatATimerCannotDo) {
  SimClock clock;
  SimPwm pwm(clock, 30000);
  EXPECT_EQ(pwm.SetPeriodMicros(0), IoStatus::kInvalidArgument);
  EXPECT_EQ(pwm.SetPeriodMicros(30001), IoStatus::kInvalidArgument);
  EXPECT_EQ(pwm.SetPulseMicros(1), IoStatus::kInvalidArgument);  // period still 0
  EXPECT_NE(std::string(pwm.LastError()).find("longer than the period"), std::string::npos);
  ASSERT_EQ(pwm.SetPeriodMicros(20000), IoStatus::kOk);
  ASSERT_EQ(pwm.SetPulseMicros(2000), IoStatus::kOk);
  EXPECT_EQ(pwm.SetPeriodMicros(1999), IoStatus::kInvalidArgument);
  EXPECT_EQ(pwm.period_us(), 20000u);
  pwm.InjectError(IoStatus::kIoError);
  EXPECT_EQ(pwm.SetEnabled(true), IoStatus::kIoError);
  EXPECT_STREQ(pwm.LastError(), "sim pwm: injected I/O error");
  EXPECT_EQ(pwm.SetEnabled(true), IoStatus::kOk);
}

TEST(ServoPen, PulsesTheWidthOfEachPenState) {
  SimClock clock;
  SimPwm pwm(clock);
  ServoPen pen(pwm, 1000, 2000);
  ASSERT_EQ(pen.Start(), IoStatus::kOk);
  EXPECT_EQ(pwm.period_us(), kServoPeriodUs);
  EXPECT_EQ(pwm.pulse_us(), 1000u);
  EXPECT_TRUE(pwm.enabled());
  PenOutput& as_pen = pen;
  ASSERT_EQ(as_pen.SetPen(true), IoStatus::kOk);
  EXPECT_EQ(pwm.pulse_us(), 2000u);
  // A CONFIG's widths move the pen to the new width of its state at once.
  ASSERT_EQ(as_pen.ConfigureServo(1200, 1800), IoStatus::kOk);
  EXPECT_EQ(pwm.pulse_us(), 1800u);
  ASSERT_EQ(as_pen.SetPen(false), IoStatus::kOk);
  EXPECT_EQ(pwm.pulse_us(), 1200u);
  // Both 0: back to the board's defaults.
  ASSERT_EQ(as_pen.ConfigureServo(0, 0), IoStatus::kOk);
  EXPECT_EQ(pwm.pulse_us(), 1000u);
  EXPECT_EQ(pen.down_us(), 2000u);
}

TEST(ServoPen, RefusesWidthsOutsideTheServoRangeAndReportsPwmErrors) {
  SimClock clock;
  SimPwm pwm(clock);
  ServoPen pen(pwm, 1000, 2000);
  ASSERT_EQ(pen.Start(), IoStatus::kOk);
  PenOutput& as_pen = pen;
  EXPECT_EQ(as_pen.ConfigureServo(499, 2000), IoStatus::kInvalidArgument);
  EXPECT_EQ(as_pen.ConfigureServo(1000, 0), IoStatus::kInvalidArgument);
  EXPECT_NE(std::string(as_pen.LastError()).find("500..2500"), std::string::npos);
  EXPECT_EQ(pen.up_us(), 1000u);  // unchanged
  pwm.InjectError(IoStatus::kIoError);
  EXPECT_EQ(as_pen.SetPen(true), IoStatus::kIoError);
  EXPECT_STREQ(as_pen.LastError(), "sim pwm: injected I/O error");
}

// A plain switch pen (SimPen) accepts a CONFIG's widths and ignores them.
TEST(PenOutput, PlainSwitchIgnoresServoWidths) {
  SimClock clock;
  SimPen pen(clock);
  PenOutput& as_pen = pen;
  EXPECT_EQ(as_pen.ConfigureServo(1200, 1800), IoStatus::kOk);
  EXPECT_TRUE(pen.events().empty());
}

// --- sysfs ----------------------------------------------------------------

class SysfsPwmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("fdsurf-pwm-" + std::to_string(getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "pwmchip0");
    std::ofstream(root_ / "pwmchip0" / "export").put('\n');
  }
  void TearDown() override { fs::remove_all(root_); }

  // The channel directory the kernel would create on export.
  void MakeChannel(unsigned channel) {
    const fs::path dir = root_ / "pwmchip0" / ("pwm" + std::to_string(channel));
    fs::create_directories(dir);
    for (const char* name : {"period", "duty_cycle", "enable"}) std::ofstream(dir / name) << "0\n";
  }
  std::string Read(const fs::path& path) const {
    std::ifstream in(root_ / path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  SysfsPwmConfig Config(unsigned chip, unsigned channel) const {
    SysfsPwmConfig config;
    config.root = root_.string();
    config.chip = chip;
    config.channel = channel;
    config.export_wait_ms = 0;
    return config;
  }

  fs::path root_;
};

TEST_F(SysfsPwmTest, ServoPenWritesNanosecondsToTheChannel) {
  MakeChannel(1);
  std::unique_ptr<SysfsPwm> pwm;
  std::string error;
  ASSERT_EQ(SysfsPwm::Open(Config(0, 1), &pwm, &error), IoStatus::kOk) << error;
  EXPECT_EQ(Read("pwmchip0/export"), "\n");  // already exported: not written
  ServoPen pen(*pwm, 1000, 2000);
  ASSERT_EQ(pen.Start(), IoStatus::kOk) << pen.LastError();
  EXPECT_EQ(Read("pwmchip0/pwm1/period"), "20000000");
  EXPECT_EQ(Read("pwmchip0/pwm1/duty_cycle"), "1000000");
  EXPECT_EQ(Read("pwmchip0/pwm1/enable"), "1");
  PenOutput& as_pen = pen;
  ASSERT_EQ(as_pen.ConfigureServo(1100, 1900), IoStatus::kOk);
  ASSERT_EQ(as_pen.SetPen(true), IoStatus::kOk);
  EXPECT_EQ(Read("pwmchip0/pwm1/duty_cycle"), "1900000");
  ASSERT_EQ(pwm->SetEnabled(false), IoStatus::kOk);
  EXPECT_EQ(Read("pwmchip0/pwm1/enable"), "0");
  pwm.reset();  // the destructor leaves the channel as it is (a limp servo may drop the pen)
  EXPECT_EQ(Read("pwmchip0/pwm1/enable"), "0");
}

TEST_F(SysfsPwmTest, ExportsAMissingChannel) {
  std::unique_ptr<SysfsPwm> pwm;
  std::string error;
  // The fake kernel does not create pwm2/: the export is written, then the
  // channel is reported missing, naming it.
  EXPECT_EQ(SysfsPwm::Open(Config(0, 2), &pwm, &error), IoStatus::kNotFound);
  EXPECT_EQ(Read("pwmchip0/export"), "2");
  EXPECT_NE(error.find("pwmchip0/pwm2/{period,duty_cycle,enable}"), std::string::npos) << error;
  EXPECT_EQ(pwm, nullptr);
}

TEST_F(SysfsPwmTest, MissingChipNamesItAndTheChipsPresent) {
  std::unique_ptr<SysfsPwm> pwm;
  std::string error;
  EXPECT_EQ(SysfsPwm::Open(Config(3, 0), &pwm, &error), IoStatus::kNotFound);
  EXPECT_EQ(error,
            "pwm: no PWM chip " + (root_ / "pwmchip3").string() + " (chips present: pwmchip0)");
}

TEST_F(SysfsPwmTest, FailedWriteNamesTheFile) {
  MakeChannel(0);
  // A directory in place of duty_cycle: open(O_WRONLY) fails with EISDIR,
  // even for root (permission bits would not stop root).
  const fs::path duty = root_ / "pwmchip0" / "pwm0" / "duty_cycle";
  fs::remove(duty);
  fs::create_directory(duty);
  std::unique_ptr<SysfsPwm> pwm;
  std::string error;
  ASSERT_EQ(SysfsPwm::Open(Config(0, 0), &pwm, &error), IoStatus::kOk) << error;
  ServoPen pen(*pwm, 1000, 2000);
  EXPECT_EQ(pen.Start(), IoStatus::kIoError);
  EXPECT_EQ(std::string(pen.LastError()),
            "pwm: cannot write '0' to " + duty.string() + ": Is a directory");
}

TEST_F(SysfsPwmTest, RefusesAPulseLongerThanThePeriodWithoutWriting) {
  MakeChannel(0);
  std::unique_ptr<SysfsPwm> pwm;
  std::string error;
  ASSERT_EQ(SysfsPwm::Open(Config(0, 0), &pwm, &error), IoStatus::kOk) << error;
  EXPECT_EQ(pwm->SetPulseMicros(1000), IoStatus::kInvalidArgument);  // no period yet
  ASSERT_EQ(pwm->SetPeriodMicros(20000), IoStatus::kOk);
  EXPECT_EQ(pwm->SetPulseMicros(20001), IoStatus::kInvalidArgument);
  EXPECT_EQ(Read("pwmchip0/pwm0/duty_cycle"), "0");
}

}  // namespace
}  // namespace fdsurf::hal
