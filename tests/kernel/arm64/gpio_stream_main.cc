// SPDX-License-Identifier: MIT
// fdsurf-gpio-stream: `fdsurf stream --device gpio:...` for a job planned
// elsewhere, built for arm64 and run inside the QEMU guest (docs/testing.md,
// "GPIO on arm64 under QEMU").
//
//   fdsurf-gpio-stream JOB --device gpio:CHIP:LINES [--tick-hz N] [--quiet]
//   fdsurf-gpio-stream serve --device gpio:CHIP:LINES --link PATH [--tick-hz N]
//   fdsurf-gpio-stream JOB --serial PATH
//
// The second form is `fdsurf serve` (tools/fdsurf/serve/gpio_server.cc,
// ServeGpio, unchanged): the Device on the lines, served on a pty at PATH
// until SIGTERM. The third streams JOB to such a server as a client on the
// serial port PATH (termios, raw), the host end of the link (HostLink) as
// `fdsurf stream --device serial:PATH` drives it.
//
// JOB is the job's commands as wire frames, one after the other, as
// fdsurf_kernel_gpio_job writes them (its first command is the CONFIG). The
// job goes through the tool's own GPIO runner (tools/fdsurf/runners/
// gpio_runner.cc, RunGpio) unchanged: the firmware's Device in real time on
// the real kernel's GPIO character device through libgpiod. This binary
// leaves out only the readers and the planner (which need cairo, pugixml and
// the rest of the host library, not worth cross-building for a test).
//
// Exit codes as `fdsurf stream`: 0 done, 2 bad input (the job file, an
// option, --device), 3 the device failed (a GPIO line busy, missing, not
// permitted...), 130 interrupted. Errors are one line on stderr,
// "fdsurf: error: ...".
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../../../tools/fdsurf/runners/runner.h"
#include "../../../tools/fdsurf/serve/gpio_server.h"
#include "../../../tools/fdsurf/stream_command.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/link.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/frame.h"

