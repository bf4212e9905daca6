// SPDX-License-Identifier: MIT
// PtyTransport against the real kernel's ptys: bytes both ways through the
// published link, raw (no echo, no translation), a client closing without
// hanging up the server, the link replaced and removed as documented.
#include "fdsurf/hal/pty_transport.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

namespace fdsurf::hal {
namespace {

namespace fs = std::filesystem;

class PtyTransportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fdsurf_pty_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    link_ = (dir_ / "tty").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The client end, opened plainly: no terminal settings of its own, so
  // that the raw mode tested is the server's.
  int OpenClient() const { return open(link_.c_str(), O_RDWR | O_NOCTTY); }

  fs::path dir_;
  std::string link_;
};

TEST_F(PtyTransportTest, MovesEveryByteBothWaysUntranslated) {
  std::unique_ptr<PtyTransport> pty;
  std::string error;
  ASSERT_EQ(PtyTransport::Open(link_, &pty, &error), IoStatus::kOk) << error;
  EXPECT_TRUE(fs::is_symlink(link_));
  EXPECT_EQ(fs::read_symlink(link_).string(), pty->slave_name());
  const int client = OpenClient();
  ASSERT_GE(client, 0);
  // COBS frames end in 0; CR, LF, ^C and ^S must pass as they are.
  const uint8_t to_device[] = {0x01, '\r', '\n', 0x03, 0x13, 0x7f, 0xff, 0x00};
  ASSERT_EQ(write(client, to_device, sizeof to_device), static_cast<ssize_t>(sizeof to_device));
  uint8_t got[64];
  size_t total = 0;
  for (int tries = 0; tries < 10 && total < sizeof to_device; ++tries) {
    size_t n = 0;
    const IoStatus status = pty->Read(got + total, sizeof got - total, &n, 100);
    ASSERT_TRUE(status == IoStatus::kOk || status == IoStatus::kTimeout);
    total += n;
  }
  ASSERT_EQ(total, sizeof to_device);
  EXPECT_EQ(std::string(got, got + total), std::string(to_device, to_device + total));
  // Nothing echoed back to the client.
  size_t n = 0;
  EXPECT_EQ(pty->Read(got, sizeof got, &n, 20), IoStatus::kTimeout);
  EXPECT_EQ(n, 0u);

  const uint8_t to_host[] = {'\n', 0x00, 0x11, 0x0d};
  ASSERT_EQ(pty->Write(to_host, sizeof to_host, 100), IoStatus::kOk) << pty->LastError();
  uint8_t back[sizeof to_host];
  ASSERT_EQ(read(client, back, sizeof back), static_cast<ssize_t>(sizeof back));
  EXPECT_EQ(std::string(back, back + sizeof back), std::string(to_host, to_host + sizeof to_host));

  // The client goes away: no hang-up for the server, and the next one gets through.
  close(client);
  EXPECT_EQ(pty->Read(got, sizeof got, &n, 20), IoStatus::kTimeout);
  const int next = OpenClient();
  ASSERT_EQ(write(next, "x", 1), 1);
  EXPECT_EQ(pty->Read(got, sizeof got, &n, 500), IoStatus::kOk);
  EXPECT_EQ(n, 1u);
  close(next);

  pty.reset();
  EXPECT_FALSE(fs::exists(fs::symlink_status(link_))) << "the link outlived its pty";
}

TEST_F(PtyTransportTest, ReplacesAStaleLinkAndLeavesANewerServersOne) {
  fs::create_symlink("/dev/pts/does-not-exist", link_);  // a killed server's
  std::unique_ptr<PtyTransport> first;
  std::unique_ptr<PtyTransport> second;
  std::string error;
  ASSERT_EQ(PtyTransport::Open(link_, &first, &error), IoStatus::kOk) << error;
  EXPECT_EQ(fs::read_symlink(link_).string(), first->slave_name());
  ASSERT_EQ(PtyTransport::Open(link_, &second, &error), IoStatus::kOk) << error;
  first.reset();
  ASSERT_TRUE(fs::is_symlink(link_)) << "the first server removed the second's link";
  EXPECT_EQ(fs::read_symlink(link_).string(), second->slave_name());
}

TEST_F(PtyTransportTest, ALinkInAFolderThatDoesNotExistIsNotFoundNamingIt) {
  std::unique_ptr<PtyTransport> pty;
  std::string error;
  const std::string link = (dir_ / "no-such-dir" / "tty").string();
  EXPECT_EQ(PtyTransport::Open(link, &pty, &error), IoStatus::kNotFound);
  EXPECT_EQ(pty, nullptr);
  EXPECT_NE(error.find("pty: publishing /dev/pts/"), std::string::npos) << error;
  EXPECT_NE(error.find(" as " + link + ": No such file or directory"), std::string::npos) << error;
}

}  // namespace
}  // namespace fdsurf::hal
