// SPDX-License-Identifier: MIT
// fdsurf_board_stream_client: streams a small job to an emulated board's
// UART socket (fdsurf_simavr_board --uart-socket PATH) with the host end of
// the real link (HostLink), the job planned as `fdsurf stream` plans it.
// It exists to test the harness and the image before the serial backend
// (`--device serial:...`) is there, and stays as the socket's own client.
//
//   fdsurf_board_stream_client --socket PATH --file FILE [--patches N]
//       [--lines N] [--fit WxH] [--speed MM_S] [--accel MM_S2] [--timeout-s S]
//
// Prints "hello tick_hz=N ...", then "done executed=N x=X y=Y frames=N
// resent=N" with the device's final status. Exit 0 when the job finished,
// 2 for bad options or input, 3 when the link failed or timed out.
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/link.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/toolpath.h"

namespace fdsurf::host {
namespace {

struct ClientOptions {
  std::string socket_path;
  std::string file;
  int patches = 2;  // the first N patches of the file; 0: all
  int lines = 2;
  double fit_w = 60;
  double fit_h = 45;
  double speed = 50;
  double accel = 1000;
  double timeout_s = 120;
};

[[noreturn]] void Usage(const std::string& why) {
  std::fprintf(stderr,
               "fdsurf_board_stream_client: %s\nusage: fdsurf_board_stream_client --socket PATH "
               "--file FILE [--patches N] [--lines N] [--fit WxH] [--speed MM_S] "
               "[--accel MM_S2] [--timeout-s S]\n",
               why.c_str());
  std::exit(2);
}

double Number(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != 0 || !(value >= 0)) {
    Usage(option + ": '" + text + "' is not a number >= 0");
  }
  return value;
}

ClientOptions Parse(int argc, char** argv) {
  ClientOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) Usage(arg + ": needs a value");
    const std::string value = argv[++i];
    if (arg == "--socket") {
      o.socket_path = value;
    } else if (arg == "--file") {
      o.file = value;
    } else if (arg == "--patches") {
      o.patches = static_cast<int>(Number(arg, value));
    } else if (arg == "--lines") {
      o.lines = static_cast<int>(Number(arg, value));
    } else if (arg == "--fit") {
      const std::size_t x = value.find('x');
      if (x == std::string::npos) Usage("--fit: '" + value + "' is not WxH");
      o.fit_w = Number(arg, value.substr(0, x));
      o.fit_h = Number(arg, value.substr(x + 1));
    } else if (arg == "--speed") {
      o.speed = Number(arg, value);
    } else if (arg == "--accel") {
      o.accel = Number(arg, value);
    } else if (arg == "--timeout-s") {
      o.timeout_s = Number(arg, value);
    } else {
      Usage("unknown option " + arg);
    }
  }
  if (o.socket_path.empty() || o.file.empty()) Usage("--socket and --file are required");
  return o;
}

// The job for a device of `tick_hz`: at most one step a tick, so the speed
// is capped at tick_hz steps of 0.0125 mm a second.
StreamJob PlanJob(const ClientOptions& o, std::uint32_t tick_hz) {
  PatchSet set = ReadPatchFile(o.file);
  if (o.patches > 0 && static_cast<std::size_t>(o.patches) < set.patches.size()) {
    set.patches.resize(static_cast<std::size_t>(o.patches));
  }
  set.curves.clear();
  ToolpathOptions drawing;
  drawing.tolerance = 0.05;
  drawing.lines_s = o.lines;
  drawing.lines_t = o.lines;
  drawing.view = *NamedView("iso");
  drawing.fit = std::array<double, 2>{o.fit_w, o.fit_h};
  drawing.margin = 5;
  drawing.dims = 2;
  drawing.mode = StepMode::kStepExact;
  MachineOptions machine;
  machine.speed = std::min(o.speed, tick_hz * 0.0125);
  machine.accel = o.accel;
  machine.pen_delay_ms = 50;
  return BuildStreamJob(set, drawing, machine, "mm");
}

int Connect(const std::string& path) {
  sockaddr_un address{};
  if (path.size() >= sizeof address.sun_path) return -1;
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0 || connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    if (fd >= 0) close(fd);
    return -1;
  }
  return fd;
}

std::uint64_t NowUs() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

