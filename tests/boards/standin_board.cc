// SPDX-License-Identifier: MIT
// fdsurf_standin_board: a stand-in for an emulated board, with the emulator
// harness interface (docs/boards.md): the real firmware Device runs on the
// host behind a Unix-domain socket, its step timer in virtual time kept in
// step with the wall clock, the bytes from the client delivered at the
// UART's byte timing, and the pins written as a waveform on SIGTERM/SIGINT
// or at the time limit. It lets the end-to-end driver, the serial relay and
// the checker be tested without an emulator, and is the control against
// which an emulated board's differences are told apart from the harness's.
//
//   fdsurf_standin_board --uart-socket PATH --waveform OUT [--time-limit-s N]
//                        [--tick-hz N] [--baud N] [--axes 2|3] [--elf IGNORED]
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <string>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/sim/waveform.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

struct Options {
  std::string elf;
  std::string socket_path;
  std::string waveform;
  double time_limit_s = 600;
  std::uint32_t tick_hz = 10000;
  std::uint32_t baud = 115200;
  int axes = 2;
};

// The listening socket and the one client it serves at a time.
class UartSocket {
 public:
  explicit UartSocket(const std::string& path) {
    listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    if (listen_fd_ < 0 || path.size() >= sizeof address.sun_path) {
      throw std::runtime_error(path + ": cannot create the socket");
    }
    std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
    unlink(path.c_str());
    if (bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
        listen(listen_fd_, 1) != 0) {
      throw std::runtime_error(path + ": cannot listen: " + std::strerror(errno));
    }
  }
  ~UartSocket() {
    if (client_fd_ >= 0) close(client_fd_);
    close(listen_fd_);
  }
  UartSocket(const UartSocket&) = delete;
  UartSocket& operator=(const UartSocket&) = delete;

  // Waits up to `timeout_ms` for something to happen; accepts a waiting
  // client, appends what the client sent to `received`.
  void Poll(int timeout_ms, std::deque<std::uint8_t>* received) {
    pollfd fd{client_fd_ >= 0 ? client_fd_ : listen_fd_, POLLIN, 0};
    if (poll(&fd, 1, timeout_ms) <= 0) return;
    if (client_fd_ < 0) {
      client_fd_ = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      return;
    }
    std::uint8_t buffer[512];
    const ssize_t n = read(client_fd_, buffer, sizeof buffer);
    if (n > 0) {
      received->insert(received->end(), buffer, buffer + n);
    } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
      close(client_fd_);  // the client left: accept the next one
      client_fd_ = -1;
    }
  }
  // Sends to the client; dropped if there is none (as a UART's TX line).
  void Send(const std::uint8_t* data, std::size_t size) {
    if (client_fd_ < 0) return;
    while (size > 0) {
      const ssize_t n = send(client_fd_, data, size, MSG_NOSIGNAL);
      if (n <= 0) return;
      data += n;
      size -= static_cast<std::size_t>(n);
    }
  }

 private:
  int listen_fd_ = -1;
  int client_fd_ = -1;
};

// The firmware, its outputs recorded in virtual time.
class Board {
 public:
  explicit Board(const Options& o)
      : options_(o), steppers_(clock_, static_cast<std::uint8_t>(o.axes)), pen_(clock_) {
    if (o.axes == 3) {
      device3_ = std::make_unique<fdsurf::device::Device<3>>(o.tick_hz);
    } else {
      device2_ = std::make_unique<fdsurf::device::Device<2>>(o.tick_hz);
    }
  }
  void OnByte(std::uint8_t byte) { device2_ ? device2_->OnByte(byte) : device3_->OnByte(byte); }
  std::size_t ReadOutput(std::uint8_t* data, std::size_t capacity) {
    return device2_ ? device2_->ReadOutput(data, capacity) : device3_->ReadOutput(data, capacity);
  }
  void Fill() { device2_ ? device2_->Fill() : device3_->Fill(); }
  void Tick(std::uint64_t t_us) {
    clock_.Set(t_us);
    (void)(device2_ ? device2_->Tick(steppers_, pen_) : device3_->Tick(steppers_, pen_));
  }
  void WriteWaveform(const std::string& path) const {
    fdsurf::sim::WaveformHeader header;
    header.board = "standin";
    header.extra["tick_hz"] = std::to_string(options_.tick_hz);
    fdsurf::sim::WaveformWriteOptions write;
    write.axes = options_.axes;
    std::ofstream out(path);
    fdsurf::sim::WriteWaveform(
        out, header,
        fdsurf::sim::TransitionsFromEvents(header, steppers_.events(), pen_.events(), write));
  }

 private:
  Options options_;
  fdsurf::hal::SimClock clock_;
  fdsurf::hal::SimStepDir steppers_;
  fdsurf::hal::SimPen pen_;
  std::unique_ptr<fdsurf::device::Device<2>> device2_;
  std::unique_ptr<fdsurf::device::Device<3>> device3_;
};

int Run(const Options& o) {
  UartSocket uart(o.socket_path);
  Board board(o);
  std::printf("ready\n");
  std::fflush(stdout);
  const auto start = std::chrono::steady_clock::now();
  const std::uint64_t tick_us = 1'000'000 / o.tick_hz;
  const double byte_us = 10e6 / o.baud;  // 8N1: ten bit times
  std::deque<std::uint8_t> received;
  double next_byte_us = 0;  // when the UART has the next received byte
  std::uint64_t tick = 0;
  std::uint8_t out[256];
  while (!g_stop) {
    uart.Poll(1, &received);
    const auto now_us =
        static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                       std::chrono::steady_clock::now() - start)
                                       .count());
    if (now_us > o.time_limit_s * 1e6) break;
    for (; tick * tick_us <= now_us; ++tick) {
      const double t = static_cast<double>(tick * tick_us);
      if (received.empty()) next_byte_us = std::max(next_byte_us, t);
      while (!received.empty() && next_byte_us + byte_us <= t) {
        board.OnByte(received.front());
        received.pop_front();
        next_byte_us += byte_us;
      }
      board.Fill();
      board.Tick(tick * tick_us);
      for (std::size_t n; (n = board.ReadOutput(out, sizeof out)) > 0;) uart.Send(out, n);
    }
  }
  board.WriteWaveform(o.waveform);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app("A stand-in board: the firmware Device on the host behind a Unix socket");
  app.add_option("--elf", o.elf, "accepted for the harness interface, not used");
  app.add_option("--uart-socket", o.socket_path, "the Unix socket to listen on")->required();
  app.add_option("--waveform", o.waveform, "where to write the pins")->required();
  app.add_option("--time-limit-s", o.time_limit_s, "stop after this much time")
      ->capture_default_str();
  app.add_option("--tick-hz", o.tick_hz, "the step timer (divides 1000000)")
      ->check(CLI::Range(100, 100000))
      ->capture_default_str();
  app.add_option("--baud", o.baud, "the UART's rate")->capture_default_str();
  app.add_option("--axes", o.axes, "2 or 3")->check(CLI::IsMember({2, 3}))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGINT, OnSignal);
  try {
    return Run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fdsurf_standin_board: error: %s\n", e.what());
    return 2;
  }
}
