// SPDX-License-Identifier: MIT
// The serial transport. libserialport opens and configures the ports it
// lists (real ttys, which it finds in sysfs); version 0.1.1 (Debian 12)
// refuses pseudo-terminals ("Device not found": they have no sysfs entry,
// and its maintainers keep ptys out of scope, sigrokproject/libserialport
// pull request #4), so those are configured here through termios, with the
// same settings. Reading, writing and the hang-up detection work on the file
// descriptor (poll, read, write) for both, because libserialport's blocking
// calls do not report a hang-up.
#include <errno.h>
#include <fcntl.h>
#include <libserialport.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>
#include <utility>

#include "fdsurf/hal/serial_transport.h"

namespace fdsurf {
namespace hal {
namespace {

using SteadyClock = std::chrono::steady_clock;

int RemainingMs(SteadyClock::time_point deadline) {
  const auto left =
      std::chrono::ceil<std::chrono::milliseconds>(deadline - SteadyClock::now()).count();
  return static_cast<int>(std::clamp<int64_t>(left, 0, 1'000'000'000));
}

// errno after a failed open, as a status and words.
IoStatus DescribeOpenErrno(int error, std::string* text) {
  switch (error) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
    case EIO:  // the slave of a pty whose master has gone
      *text = "no such port";
      return IoStatus::kNotFound;
    case EBUSY:
      *text = "busy (another program has it open)";
      return IoStatus::kBusy;
    case EACCES:
    case EPERM:
      *text =
          "permission denied (add yourself to the group that owns the port, usually dialout: "
          "sudo usermod -aG dialout $USER, then log in again)";
      return IoStatus::kPermissionDenied;
    default:
      *text = std::string("cannot open: ") + std::strerror(error);
      return IoStatus::kIoError;
  }
}

std::string OrMessage(const char* text) { return text == nullptr ? "unknown error" : text; }

bool BaudConstant(uint32_t baud, speed_t* speed) {
  static const struct {
    uint32_t baud;
    speed_t speed;
  } kSpeeds[] = {{50, B50},           {75, B75},           {110, B110},         {134, B134},
                 {150, B150},         {200, B200},         {300, B300},         {600, B600},
                 {1200, B1200},       {1800, B1800},       {2400, B2400},       {4800, B4800},
                 {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},
                 {115200, B115200},   {230400, B230400},   {460800, B460800},   {500000, B500000},
                 {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
                 {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000},
                 {3500000, B3500000}, {4000000, B4000000}};
  for (const auto& entry : kSpeeds) {
    if (entry.baud == baud) {
      *speed = entry.speed;
      return true;
    }
  }
  return false;
}

// Raw 8N1, no flow control, `baud`, through termios (ports libserialport
// does not take). A pty has no line rate: a baud termios has no constant for
// (250000) is accepted there and changes nothing. Returns "" or what failed.
std::string ConfigureTermios(int fd, uint32_t baud, bool pty, IoStatus* status) {
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    *status = IoStatus::kIoError;
    return std::string("not a serial port (") + std::strerror(errno) + ")";
  }
  cfmakeraw(&tio);
  tio.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS);
  tio.c_cflag |= CS8 | CLOCAL | CREAD;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  speed_t speed = B0;
  if (BaudConstant(baud, &speed)) {
    cfsetispeed(&tio, speed);
    cfsetospeed(&tio, speed);
  } else if (!pty) {
    *status = IoStatus::kInvalidArgument;
    return "baud " + std::to_string(baud) + " is not one termios can set";
  }
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    *status = IoStatus::kIoError;
    return std::string("cannot configure: ") + std::strerror(errno);
  }
  return "";
}

// Raw 8N1, no flow control, `baud`, through libserialport. Returns "" or
// what failed.
std::string ConfigureWithLibserialport(struct sp_port* port, uint32_t baud, IoStatus* status) {
  const auto failed = [&](const char* what) {
    *status = IoStatus::kIoError;
    char* message = sp_last_error_message();
    std::string text = std::string("cannot set ") + what + ": " + OrMessage(message);
    sp_free_error_message(message);
    return text;
  };
  if (sp_set_baudrate(port, static_cast<int>(baud)) != SP_OK) {
    std::string text = failed("the baud");
    *status = IoStatus::kInvalidArgument;
    return text;
  }
  if (sp_set_bits(port, 8) != SP_OK) return failed("8 data bits");
  if (sp_set_parity(port, SP_PARITY_NONE) != SP_OK) return failed("no parity");
  if (sp_set_stopbits(port, 1) != SP_OK) return failed("1 stop bit");
  if (sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE) != SP_OK) return failed("no flow control");
  return "";
}

// Non-blocking, VMIN 1 and VTIME 0: an empty line reads as EAGAIN, so that
// a read of 0 bytes (end of file) is always a hang-up. (With VMIN 0 a tty
// reads 0 bytes whenever nothing is there, O_NONBLOCK or not.)
void ReadOneByteAtLeast(int fd) {
  (void)fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) return;
  tio.c_cc[VMIN] = 1;
  tio.c_cc[VTIME] = 0;
  (void)tcsetattr(fd, TCSANOW, &tio);
}

