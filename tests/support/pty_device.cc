// SPDX-License-Identifier: MIT
// A serial device for tests, on a real kernel pseudo-terminal: the firmware's
// Device<2> runs here on the pty's master side and the slave is published
// under a stable symlink (hal/linux pty_transport.h, as `fdsurf serve`
// publishes itself), which the host opens as `serial:LINK`.
//
//   pty_device --link PATH [--report FILE] [--tick-hz 20000] [--speedup 1]
//              [--silent-ms N] [--never-answer] [--hangup-after-bytes N]
//              [--back-after-ms M] [--time-limit-s S] [--endstops X,Y]
//
// --silent-ms N          a board reset by DTR: from the first byte the host
//                        sends, N ms of bytes are read and ignored (the
//                        bootloader), then the firmware answers.
// --never-answer         reads everything, answers nothing.
// --hangup-after-bytes N after N bytes received, closes the pty (the host
//                        sees a hang-up); after --back-after-ms M (500) it
//                        opens a new pty and points the symlink at it. The
//                        Device keeps its state and keeps moving meanwhile.
// SIGUSR2               a power cut: the pty closes, the Device is rebuilt
//                        from nothing (no session, position 0, not homed,
//                        an empty queue), the pen goes up and the drivers
//                        off; the carriage stays where it physically is
//                        (the switches and the drawn points keep counting
//                        from where it started). After --back-after-ms M it
//                        comes back on a new pty, as a board powered again.
// --speedup K            K device ticks of 1/tick-hz s per real 1/tick-hz s.
// --endstops X,Y         min endstop switches on X and Y; the carriage starts
//                        X, Y steps from them (so HOME has to search).
//
// Prints "ready" once the link exists. On SIGTERM, SIGINT or the time limit
// (30 s) it writes the report (key value lines: executed commands, steps per
// axis, a digest of every step and pen change in order, stops received,
// HELLOs, duplicates, pen state, whether it was at rest; the points the pen
// was down on, counted once and as a digest of the set, and the pen-down
// steps counted with repeats; the power cuts) and exits 0. On
// SIGUSR1 it writes the report as it is now and goes on (a snapshot, e.g.
// while the host pauses between layers). The report is renamed into place,
// so a reader never sees half of one.
#include <signal.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/inputs.h"
#include "fdsurf/hal/outputs.h"
#include "fdsurf/hal/pty_transport.h"

namespace {

volatile sig_atomic_t g_quit = 0;
volatile sig_atomic_t g_snapshot = 0;
volatile sig_atomic_t g_power_cut = 0;
void OnSignal(int) { g_quit = 1; }
void OnSnapshot(int) { g_snapshot = 1; }
void OnPowerCut(int) { g_power_cut = 1; }

struct Options {
  std::string link;
  std::string report;
  uint32_t tick_hz = 20000;
  double speedup = 1;
  long silent_ms = 0;
  bool never_answer = false;
  long hangup_after_bytes = -1;
  long back_after_ms = 500;
  double time_limit_s = 30;
  bool endstops = false;
  long endstop_offset[2] = {0, 0};
};

// Counts steps per axis and folds every step and pen change, in order, into
// an FNV-1a digest (the 64-bit offset basis and prime of
// http://www.isthe.com/chongo/tech/comp/fnv/, as tests/kernel/gadget_device.cc):
// two runs that executed the same commands once each have
// the same digest.
class RecordingOutputs final : public fdsurf::hal::StepDirOutputs, public fdsurf::hal::PenOutput {
 public:
  RecordingOutputs() : StepDirOutputs(2) {}
  uint64_t steps[3] = {0, 0, 0};
  int64_t position[3] = {0, 0, 0};            // signed, for the endstops
  uint64_t digest = 14695981039346656037ull;  // FNV-1a 64-bit offset basis
  /// The same over the steps only (a pause adds a pen lift and lowering).
  uint64_t step_digest = 14695981039346656037ull;
  bool pen_down = false;
  bool enabled = false;
  /// Where the pen was down: each point once (its position after a step).
  std::set<std::pair<int64_t, int64_t>> drawn;
  /// Pen-down steps, repeats included (more than drawn.size() when a
  /// stretch was drawn twice).
  uint64_t pen_down_steps = 0;

