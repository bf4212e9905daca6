// SPDX-License-Identifier: MIT
// `fdsurf serve`'s server (tools/fdsurf/serve/gpio_server.h, unchanged) on a fake libgpiod 1.6
// (hal/test/fake_gpiod.cc, linked with --wrap) and a simulated carriage:
// the server's real pty, real time and real protocol, with GPIO lines that
// any machine has. Used by tests/cli/gpio_serve_cli_test.cc.
//
//   fdsurf_gpio_serve_fake --link PATH --report FILE [--start X,Y]
//                          [--tick-hz N] [--fail-pen-after-steps N]
//
// The chip gpiochip0 has 8 lines, given to serve as
//   gpio:gpiochip0:0,1,2,3,4,5:xmin=!6,ymin=!7
// STEP X 0, DIR X 1, STEP Y 2, DIR Y 3, ~EN 4 (active-low), PEN 5, and
// normally-open min switches pulling lines 6 and 7 low. Every rising STEP
// edge moves the carriage one step (towards negative when DIR is high); the
// switch of an axis closes where the carriage's real position, the counted
// steps plus --start's offset, reaches 0. --fail-pen-after-steps N makes
// every write to the pen line fail once N steps were made (EIO).
//
// Serve's own messages go to stderr. When serve returns (SIGINT, SIGTERM or
// a failed output), the report FILE gets key value lines: serve's exit code,
// steps and position per axis, the levels of the EN and PEN lines, the
// pen-down points counted once and their digest, the pen changes; and the
// process exits with serve's code.
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <set>
#include <string>
#include <utility>

#include "../../hal/test/fake_gpiod.h"
#include "../../tools/fdsurf/runners/runner.h"
#include "../../tools/fdsurf/serve/gpio_server.h"
#include "fdsurf/host/errors.h"

namespace {

using fdsurf::hal::testing::FakeGpio;

constexpr unsigned kStep[2] = {0, 2};
constexpr unsigned kDir[2] = {1, 3};
constexpr unsigned kEnable = 4;
constexpr unsigned kPen = 5;
constexpr unsigned kMinSwitch[2] = {6, 7};

struct Carriage {
  long start[2] = {0, 0};  // steps from the min switch at the start
  long steps[2] = {0, 0};  // counted, signed
  unsigned long step_edges[2] = {0, 0};
  int level[8] = {0, 0, 0, 0, 1, 0, 1, 1};  // EN high: drivers off
  long fail_pen_after_steps = -1;
  std::set<std::pair<long, long>> drawn;
  unsigned pen_changes = 0;

  // The digest of `drawn` (FNV-1a 64, as tests/support/pty_device.cc's).
  std::uint64_t DrawnDigest() const {
    std::uint64_t h = 14695981039346656037ull;
    for (const auto& [x, y] : drawn) {
      for (const long v : {x, y}) {
        for (int b = 0; b < 8; ++b) {
          h ^= static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * b));
          h *= 1099511628211ull;
        }
      }
    }
    return h;
  }

  void OnSet(FakeGpio& fake, unsigned offset, int value) {
    const int before = level[offset];
    level[offset] = value;
    if (offset == kPen && before != value) ++pen_changes;
    for (int a = 0; a < 2; ++a) {
      if (offset != kStep[a] || before != 0 || value != 1) continue;
      steps[a] += level[kDir[a]] != 0 ? -1 : 1;
      ++step_edges[a];
      if (level[kPen] != 0) drawn.insert({steps[0], steps[1]});
      // A closed normally-open switch pulls its line low.
      fake.chips["gpiochip0"].lines[kMinSwitch[a]].value = steps[a] + start[a] <= 0 ? 0 : 1;
    }
    if (fail_pen_after_steps >= 0 &&
        static_cast<long>(step_edges[0] + step_edges[1]) >= fail_pen_after_steps) {
      fake.chips["gpiochip0"].lines[kPen].set_errno = EIO;
    }
  }
};

bool ParseArgs(int argc, char** argv, fdsurf::host::ServeOptions* serve, std::string* report,
               Carriage* carriage) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const char* value = argv[i + 1];
    if (flag == "--link") {
      serve->link = value;
    } else if (flag == "--report") {
      *report = value;
    } else if (flag == "--tick-hz") {
      serve->tick_hz = static_cast<unsigned>(std::strtoul(value, nullptr, 10));
    } else if (flag == "--start") {
      if (std::sscanf(value, "%ld,%ld", &carriage->start[0], &carriage->start[1]) != 2) {
        return false;
      }
    } else if (flag == "--fail-pen-after-steps") {
      carriage->fail_pen_after_steps = std::strtol(value, nullptr, 10);
    } else {
      return false;
    }
  }
  return argc % 2 == 1 && !serve->link.empty() && !report->empty();
}

void WriteReport(const std::string& path, int code, const Carriage& c) {
  const std::string temporary = path + ".new";
  FILE* f = std::fopen(temporary.c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(f, "exit %d\nsteps_x %lu\nsteps_y %lu\nposition_x %ld\nposition_y %ld\n", code,
               c.step_edges[0], c.step_edges[1], c.steps[0] + c.start[0], c.steps[1] + c.start[1]);
  std::fprintf(f, "enable_level %d\npen_level %d\npen_changes %u\n", c.level[kEnable],
               c.level[kPen], c.pen_changes);
  std::fprintf(f, "drawn_points %zu\ndrawn_digest %016llx\n", c.drawn.size(),
               static_cast<unsigned long long>(c.DrawnDigest()));
  std::fclose(f);
  std::rename(temporary.c_str(), path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  fdsurf::host::ServeOptions serve;
  serve.device = "gpio:gpiochip0:0,1,2,3,4,5:xmin=!6,ymin=!7";
  std::string report;
  Carriage carriage;
  if (!ParseArgs(argc, argv, &serve, &report, &carriage)) {
    std::fprintf(stderr,
                 "fdsurf_gpio_serve_fake: --link PATH --report FILE [--start X,Y] [--tick-hz N] "
                 "[--fail-pen-after-steps N]\n");
    return 2;
  }
  FakeGpio fake;
  fake.AddChip("gpiochip0", 8);
  for (int a = 0; a < 2; ++a) {
    fake.chips["gpiochip0"].lines[kMinSwitch[a]].value = carriage.start[a] <= 0 ? 0 : 1;
  }
  fake.on_set = [&](unsigned offset, int value) { carriage.OnSet(fake, offset, value); };
  fdsurf::hal::testing::g_fake_gpio = &fake;
  int code = 0;
  try {
    code = fdsurf::host::ServeGpio(serve);
  } catch (const fdsurf::host::InputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    code = 2;
  } catch (const fdsurf::host::DeviceError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    code = 3;
  }
  WriteReport(report, code, carriage);
  return code;
}