namespace fdsurf::host {

// cli_options.cc's two helpers that the runners use. That file brings in the
// readers (SVG: pugixml), so this binary has its own: no progress line (the
// guest's console is not a terminal anyway), and the summary's wording.
bool ShowProgress(bool /*quiet*/) { return false; }

std::string DescribeDrawing(std::size_t patches, std::size_t curves) {
  return std::to_string(patches) + " patches and " + std::to_string(curves) + " curves";
}

namespace {

struct Options {
  std::string job;
  StreamOptions stream;
  bool serve = false;  // the first argument was `serve`
  std::string link;    // serve's --link
  std::string serial;  // --serial PATH: stream to a server there
};

Options ParseArguments(int argc, char** argv) {
  Options o;
  o.stream.device.clear();
  o.stream.no_pause = true;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (i == 1 && arg == "serve") {
      o.serve = true;
    } else if (arg == "--link" && has_value) {
      o.link = argv[++i];
    } else if (arg == "--serial" && has_value) {
      o.serial = argv[++i];
    } else if (arg == "--device" && has_value) {
      o.stream.device = argv[++i];
    } else if (arg == "--tick-hz" && has_value) {
      char* end = nullptr;
      const unsigned long hz = std::strtoul(argv[++i], &end, 10);
      if (*end != '\0' || hz == 0 || hz > 1'000'000) {
        throw InputError(std::string("--tick-hz: '") + argv[i] + "' is not 1 to 1000000");
      }
      o.stream.tick_hz = static_cast<std::uint32_t>(hz);
    } else if (arg == "--quiet") {
      o.stream.quiet = true;
    } else if (arg.rfind("--", 0) != 0 && o.job.empty()) {
      o.job = arg;
    } else {
      throw InputError("unexpected argument '" + arg +
                       "'; usage: fdsurf-gpio-stream JOB --device gpio:CHIP:LINES "
                       "[--tick-hz N] [--quiet]");
    }
  }
  const bool ok = o.serve ? o.job.empty() && !o.link.empty() && !o.stream.device.empty()
                          : !o.job.empty() && o.stream.device.empty() != o.serial.empty();
  if (!ok) {
    throw InputError(
        "usage: fdsurf-gpio-stream JOB --device gpio:CHIP:LINES [--tick-hz N], "
        "fdsurf-gpio-stream serve --device gpio:CHIP:LINES --link PATH [--tick-hz N], or "
        "fdsurf-gpio-stream JOB --serial PATH");
  }
  o.stream.file = o.job;
  return o;
}

// The job's commands from its frames; InputError naming the file and the
// frame (its index and byte offset) for anything that is not a command.
StreamJob ReadJob(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the job file");
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  StreamJob job;
  protocol::FrameDecoderBuffer<> decoder;
  std::size_t frame_start = 0;
  for (std::size_t k = 0; k < bytes.size(); ++k) {
    const auto byte = static_cast<std::uint8_t>(bytes[k]);
    const bool complete = decoder.OnByte(byte);
    if (byte != 0) continue;
    const std::string where = path + ": frame " + std::to_string(job.commands.size()) + " (byte " +
                              std::to_string(frame_start) + ")";
    if (!complete) throw InputError(where + ": not a valid frame (COBS or CRC)");
    protocol::Command command;
    const protocol::DecodeResult result = protocol::DecodeCommand(decoder.frame(), &command);
    if (!result.ok()) {
      throw InputError(where + ": not a command: " + protocol::ErrorName(result.code) + " (field " +
                       std::to_string(result.field) + ")");
    }
    if (job.commands.empty() && command.type != protocol::MessageType::kConfig) {
      throw InputError(where + ": the first command must be the CONFIG");
    }
    job.commands.push_back(command);
    job.labels.push_back("command " + std::to_string(job.commands.size() - 1) + " (" + path + ")");
    frame_start = k + 1;
  }
  if (frame_start != bytes.size()) {
    throw InputError(path + ": ends inside a frame (byte " + std::to_string(frame_start) + ")");
  }
  if (job.commands.empty()) throw InputError(path + ": no commands");
  job.config = job.commands.front().body.config;
  return job;
}

// The serial port at `path`, raw (8 bits, no echo, no translation) and
// non-blocking; InputError naming it when it cannot be opened.
int OpenSerial(const std::string& path) {
  const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  termios tio{};
  if (fd < 0 || tcgetattr(fd, &tio) != 0) {
    throw InputError("--serial " + path + ": " + std::strerror(errno));
  }
  cfmakeraw(&tio);
  tcsetattr(fd, TCSANOW, &tio);
  return fd;
}

// The job through HostLink on the serial port, until every command was
// executed and the device is idle (0), the link failed (3) or 60 s passed.
int StreamToServer(const Options& o, const StreamJob& job) {
  const int fd = OpenSerial(o.serial);
  HostLink link(LinkOptions());
  Enqueue(job, &link);
  hal::MonotonicClock clock;
  const std::uint64_t deadline = clock.NowMicros() + 60'000'000;
  std::vector<std::uint8_t> out;
  std::uint8_t in[256];
  while (!link.Finished() && !link.Failed() && clock.NowMicros() < deadline) {
    out.clear();
    link.Poll(clock.NowMicros(), &out);
    for (std::size_t sent = 0; sent < out.size();) {
      const ssize_t n = write(fd, out.data() + sent, out.size() - sent);
      if (n > 0) sent += static_cast<std::size_t>(n);
      if (n < 0 && errno != EAGAIN && errno != EINTR) {
        throw DeviceError("--serial " + o.serial + ": write: " + std::strerror(errno));
      }
    }
    pollfd p{fd, POLLIN, 0};
    (void)poll(&p, 1, 2);
    const ssize_t n = read(fd, in, sizeof in);
    if (n > 0) link.OnBytes(in, static_cast<std::size_t>(n), clock.NowMicros());
  }
  close(fd);
  if (link.Failed()) throw DeviceError("serial " + o.serial + ": " + link.error());
  if (!link.Finished()) throw DeviceError("serial " + o.serial + ": the job took over 60 s");
  if (!o.stream.quiet) {
    std::fprintf(stderr, "%s: %zu commands executed by the server at %s\n", o.job.c_str(),
                 job.commands.size(), o.serial.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace fdsurf::host

int main(int argc, char** argv) {
  using namespace fdsurf::host;
  try {
    Options o = ParseArguments(argc, argv);
    if (o.serve) {
      ServeOptions serve;
      serve.device = o.stream.device;
      serve.link = o.link;
      serve.tick_hz = o.stream.tick_hz;
      serve.quiet = o.stream.quiet;
      return ServeGpio(serve);
    }
    const StreamJob job = ReadJob(o.job);
    if (!o.serial.empty()) return StreamToServer(o, job);
    o.stream.dims = job.config.axes;
    return RunGpio(o.stream, job);
  } catch (const DeviceError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 3;
  } catch (const InputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 2;
  } catch (const EngineError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 3;
  }
}