  /// A digest of `drawn` (in its order, so of the set alone).
  uint64_t DrawnDigest() const {
    uint64_t h = 14695981039346656037ull;
    for (const auto& [x, y] : drawn) {
      for (const int64_t v : {x, y}) {
        for (int b = 0; b < 8; ++b) {
          h ^= static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * b));
          h *= 1099511628211ull;
        }
      }
    }
    return h;
  }

 private:
  void Fold(uint8_t byte) {
    digest ^= byte;
    digest *= 1099511628211ull;
  }
  fdsurf::hal::IoStatus DoSetEnabled(bool on) override {
    enabled = on;
    return fdsurf::hal::IoStatus::kOk;
  }
  fdsurf::hal::IoStatus DoSetDirections(uint8_t negative_mask) override {
    negative_ = negative_mask;
    return fdsurf::hal::IoStatus::kOk;
  }
  fdsurf::hal::IoStatus DoStep(uint8_t axis_mask) override {
    for (int a = 0; a < 3; ++a) {
      steps[a] += (axis_mask >> a) & 1u;
      if ((axis_mask >> a & 1u) != 0) position[a] += (negative_ >> a & 1u) != 0 ? -1 : 1;
    }
    if (pen_down) {
      drawn.insert({position[0], position[1]});
      ++pen_down_steps;
    }
    const auto byte = static_cast<uint8_t>(axis_mask | (negative_ & axis_mask) << 4);
    Fold(byte);
    step_digest ^= byte;
    step_digest *= 1099511628211ull;
    return fdsurf::hal::IoStatus::kOk;
  }
  fdsurf::hal::IoStatus DoSetPen(bool down) override {
    pen_down = down;
    Fold(down ? 0x81 : 0x80);
    return fdsurf::hal::IoStatus::kOk;
  }
  const char* DoLastError() const override { return ""; }
  uint8_t negative_ = 0;
};

// Min switches on X and Y where the carriage's real position (counted steps
// plus the start offset) reaches 0.
class MinSwitches final : public fdsurf::hal::EndstopInputs {
 public:
  MinSwitches(const RecordingOutputs& outputs, const long (&offset)[2])
      : outputs_(outputs), offset_{offset[0], offset[1]} {}

 private:
  fdsurf::hal::EndstopState DoFitted() const override { return {0x03, 0}; }
  fdsurf::hal::IoStatus DoRead(fdsurf::hal::EndstopState* state) override {
    state->min_mask = 0;
    state->max_mask = 0;
    for (int a = 0; a < 2; ++a) {
      if (outputs_.position[a] + offset_[a] <= 0) state->min_mask |= static_cast<uint8_t>(1u << a);
    }
    return fdsurf::hal::IoStatus::kOk;
  }
  const char* DoLastError() const override { return ""; }
  const RecordingOutputs& outputs_;
  long offset_[2];
};

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--never-answer") {
      o->never_answer = true;
    } else if (arg == "--link" && has_value) {
      o->link = argv[++i];
    } else if (arg == "--report" && has_value) {
      o->report = argv[++i];
    } else if (arg == "--tick-hz" && has_value) {
      o->tick_hz = static_cast<uint32_t>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--speedup" && has_value) {
      o->speedup = std::strtod(argv[++i], nullptr);
    } else if (arg == "--silent-ms" && has_value) {
      o->silent_ms = std::strtol(argv[++i], nullptr, 10);
    } else if (arg == "--hangup-after-bytes" && has_value) {
      o->hangup_after_bytes = std::strtol(argv[++i], nullptr, 10);
    } else if (arg == "--back-after-ms" && has_value) {
      o->back_after_ms = std::strtol(argv[++i], nullptr, 10);
    } else if (arg == "--endstops" && has_value) {
      o->endstops =
          std::sscanf(argv[++i], "%ld,%ld", &o->endstop_offset[0], &o->endstop_offset[1]) == 2;
      if (!o->endstops) {
        std::fprintf(stderr, "pty_device: --endstops X,Y (steps)\n");
        return false;
      }
    } else if (arg == "--time-limit-s" && has_value) {
      o->time_limit_s = std::strtod(argv[++i], nullptr);
    } else {
      std::fprintf(stderr, "pty_device: unknown or incomplete option '%s'\n", arg.c_str());
      return false;
    }
  }
  if (o->link.empty() || o->tick_hz == 0 || !(o->speedup > 0)) {
    std::fprintf(stderr, "pty_device: --link PATH is required; --tick-hz, --speedup > 0\n");
    return false;
  }
  return true;
}

using Clock = std::chrono::steady_clock;

long MsSince(Clock::time_point t) {
  return static_cast<long>(
      std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t).count());
}

struct Run {
  const Options& o;
  std::optional<fdsurf::device::Device<2>> device;  // rebuilt by a power cut
  RecordingOutputs outputs;
  MinSwitches switches{outputs, o.endstop_offset};
  std::unique_ptr<fdsurf::hal::PtyTransport> pty;  // none while hung up or powered off
  long bytes_in = 0;
  bool heard = false;  // a first byte arrived: the "reset" happened
  Clock::time_point first_byte;
  bool down = false;  // hung up, waiting to come back
  Clock::time_point down_since;
  uint64_t ticks_done = 0;
  unsigned power_cuts = 0;

  explicit Run(const Options& options) : o(options) { PowerOn(); }

  void PowerOn() {
    device.emplace(o.tick_hz);
    if (o.endstops) device->set_endstops(&switches);
  }

  // SIGUSR2: the device loses power (see the top of the file).
  void PowerCut() {
    pty.reset();  // the link goes with it
    down = true;
    down_since = Clock::now();
    outputs.pen_down = false;
    outputs.enabled = false;
    ++power_cuts;
    PowerOn();
  }