// No hang-up on close (HUPCL clear): DTR stays asserted when the port is
// closed, so the next open raises no DTR edge and an Arduino that resets
// on that edge (the Mega's auto-reset) keeps running, with its homing,
// between two fdsurf commands. Only the first open after the board was
// plugged in (DTR low until then) resets it.
void KeepDtrAfterClose(int fd) {
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) return;
  tio.c_cflag &= ~static_cast<tcflag_t>(HUPCL);
  (void)tcsetattr(fd, TCSANOW, &tio);
}

}  // namespace

SerialTransport::SerialTransport(std::string path, const SerialOptions& options)
    : path_(std::move(path)), options_(options) {}

SerialTransport::~SerialTransport() { Close(); }

IoStatus SerialTransport::Open(const std::string& path, const SerialOptions& options,
                               std::unique_ptr<SerialTransport>* transport, std::string* error) {
  transport->reset();
  std::unique_ptr<SerialTransport> self(new SerialTransport(path, options));
  const IoStatus status = self->Attach(path, error);
  if (status != IoStatus::kOk) return status;
  self->identity_ = DescribeSerialPort(path);
  *transport = std::move(self);
  return IoStatus::kOk;
}

IoStatus SerialTransport::Attach(const std::string& node, std::string* error) {
  const std::string who = "serial " + path_ + ": ";
  char resolved[PATH_MAX];
  if (realpath(node.c_str(), resolved) == nullptr) {
    std::string text;
    const IoStatus status = DescribeOpenErrno(errno, &text);
    *error = who + text;
    return status;
  }
  struct sp_port* port = nullptr;
  int fd = -1;
  IoStatus status = IoStatus::kOk;
  std::string problem;
  if (sp_get_port_by_name(resolved, &port) == SP_OK) {
    if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
      status = DescribeOpenErrno(sp_last_error_code(), &problem);
    } else if (problem = ConfigureWithLibserialport(port, options_.baud, &status);
               problem.empty()) {
      (void)sp_get_port_handle(port, &fd);
    }
  } else {
    port = nullptr;
    fd = ::open(resolved, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      status = DescribeOpenErrno(errno, &problem);
    } else if (problem = ConfigureTermios(fd, options_.baud,
                                          std::strncmp(resolved, "/dev/pts/", 9) == 0, &status);
               !problem.empty()) {
      ::close(fd);
      fd = -1;
    }
  }
  // Exclusive: flock stops another cooperating program even as root,
  // TIOCEXCL every other non-root open.
  if (fd >= 0 && flock(fd, LOCK_EX | LOCK_NB) != 0) {
    status = errno == EWOULDBLOCK ? IoStatus::kBusy : IoStatus::kIoError;
    problem = status == IoStatus::kBusy ? "busy (another program has it open)"
                                        : std::string("cannot lock: ") + std::strerror(errno);
    if (port == nullptr) ::close(fd);
    fd = -1;
  }
  if (fd < 0) {
    if (port != nullptr) {
      (void)sp_close(port);
      sp_free_port(port);
    }
    *error = who + (problem.empty() ? "cannot open" : problem);
    return status == IoStatus::kOk ? IoStatus::kIoError : status;
  }
  (void)ioctl(fd, TIOCEXCL);
  ReadOneByteAtLeast(fd);
  KeepDtrAfterClose(fd);
  (void)tcflush(fd, TCIOFLUSH);
  fd_ = fd;
  sp_port_ = port;
  by_libserialport_ = port != nullptr;
  node_ = resolved;
  return IoStatus::kOk;
}

void SerialTransport::Close() {
  if (fd_ < 0) return;
  // A tty that stays open elsewhere (the pty's other side) keeps the flag.
  (void)ioctl(fd_, TIOCNXCL);
  (void)flock(fd_, LOCK_UN);
  if (sp_port_ != nullptr) {
    struct sp_port* port = static_cast<struct sp_port*>(sp_port_);
    (void)sp_close(port);
    sp_free_port(port);
    sp_port_ = nullptr;
  } else {
    ::close(fd_);
  }
  fd_ = -1;
}

IoStatus SerialTransport::Fail(IoStatus status, std::string detail) {
  last_error_ = "serial " + path_ + ": " + std::move(detail);
  return status;
}

IoStatus SerialTransport::HangUp(const std::string& during) {
  Close();
  return Fail(IoStatus::kDisconnected, "hung up (unplugged, or the other end closed) during " +
                                           during + "; call Reconnect()");
}

