// SPDX-License-Identifier: MIT
// SerialTransport on real kernel pseudo-terminals: the test holds the master
// side (the "device") and publishes the slave under a symlink, as a
// /dev/serial/by-id link would be; the transport opens the link.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "fdsurf/hal/serial_transport.h"

namespace fdsurf::hal {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

struct Pty {
  int master = -1;
  int slave = -1;
  std::string name;
  Pty() {
    char buffer[128];
    if (openpty(&master, &slave, buffer, nullptr, nullptr) == 0) name = buffer;
  }
  ~Pty() { Close(); }
  void Close() {
    if (master >= 0) close(master);
    if (slave >= 0) close(slave);
    master = slave = -1;
  }
  // What the master side has received within `timeout_ms`.
  std::string Drain(int timeout_ms) const {
    std::string got;
    pollfd p{master, POLLIN, 0};
    while (poll(&p, 1, timeout_ms) > 0) {
      char buffer[4096];
      const ssize_t n = read(master, buffer, sizeof buffer);
      if (n <= 0) break;
      got.append(buffer, static_cast<size_t>(n));
      timeout_ms = 20;
    }
    return got;
  }
};

class SerialPty : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fdsurf_serial_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    link_ = (dir_ / "ttyFD0").string();
    ASSERT_FALSE(pty_.name.empty());
    Publish(pty_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  void Publish(const Pty& pty) {
    const std::string temporary = link_ + ".new";
    fs::remove(temporary);
    fs::create_symlink(pty.name, temporary);
    fs::rename(temporary, link_);
  }

  std::unique_ptr<SerialTransport> OpenOk(uint32_t baud = 115200) {
    std::unique_ptr<SerialTransport> port;
    std::string error;
    SerialOptions options;
    options.baud = baud;
    EXPECT_EQ(SerialTransport::Open(link_, options, &port, &error), IoStatus::kOk) << error;
    return port;
  }

  fs::path dir_;
  std::string link_;
  Pty pty_;
};

TEST_F(SerialPty, OpensRaw8N1WithoutFlowControlAtTheBaud) {
  auto port = OpenOk(57600);
  ASSERT_TRUE(port);
  EXPECT_EQ(port->device_node(), fs::canonical(pty_.name).string());
  EXPECT_EQ(port->identity().transport, "pty");
  EXPECT_FALSE(port->opened_by_libserialport());  // libserialport 0.1.1 refuses ptys
  termios tio{};
  ASSERT_EQ(tcgetattr(pty_.slave, &tio), 0);
  EXPECT_EQ(tio.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  EXPECT_EQ(tio.c_cflag & (PARENB | CSTOPB | CRTSCTS), 0u);
  EXPECT_EQ(tio.c_iflag & (IXON | IXOFF | ICRNL | ISTRIP), 0u);
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO | ISIG), 0u);
  EXPECT_EQ(tio.c_oflag & OPOST, 0u);  // no \n -> \r\n on the way out
  EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B57600));
}

// A serial port starts with HUPCL set (the kernel's standard termios; a
// pty does not, so the test sets it); the port clears it so that closing it
// keeps DTR up and an Arduino is not reset by the next fdsurf's open.
TEST_F(SerialPty, ClosingKeepsDtrUpSoTheNextOpenDoesNotResetAnArduino) {
  termios before{};
  ASSERT_EQ(tcgetattr(pty_.slave, &before), 0);
  before.c_cflag |= HUPCL;
  ASSERT_EQ(tcsetattr(pty_.slave, TCSANOW, &before), 0);
  auto port = OpenOk(115200);
  ASSERT_TRUE(port);
  termios tio{};
  ASSERT_EQ(tcgetattr(pty_.slave, &tio), 0);
  EXPECT_EQ(tio.c_cflag & HUPCL, 0u);
}

TEST_F(SerialPty, MovesEveryByteValueBothWays) {
  auto port = OpenOk();
  ASSERT_TRUE(port);
  std::vector<uint8_t> all(256);
  for (int i = 0; i < 256; ++i) all[static_cast<size_t>(i)] = static_cast<uint8_t>(i);
  ASSERT_EQ(port->Write(all.data(), all.size(), 1000), IoStatus::kOk) << port->LastError();
  const std::string got = pty_.Drain(500);
  ASSERT_EQ(got.size(), 256u);
  EXPECT_EQ(std::vector<uint8_t>(got.begin(), got.end()), all);

  ASSERT_EQ(write(pty_.master, all.data(), all.size()), 256);
  std::vector<uint8_t> back;
  uint8_t buffer[100];
  while (back.size() < 256) {
    size_t n = 0;
    ASSERT_EQ(port->Read(buffer, sizeof buffer, &n, 500), IoStatus::kOk) << port->LastError();
    ASSERT_GE(n, 1u);
    ASSERT_LE(n, sizeof buffer);
    back.insert(back.end(), buffer, buffer + n);
  }
  EXPECT_EQ(back, all);
}