HostLinkOptions ClientLinkOptions() {
  HostLinkOptions options;
  options.status_interval_us = 250'000;
  // The Mega validates a patch for about 0.1-0.5 s before it answers.
  options.retransmit_timeout_us = 1'000'000;
  options.max_retransmit_timeout_us = 2'000'000;
  return options;
}

// One round of the link: what the board sent in, what the link has out.
// False when the socket failed.
bool Exchange(int fd, HostLink* link) {
  timeval wait{0, 2000};
  (void)setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof wait);
  std::uint8_t in[512];
  const ssize_t n = recv(fd, in, sizeof in, 0);
  if (n == 0) {
    std::fprintf(stderr, "fdsurf_board_stream_client: the board closed the socket\n");
    return false;
  }
  if (n > 0) link->OnBytes(in, static_cast<std::size_t>(n), NowUs());
  std::vector<std::uint8_t> out;
  link->Poll(NowUs(), &out);
  if (!out.empty() && send(fd, out.data(), out.size(), MSG_NOSIGNAL) < 0) {
    std::fprintf(stderr, "fdsurf_board_stream_client: send: %s\n", std::strerror(errno));
    return false;
  }
  return true;
}

// A session without commands, for the board's HELLO reply (its tick rate);
// 0 when it does not answer in time.
std::uint32_t AskTickRate(int fd, double timeout_s) {
  HostLink link(ClientLinkOptions());
  const std::uint64_t deadline = NowUs() + static_cast<std::uint64_t>(timeout_s * 1e6);
  while (!link.hello() && !link.Failed() && NowUs() < deadline) {
    if (!Exchange(fd, &link)) return 0;
  }
  if (!link.hello()) return 0;
  std::printf("hello tick_hz=%u queue=%u axes=%u\n", link.hello()->tick_hz,
              link.hello()->queue_capacity, link.hello()->max_axes);
  std::fflush(stdout);
  return link.hello()->tick_hz;
}

// The link until the job is finished, it fails, or the time runs out.
int Stream(int fd, const StreamJob& job, double timeout_s) {
  HostLink link(ClientLinkOptions());
  for (std::size_t k = 0; k < job.commands.size(); ++k) {
    if (!link.Enqueue(job.commands[k], job.labels[k]).ok()) {
      std::fprintf(stderr, "fdsurf_board_stream_client: %s cannot be sent\n",
                   job.labels[k].c_str());
      return 2;
    }
  }
  const std::uint64_t deadline = NowUs() + static_cast<std::uint64_t>(timeout_s * 1e6);
  while (!link.Finished() && !link.Failed() && NowUs() < deadline) {
    if (!Exchange(fd, &link)) return 3;
  }
  if (!link.Finished()) {
    std::fprintf(stderr, "fdsurf_board_stream_client: %s\n",
                 link.Failed() ? link.error().c_str() : "timed out");
    return 3;
  }
  const auto& status = *link.status();
  std::printf("done executed=%u x=%d y=%d frames=%llu resent=%llu\n", status.executed,
              status.position[0], status.position[1],
              static_cast<unsigned long long>(link.stats().frames_sent),
              static_cast<unsigned long long>(link.stats().retransmitted));
  return 0;
}

}  // namespace
}  // namespace fdsurf::host

int main(int argc, char** argv) {
  using namespace fdsurf::host;
  const ClientOptions o = Parse(argc, argv);
  const int fd = Connect(o.socket_path);
  if (fd < 0) {
    std::fprintf(stderr, "fdsurf_board_stream_client: --socket %s: %s\n", o.socket_path.c_str(),
                 std::strerror(errno));
    return 3;
  }
  const std::uint32_t tick_hz = AskTickRate(fd, 10);
  if (tick_hz == 0) {
    std::fprintf(stderr, "fdsurf_board_stream_client: --socket %s: no HELLO reply in 10 s\n",
                 o.socket_path.c_str());
    close(fd);
    return 3;
  }
  StreamJob job;
  try {
    job = PlanJob(o, tick_hz);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fdsurf_board_stream_client: %s: %s\n", o.file.c_str(), e.what());
    close(fd);
    return 2;
  }
  std::printf("job commands=%zu patches=%zu max_rate=%u\n", job.commands.size(), job.patches.size(),
              job.config.max_rate);
  std::fflush(stdout);
  const int rc = Stream(fd, job, o.timeout_s);
  close(fd);
  return rc;
}
