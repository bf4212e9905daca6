// SPDX-License-Identifier: MIT
// Streams a drawing to an emulated board over its harness's Unix socket
// (boards/microbit-v1/host/run_qemu.py --uart-socket PATH) with the host's
// own link (HostLink) and job builder (BuildStreamJob), until the serial
// backend of `fdsurf stream` can do it through a pty.
//
//   fdsurf_board_socket_stream --socket PATH [--lines N] [--fit MM] [--speed MM/S]
//                              [--timeout-s S] FILE
//
// Prints `key value` lines on stdout: the device's HELLO (tick_hz, queue),
// its final STATUS (position_x/y in steps, executed, moves, pen_down) and
// the link's counters. Exit 0 when every command was executed, 1 on bad
// arguments or a file that cannot be read, 3 when the link failed or the
// time ran out (the message names the socket).
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "fdsurf/host/link.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/toolpath.h"

namespace {

struct Options {
  std::string socket;
  std::string file;
  int lines = 3;
  double fit_mm = 10;
  double speed = 50;
  double timeout_s = 120;
};

std::uint64_t NowUs() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--socket" && has_value) {
      o->socket = argv[++i];
    } else if (arg == "--lines" && has_value) {
      o->lines = std::atoi(argv[++i]);
    } else if (arg == "--fit" && has_value) {
      o->fit_mm = std::atof(argv[++i]);
    } else if (arg == "--speed" && has_value) {
      o->speed = std::atof(argv[++i]);
    } else if (arg == "--timeout-s" && has_value) {
      o->timeout_s = std::atof(argv[++i]);
    } else if (!arg.empty() && arg[0] != '-' && o->file.empty()) {
      o->file = arg;
    } else {
      std::fprintf(stderr, "socket_stream: unknown or incomplete argument '%s'\n", arg.c_str());
      return false;
    }
  }
  if (o->socket.empty() || o->file.empty() || o->lines < 2 || o->fit_mm <= 0 || o->speed <= 0 ||
      o->timeout_s <= 0) {
    std::fprintf(stderr,
                 "usage: socket_stream --socket PATH [--lines N>=2] [--fit MM>0] [--speed MM/S>0]"
                 " [--timeout-s S>0] FILE\n");
    return false;
  }
  return true;
}

int ConnectUnix(const std::string& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (path.size() >= sizeof address.sun_path) return -1;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  const int fd = socket(AF_UNIX, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  if (connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

bool WriteAll(int fd, const std::vector<std::uint8_t>& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// Runs the link until the job is done, it fails, or the time runs out.
// Returns the error ("" on success).
std::string RunLink(int fd, fdsurf::host::HostLink* link, double timeout_s) {
  const std::uint64_t deadline = NowUs() + static_cast<std::uint64_t>(timeout_s * 1e6);
  std::vector<std::uint8_t> out;
  std::uint8_t in[512];
  while (!link->Finished() && !link->Failed()) {
    const std::uint64_t now = NowUs();
    if (now > deadline) return "the job did not finish in " + std::to_string(timeout_s) + " s";
    out.clear();
    link->Poll(now, &out);
    if (!out.empty() && !WriteAll(fd, out)) return "write failed (the harness went away)";
    const std::uint64_t next = link->NextPollUs(NowUs());
    const std::uint64_t wait_us = next > now ? next - now : 0;
    pollfd p{fd, POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(wait_us > 20'000 ? 20 : wait_us / 1000));
    if (ready > 0) {
      const ssize_t n = read(fd, in, sizeof in);
      if (n <= 0) return "the harness closed the socket";
      link->OnBytes(in, static_cast<std::size_t>(n), NowUs());
    }
  }
  return link->Failed() ? link->error() : "";
}

void PrintResults(const fdsurf::host::HostLink& link) {
  if (link.hello()) {
    std::printf("tick_hz %u\nqueue_capacity %u\n", static_cast<unsigned>(link.hello()->tick_hz),
                static_cast<unsigned>(link.hello()->queue_capacity));
  }
  if (link.status()) {
    const fdsurf::protocol::StatusReport& s = *link.status();
    std::printf("position_x %ld\nposition_y %ld\nexecuted %lu\nmoves %lu\npen_down %d\n",
                static_cast<long>(s.position[0]), static_cast<long>(s.position[1]),
                static_cast<unsigned long>(s.executed), static_cast<unsigned long>(s.moves),
                s.pen_down ? 1 : 0);
  }
  const fdsurf::host::HostLinkStats& st = link.stats();
  std::printf("commands %llu\nbytes_sent %llu\nbytes_received %llu\nretransmitted %llu\n",
              static_cast<unsigned long long>(link.enqueued()),
              static_cast<unsigned long long>(st.bytes_sent),
              static_cast<unsigned long long>(st.bytes_received),
              static_cast<unsigned long long>(st.retransmitted));
  std::printf("naks %llu\ntimeouts %llu\n", static_cast<unsigned long long>(st.naks),
              static_cast<unsigned long long>(st.timeouts));
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!ParseOptions(argc, argv, &o)) return 1;
  fdsurf::host::StreamJob job;
  try {
    const fdsurf::host::PatchSet set = fdsurf::host::ReadPatchFile(o.file);
    fdsurf::host::ToolpathOptions drawing;
    drawing.lines_s = o.lines;
    drawing.lines_t = o.lines;
    drawing.view = *fdsurf::host::NamedView("top");
    drawing.fit = std::array<double, 2>{o.fit_mm, o.fit_mm};
    drawing.margin = 1.0;
    fdsurf::host::MachineOptions machine;
    machine.speed = o.speed;
    job = fdsurf::host::BuildStreamJob(set, drawing, machine, "mm");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "socket_stream: %s: %s\n", o.file.c_str(), e.what());
    return 1;
  }
  const int fd = ConnectUnix(o.socket);
  if (fd < 0) {
    std::fprintf(stderr, "socket_stream: %s: cannot connect (%s)\n", o.socket.c_str(),
                 std::strerror(errno));
    return 3;
  }
  fdsurf::host::HostLink link;
  for (std::size_t i = 0; i < job.commands.size(); ++i) {
    if (!link.Enqueue(job.commands[i], job.labels[i]).ok()) {
      std::fprintf(stderr, "socket_stream: %s: refused by the codec\n", job.labels[i].c_str());
      return 1;
    }
  }
  const std::string error = RunLink(fd, &link, o.timeout_s);
  close(fd);
  PrintResults(link);
  if (!error.empty()) {
    std::fprintf(stderr, "socket_stream: %s: %s\n", o.socket.c_str(), error.c_str());
    return 3;
  }
  return 0;
}