TEST_F(SerialPty, ReadTimesOutAfterItsTimeoutWithNothing) {
  auto port = OpenOk();
  ASSERT_TRUE(port);
  uint8_t buffer[8];
  size_t n = 99;
  const auto start = Clock::now();
  EXPECT_EQ(port->Read(buffer, sizeof buffer, &n, 80), IoStatus::kTimeout);
  const double took = MsSince(start);
  EXPECT_EQ(n, 0u);
  EXPECT_GE(took, 79.0);
  EXPECT_LT(took, 1000.0);
  EXPECT_NE(std::string(port->LastError()).find("nothing received within 80 ms"),
            std::string::npos);
  EXPECT_EQ(port->Read(nullptr, 8, &n, 0), IoStatus::kInvalidArgument);
}

TEST_F(SerialPty, WriteToAPeerThatNeverReadsTimesOutWithTheCountSent) {
  auto port = OpenOk();
  ASSERT_TRUE(port);
  std::vector<uint8_t> lots(4 << 20, 0x55);
  const auto start = Clock::now();
  EXPECT_EQ(port->Write(lots.data(), lots.size(), 100), IoStatus::kTimeout);
  EXPECT_LT(MsSince(start), 2000.0);
  const std::string error = port->LastError();
  EXPECT_NE(error.find("write timed out after "), std::string::npos) << error;
  EXPECT_NE(error.find(" of 4194304 bytes (100 ms)"), std::string::npos) << error;
}

TEST_F(SerialPty, TheOtherEndClosingIsAHangUpThenReconnectFollowsTheLink) {
  auto port = OpenOk();
  ASSERT_TRUE(port);
  pty_.Close();
  uint8_t buffer[8];
  size_t n = 0;
  const auto start = Clock::now();
  EXPECT_EQ(port->Read(buffer, sizeof buffer, &n, 2000), IoStatus::kDisconnected);
  EXPECT_LT(MsSince(start), 1000.0);  // at once, not after the timeout
  EXPECT_FALSE(port->connected());
  const std::string error = port->LastError();
  EXPECT_NE(error.find("serial " + link_ + ": hung up"), std::string::npos) << error;
  EXPECT_EQ(port->Write(buffer, 1, 10), IoStatus::kDisconnected);

  // The device comes back on another pty after 200 ms; the link follows it.
  Pty again;
  std::thread replug([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    Publish(again);
  });
  const auto waited = Clock::now();
  const IoStatus status = port->Reconnect(3000);
  replug.join();
  ASSERT_EQ(status, IoStatus::kOk) << port->LastError();
  EXPECT_GE(MsSince(waited), 150.0);
  EXPECT_EQ(port->device_node(), fs::canonical(again.name).string());
  const uint8_t hello[] = {1, 2, 3};
  ASSERT_EQ(port->Write(hello, 3, 500), IoStatus::kOk);
  EXPECT_EQ(again.Drain(500), std::string("\x01\x02\x03"));
}

TEST_F(SerialPty, ReconnectGivesUpWhenTheDeviceDoesNotComeBack) {
  auto port = OpenOk();
  ASSERT_TRUE(port);
  pty_.Close();
  fs::remove(link_);
  uint8_t buffer[8];
  size_t n = 0;
  ASSERT_EQ(port->Read(buffer, sizeof buffer, &n, 1000), IoStatus::kDisconnected);
  const auto start = Clock::now();
  EXPECT_EQ(port->Reconnect(300), IoStatus::kTimeout);
  EXPECT_GE(MsSince(start), 299.0);
  EXPECT_LT(MsSince(start), 2000.0);
  const std::string error = port->LastError();
  EXPECT_EQ(error, "serial " + link_ + ": no such port; not back within 300 ms");
}

TEST_F(SerialPty, AMissingPortIsNotFoundNamingIt) {
  std::unique_ptr<SerialTransport> port;
  std::string error;
  const std::string missing = (dir_ / "ttyACM9").string();
  EXPECT_EQ(SerialTransport::Open(missing, SerialOptions{}, &port, &error), IoStatus::kNotFound);
  EXPECT_FALSE(port);
  EXPECT_EQ(error, "serial " + missing + ": no such port");
}

TEST_F(SerialPty, ASecondOpenIsBusy) {
  auto first = OpenOk();
  ASSERT_TRUE(first);
  std::unique_ptr<SerialTransport> second;
  std::string error;
  EXPECT_EQ(SerialTransport::Open(link_, SerialOptions{}, &second, &error), IoStatus::kBusy);
  EXPECT_EQ(error, "serial " + link_ + ": busy (another program has it open)");
  first.reset();  // closing releases it
  EXPECT_EQ(SerialTransport::Open(link_, SerialOptions{}, &second, &error), IoStatus::kOk) << error;
}

TEST_F(SerialPty, AFileThatIsNoTtyIsRefused) {
  std::unique_ptr<SerialTransport> port;
  std::string error;
  EXPECT_EQ(SerialTransport::Open("/dev/null", SerialOptions{}, &port, &error), IoStatus::kIoError);
  EXPECT_NE(error.find("serial /dev/null: not a serial port"), std::string::npos) << error;
}

