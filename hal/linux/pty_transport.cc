// SPDX-License-Identifier: MIT
#include "fdsurf/hal/pty_transport.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>

namespace fdsurf {
namespace hal {
namespace {

std::string ErrnoText(const std::string& what) { return what + ": " + std::strerror(errno); }

// Waits until `fd` is ready for `events`, at most `timeout_ms`: whether it is.
bool WaitFor(int fd, short events, uint32_t timeout_ms) {
  pollfd p{fd, events, 0};
  const int wait = timeout_ms > INT_MAX ? INT_MAX : static_cast<int>(timeout_ms);
  int ready = 0;
  do {
    ready = poll(&p, 1, wait);
  } while (ready < 0 && errno == EINTR);
  return ready > 0;
}

}  // namespace

IoStatus PtyTransport::Open(const std::string& link, std::unique_ptr<PtyTransport>* pty,
                            std::string* error) {
  int master = -1;
  int slave = -1;
  char name[PATH_MAX];
  if (openpty(&master, &slave, name, nullptr, nullptr) != 0) {
    *error = ErrnoText("pty: openpty");
    return IoStatus::kIoError;
  }
  termios tio{};
  bool ready = tcgetattr(slave, &tio) == 0;
  if (ready) {
    cfmakeraw(&tio);
    ready = tcsetattr(slave, TCSANOW, &tio) == 0 &&
            fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK) == 0;
  }
  if (!ready) {
    *error = ErrnoText(std::string("pty: setting up ") + name);
    close(master);
    close(slave);
    return IoStatus::kIoError;
  }
  const std::string temporary = link + ".new";
  unlink(temporary.c_str());
  if (symlink(name, temporary.c_str()) != 0 || rename(temporary.c_str(), link.c_str()) != 0) {
    const int failure = errno;
    *error = ErrnoText("pty: publishing " + std::string(name) + " as " + link);
    unlink(temporary.c_str());
    close(master);
    close(slave);
    return failure == ENOENT                       ? IoStatus::kNotFound
           : failure == EACCES || failure == EPERM ? IoStatus::kPermissionDenied
                                                   : IoStatus::kIoError;
  }
  pty->reset(new PtyTransport(master, slave, link, name));
  return IoStatus::kOk;
}

PtyTransport::~PtyTransport() {
  // Another server may have published its own pty at the same path since.
  char target[PATH_MAX];
  const ssize_t n = readlink(link_.c_str(), target, sizeof target - 1);
  if (n > 0 && std::string(target, static_cast<size_t>(n)) == slave_name_) unlink(link_.c_str());
  close(slave_);
  close(master_);
}

IoStatus PtyTransport::Failed(IoStatus status, const std::string& what) {
  last_error_ = "pty " + link_ + ": " + what;
  return status;
}

IoStatus PtyTransport::DoWrite(const uint8_t* data, size_t size, uint32_t timeout_ms) {
  if (data == nullptr && size > 0) return Failed(IoStatus::kInvalidArgument, "no data");
  size_t sent = 0;
  while (sent < size) {
    const ssize_t n = write(master_, data + sent, size - sent);
    if (n > 0) {
      sent += static_cast<size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && errno != EAGAIN) {
      return Failed(IoStatus::kIoError, ErrnoText("write"));
    } else if (!WaitFor(master_, POLLOUT, timeout_ms)) {
      return Failed(IoStatus::kTimeout, std::to_string(sent) + " of " + std::to_string(size) +
                                            " bytes written: the client is not reading");
    }
  }
  return IoStatus::kOk;
}

IoStatus PtyTransport::DoRead(uint8_t* data, size_t capacity, size_t* received,
                              uint32_t timeout_ms) {
  if (received != nullptr) *received = 0;
  if (data == nullptr || received == nullptr || capacity == 0) {
    return Failed(IoStatus::kInvalidArgument, "no buffer");
  }
  for (;;) {
    const ssize_t n = read(master_, data, capacity);
    if (n > 0) {
      *received = static_cast<size_t>(n);
      return IoStatus::kOk;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN) return Failed(IoStatus::kIoError, ErrnoText("read"));
    if (timeout_ms == 0 || !WaitFor(master_, POLLIN, timeout_ms)) return IoStatus::kTimeout;
    timeout_ms = 0;  // ready now: one more read
  }
}

IoStatus PtyTransport::DoReconnect(uint32_t /*timeout_ms*/) { return IoStatus::kOk; }

}  // namespace hal
}  // namespace fdsurf