  // Publishes a new pty at the link: false (said why) when it cannot.
  bool OpenPty() {
    std::string error;
    if (fdsurf::hal::PtyTransport::Open(o.link, &pty, &error) == fdsurf::hal::IoStatus::kOk) {
      return true;
    }
    std::fprintf(stderr, "pty_device: %s\n", error.c_str());
    return false;
  }

  // Bytes in from the host (waiting up to 1 ms for the first), replies out.
  void Service() {
    uint8_t buffer[256];
    size_t n = 0;
    if (pty) {
      (void)pty->Read(buffer, sizeof buffer, &n, 1);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    for (size_t i = 0; i < n; ++i) {
      if (!heard) {
        heard = true;
        first_byte = Clock::now();
      }
      ++bytes_in;
      const bool silent = o.never_answer || MsSince(first_byte) < o.silent_ms;
      if (!silent) device->OnByte(buffer[i]);
      if (o.hangup_after_bytes >= 0 && bytes_in == o.hangup_after_bytes && !down) {
        pty.reset();  // the host sees a hang-up; the link goes with it
        down = true;
        down_since = Clock::now();
        break;
      }
    }
    for (size_t got; (got = device->ReadOutput(buffer, sizeof buffer)) > 0;) {
      if (pty) (void)pty->Write(buffer, got, 0);  // what the pty cannot take is lost, as on a wire
    }
    if (down && MsSince(down_since) >= o.back_after_ms) {
      down = false;
      if (!OpenPty()) g_quit = 1;
    }
  }

  // The ticks that are due by now, at the speed-up.
  void Tick(Clock::time_point start) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const auto due = static_cast<uint64_t>(elapsed * o.tick_hz * o.speedup);
    for (int budget = 4096; ticks_done < due && budget > 0; --budget, ++ticks_done) {
      (void)device->Tick(outputs, outputs);
    }
    ticks_done = std::max(ticks_done, due > 100000 ? due - 100000 : 0);
  }

  void Report() const {
    if (o.report.empty()) return;
    const std::string temporary = o.report + ".new";
    FILE* f = std::fopen(temporary.c_str(), "w");
    if (f == nullptr) return;
    const auto& stats = device->link_stats();
    std::fprintf(f, "executed %u\nsteps_x %llu\nsteps_y %llu\ndigest %016llx\n", device->executed(),
                 static_cast<unsigned long long>(outputs.steps[0]),
                 static_cast<unsigned long long>(outputs.steps[1]),
                 static_cast<unsigned long long>(outputs.digest));
    std::fprintf(f, "stops %u\nhellos %u\nduplicates %u\naccepted %u\npen_down %d\nidle %d\n",
                 stats.stops, stats.hellos, stats.duplicates, stats.commands_accepted,
                 outputs.pen_down ? 1 : 0, device->Idle() ? 1 : 0);
    std::fprintf(f, "bytes_in %ld\n", bytes_in);
    fdsurf::protocol::StatusReport status{};
    device->FillStatus(&status);
    std::fprintf(f, "pauses %u\nresumes %u\nhalts %u\nstep_digest %016llx\nenabled %d\nstate %d\n",
                 stats.pauses, stats.resumes, stats.halts,
                 static_cast<unsigned long long>(outputs.step_digest), outputs.enabled ? 1 : 0,
                 static_cast<int>(status.state));
    std::fprintf(f, "drawn_points %zu\ndrawn_digest %016llx\npen_down_steps %llu\npower_cuts %u\n",
                 outputs.drawn.size(), static_cast<unsigned long long>(outputs.DrawnDigest()),
                 static_cast<unsigned long long>(outputs.pen_down_steps), power_cuts);
    std::fclose(f);
    std::rename(temporary.c_str(), o.report.c_str());
  }
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!ParseOptions(argc, argv, &o)) return 2;
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  struct sigaction snapshot {};
  snapshot.sa_handler = OnSnapshot;
  sigaction(SIGUSR1, &snapshot, nullptr);
  struct sigaction power_cut {};
  power_cut.sa_handler = OnPowerCut;
  sigaction(SIGUSR2, &power_cut, nullptr);
  signal(SIGPIPE, SIG_IGN);
  auto run = std::make_unique<Run>(o);
  if (!run->OpenPty()) return 1;
  std::printf("ready\n");
  std::fflush(stdout);
  const Clock::time_point start = Clock::now();
  while (g_quit == 0 &&
         std::chrono::duration<double>(Clock::now() - start).count() < o.time_limit_s) {
    run->Service();
    run->device->Fill();
    run->Tick(start);
    if (g_power_cut != 0) {
      g_power_cut = 0;
      run->PowerCut();
    }
    if (g_snapshot != 0) {
      g_snapshot = 0;
      run->Report();
    }
  }
  run->Report();
  run->pty.reset();
  return 0;
}