TEST(SerialDevice, ParsesPathBaudAndAuto) {
  SerialSpec spec;
  std::string error;
  ASSERT_TRUE(ParseSerialDevice("serial:/dev/ttyACM0", &spec, &error)) << error;
  EXPECT_EQ(spec.path, "/dev/ttyACM0");
  EXPECT_EQ(spec.baud, 115200u);
  EXPECT_FALSE(spec.automatic);
  ASSERT_TRUE(ParseSerialDevice("serial:/dev/ttyUSB1:250000", &spec, &error)) << error;
  EXPECT_EQ(spec.path, "/dev/ttyUSB1");
  EXPECT_EQ(spec.baud, 250000u);
  ASSERT_TRUE(ParseSerialDevice("serial:auto", &spec, &error));
  EXPECT_TRUE(spec.automatic);
  // A by-path name has colons of its own: the baud is the last field.
  ASSERT_TRUE(ParseSerialDevice("serial:/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0:9600",
                                &spec, &error))
      << error;
  EXPECT_EQ(spec.path, "/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0");
  EXPECT_EQ(spec.baud, 9600u);
}

TEST(SerialDevice, RefusesWhatItCannotUse) {
  SerialSpec spec;
  std::string error;
  EXPECT_FALSE(ParseSerialDevice("serial:", &spec, &error));
  EXPECT_NE(error.find("names no port"), std::string::npos);
  EXPECT_FALSE(ParseSerialDevice("serial:/dev/ttyACM0:fast", &spec, &error));
  EXPECT_NE(error.find("baud 'fast' is not a number"), std::string::npos) << error;
  EXPECT_FALSE(ParseSerialDevice("serial:/dev/ttyACM0:10", &spec, &error));
  EXPECT_NE(error.find("baud 10 is not within 50..4000000"), std::string::npos) << error;
  EXPECT_FALSE(ParseSerialDevice("serial::115200", &spec, &error));
}

TEST(SerialPorts, ListsWhatSysfsHasAndDescribesAPty) {
  for (const SerialPortInfo& port : ListSerialPorts()) {
    EXPECT_EQ(port.path.rfind("/dev/", 0), 0u) << port.path;
    EXPECT_FALSE(port.transport.empty());
  }
  Pty pty;
  const SerialPortInfo info = DescribeSerialPort(pty.name);
  EXPECT_EQ(info.path, pty.name);
  EXPECT_EQ(info.transport, "pty");
  EXPECT_EQ(info.VidPid(), "");
}

// A real tty that libserialport lists (a UART in sysfs, often /dev/ttyS0 in
// a VM or container): it opens and configures it itself.
TEST(SerialPorts, LibserialportOpensThePortsItLists) {
  for (const SerialPortInfo& listed : ListSerialPorts()) {
    std::unique_ptr<SerialTransport> port;
    std::string error;
    if (SerialTransport::Open(listed.path, SerialOptions{}, &port, &error) != IoStatus::kOk) {
      continue;  // no UART behind it (EIO), or in use
    }
    EXPECT_TRUE(port->opened_by_libserialport()) << listed.path;
    EXPECT_EQ(port->identity().transport, listed.transport);
    return;
  }
  GTEST_SKIP() << "no listed serial port can be opened here";
}

// The reconnect's rule for a USB port: the same VID:PID and serial number,
// wherever it comes back; a port without a USB serial is its path again.
TEST(SerialPorts, AUsbBoardIsFoundAgainByItsSerialNumberUnderAnotherPath) {
  SerialPortInfo mega;
  mega.path = "/dev/ttyACM0";
  mega.transport = "usb";
  mega.usb_vendor_id = 0x2341;
  mega.usb_product_id = 0x0042;
  mega.usb_serial = "85736323838351F0E1A1";
  SerialPortInfo back = mega;
  back.path = "/dev/ttyACM1";  // re-enumerated under another node
  SerialPortInfo other_mega = mega;
  other_mega.path = "/dev/ttyACM0";  // another board of the same kind took the old node
  other_mega.usb_serial = "7543830343635140B1C0";
  SerialPortInfo same_serial_other_vid = back;
  same_serial_other_vid.path = "/dev/ttyUSB0";
  same_serial_other_vid.usb_vendor_id = 0x0403;

  EXPECT_EQ(FindSamePort({other_mega, back}, mega), "/dev/ttyACM1");
  EXPECT_EQ(FindSamePort({other_mega, same_serial_other_vid}, mega), "") << "not back yet";
  EXPECT_EQ(FindSamePort({}, mega), "");

  SerialPortInfo pty;
  pty.path = "/tmp/board/ttyBOARD";
  pty.transport = "pty";
  EXPECT_EQ(FindSamePort({other_mega}, pty), "/tmp/board/ttyBOARD");
  SerialPortInfo usb_without_serial = mega;
  usb_without_serial.usb_serial.clear();
  usb_without_serial.path = "/dev/serial/by-id/usb-1a86_USB2.0-Serial-if00-port0";
  EXPECT_EQ(FindSamePort({back}, usb_without_serial), usb_without_serial.path);
}

}  // namespace
}  // namespace fdsurf::hal