IoStatus SerialTransport::DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) {
  if (data == nullptr && size > 0) return Fail(IoStatus::kInvalidArgument, "write of null data");
  if (fd_ < 0) return Fail(IoStatus::kDisconnected, "disconnected; call Reconnect()");
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(timeout_ms);
  size_t sent = 0;
  const auto progress = [&] {
    return " after " + std::to_string(sent) + " of " + std::to_string(size) + " bytes";
  };
  while (sent < size) {
    const ssize_t n = ::write(fd_, data + sent, size - sent);
    if (n > 0) {
      sent += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN) {
      if (errno == EIO || errno == ENXIO || errno == ENODEV || errno == EPIPE) {
        return HangUp("write" + progress());
      }
      return Fail(IoStatus::kIoError,
                  std::string("write failed: ") + std::strerror(errno) + progress());
    }
    pollfd p{fd_, POLLOUT, 0};
    const int ready = ::poll(&p, 1, RemainingMs(deadline));
    if (ready == 0 || (ready < 0 && errno == EINTR && SteadyClock::now() >= deadline)) {
      return Fail(IoStatus::kTimeout,
                  "write timed out" + progress() + " (" + std::to_string(timeout_ms) + " ms)");
    }
    if (ready > 0 && (p.revents & (POLLHUP | POLLERR)) != 0) return HangUp("write" + progress());
  }
  return IoStatus::kOk;
}

IoStatus SerialTransport::DoRead(uint8_t* data, size_t capacity, size_t* received,
                                 uint32_t timeout_ms) {
  if (received != nullptr) *received = 0;
  if (data == nullptr || received == nullptr || capacity == 0) {
    return Fail(IoStatus::kInvalidArgument, "read into a null or empty buffer");
  }
  if (fd_ < 0) return Fail(IoStatus::kDisconnected, "disconnected; call Reconnect()");
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(timeout_ms);
  bool hung_up = false;
  while (true) {
    const ssize_t n = ::read(fd_, data, capacity);
    if (n > 0) {
      *received = static_cast<size_t>(n);
      return IoStatus::kOk;
    }
    // A hung-up tty reads as end of file; a pty whose master closed, EIO.
    if (n == 0 || hung_up) return HangUp("read");
    if (errno == EIO || errno == ENXIO || errno == ENODEV) return HangUp("read");
    if (errno != EAGAIN && errno != EINTR) {
      return Fail(IoStatus::kIoError, std::string("read failed: ") + std::strerror(errno));
    }
    pollfd p{fd_, POLLIN, 0};
    const int ready = ::poll(&p, 1, RemainingMs(deadline));
    // A signal ends the wait early, so that the caller sees it at once.
    if (ready == 0 || (ready < 0 && errno == EINTR)) {
      return Fail(IoStatus::kTimeout,
                  "nothing received within " + std::to_string(timeout_ms) + " ms");
    }
    if (ready < 0) return Fail(IoStatus::kIoError, std::string("poll: ") + std::strerror(errno));
    // Read once more: bytes may have come before the hang-up.
    hung_up = (p.revents & (POLLHUP | POLLERR)) != 0 && (p.revents & POLLIN) == 0;
    if ((p.revents & POLLNVAL) != 0) return Fail(IoStatus::kIoError, "poll: invalid descriptor");
  }
}

std::string FindSamePort(const std::vector<SerialPortInfo>& ports, const SerialPortInfo& identity) {
  if (identity.transport != "usb" || identity.usb_serial.empty()) return identity.path;
  for (const SerialPortInfo& port : ports) {
    if (port.usb_vendor_id == identity.usb_vendor_id &&
        port.usb_product_id == identity.usb_product_id && port.usb_serial == identity.usb_serial) {
      return port.path;
    }
  }
  return "";
}

std::string SerialTransport::FindAgain() const {
  if (identity_.transport != "usb" || identity_.usb_serial.empty()) return path_;
  return FindSamePort(ListSerialPorts(), identity_);
}

IoStatus SerialTransport::DoReconnect(uint32_t timeout_ms) {
  if (fd_ >= 0) return IoStatus::kOk;
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(timeout_ms);
  const std::string who =
      identity_.usb_serial.empty()
          ? path_
          : path_ + " (usb " + identity_.VidPid() + " serial " + identity_.usb_serial + ")";
  while (true) {
    const std::string node = FindAgain();
    std::string error = "serial " + who + ": no such port";
    IoStatus status = IoStatus::kNotFound;
    if (!node.empty()) status = Attach(node, &error);
    if (status == IoStatus::kOk) return IoStatus::kOk;
    if (SteadyClock::now() >= deadline) {
      // Back but not openable says why; not back is a timeout.
      if (status != IoStatus::kNotFound) {
        last_error_ = error;
        return status;
      }
      last_error_ = error + "; not back within " + std::to_string(timeout_ms) + " ms";
      return IoStatus::kTimeout;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(
        std::min<int64_t>(options_.reconnect_poll_ms, RemainingMs(deadline) + 1)));
  }
}

}  // namespace hal
}  // namespace fdsurf
