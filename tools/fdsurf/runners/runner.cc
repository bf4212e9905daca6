// SPDX-License-Identifier: MIT
#include "runner.h"

#include <poll.h>
#include <signal.h>
#include <termios.h>
#include <unistd.h>

#include <cstdio>
#include <regex>
#include <string>

#include "../cli_options.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/text.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/protocol/codec.h"

namespace fdsurf::host {
namespace {

volatile sig_atomic_t g_interrupts = 0;
struct sigaction g_previous_int {};
struct sigaction g_previous_term {};
// The terminal's settings while PauseKeys has changed them, for the exit on
// a third signal (tcsetattr is async-signal-safe).
termios g_saved_terminal{};
volatile sig_atomic_t g_terminal_saved = 0;

void OnInterrupt(int) {
  g_interrupts = g_interrupts + 1;
  if (g_interrupts >= 3) {
    if (g_terminal_saved != 0) tcsetattr(STDIN_FILENO, TCSANOW, &g_saved_terminal);
    static const char kMessage[] = "\nfdsurf: interrupted a third time: exiting at once\n";
    (void)!write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
    _exit(130);
  }
}

// The index in job.layers of the layer that command `command` belongs to.
std::size_t LayerIndex(const StreamJob& job, std::size_t command) {
  std::size_t index = 0;
  while (index + 1 < job.layers.size() && job.layers[index + 1].command <= command) ++index;
  return index;
}

// Until a line (Enter) or end of file arrives on stdin, or Ctrl-C: true for
// the line. `service` runs between the checks.
bool WaitForEnter(const std::function<void()>& service) {
  while (!InterruptGuard::Interrupted()) {
    if (service) service();
    pollfd in{STDIN_FILENO, POLLIN, 0};
    const int ready = ::poll(&in, 1, service ? 0 : 20);
    if (ready <= 0 || (in.revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
    // A terminal in canonical mode is readable once a whole line is typed;
    // a hang-up or Ctrl-D reads 0 bytes: go on then too, never spin.
    char line[256];
    const ssize_t got = ::read(STDIN_FILENO, line, sizeof line);
    if (got <= 0 ||
        std::string(line, static_cast<std::size_t>(got)).find('\n') != std::string::npos) {
      return !InterruptGuard::Interrupted();
    }
  }
  return false;
}

}  // namespace

InterruptGuard::InterruptGuard() {
  g_interrupts = 0;
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a wait in poll() ends at once
  sigaction(SIGINT, &action, &g_previous_int);
  sigaction(SIGTERM, &action, &g_previous_term);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
}

bool InterruptGuard::Interrupted() { return g_interrupts != 0; }

bool InterruptGuard::Again() { return g_interrupts >= 2; }

PauseKeys::PauseKeys(bool enabled) {
  if (!enabled || ::isatty(STDIN_FILENO) == 0 || g_terminal_saved != 0) return;
  termios settings{};
  if (tcgetattr(STDIN_FILENO, &settings) != 0) return;
  g_saved_terminal = settings;
  settings.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);  // ISIG stays: Ctrl-C signals
  settings.c_cc[VMIN] = 0;
  settings.c_cc[VTIME] = 0;
  g_terminal_saved = 1;
  if (tcsetattr(STDIN_FILENO, TCSANOW, &settings) != 0) {
    g_terminal_saved = 0;
    return;
  }
  active_ = true;
}

PauseKeys::~PauseKeys() {
  if (!active_) return;
  tcsetattr(STDIN_FILENO, TCSANOW, &g_saved_terminal);
  g_terminal_saved = 0;
}

bool PauseKeys::Pressed() {
  if (!active_) return false;
  bool pressed = false;
  for (;;) {
    pollfd in{STDIN_FILENO, POLLIN, 0};
    if (::poll(&in, 1, 0) <= 0 || (in.revents & POLLIN) == 0) return pressed;
    char keys[64];
    const ssize_t got = ::read(STDIN_FILENO, keys, sizeof keys);
    if (got <= 0) return pressed;
    for (ssize_t i = 0; i < got; ++i) {
      pressed = pressed || keys[i] == ' ' || keys[i] == 'p' || keys[i] == 'P';
    }
  }
}

PauseToggle::PauseToggle(bool enabled, bool quiet, ProgressLine* progress)
    : keys_(enabled), quiet_(quiet), progress_(progress) {
  progress_->SetPauseState(keys_.active(), false);
}

void PauseToggle::Poll(HostLink* link) {
  if (!keys_.Pressed()) return;
  paused_ = !paused_;
  if (paused_) {
    link->RequestPause();
  } else {
    link->RequestResume();
  }
  progress_->SetPauseState(true, paused_);
  if (!quiet_) {
    progress_->Finish();
    std::fprintf(stderr, paused_ ? "fdsurf: paused: space to resume\n" : "fdsurf: resumed\n");
  }
}

// Status queries four times a second: enough for the progress line and for
// noticing the end, few enough to leave the link to the commands.
HostLinkOptions LinkOptions() {
  HostLinkOptions options;
  options.status_interval_us = 250'000;
  return options;
}

void Enqueue(const StreamJob& job, HostLink* link) { Enqueue(job, link, 0, job.commands.size()); }

void Enqueue(const StreamJob& job, HostLink* link, std::size_t from, std::size_t to) {
  for (std::size_t k = from; k < to; ++k) {
    const protocol::DecodeResult result = link->Enqueue(job.commands[k], job.labels[k]);
    if (!result.ok()) {
      throw EngineError(job.labels[k] + ": cannot be sent: " + protocol::ErrorName(result.code) +
                        " (field " + std::to_string(result.field) + ", docs/protocol.md)");
    }
  }
}

// What a device error's detail number means, in words.
std::string DetailInWords(const std::string& error, unsigned detail) {
  using protocol::ErrorCode;
  if (error == protocol::ErrorName(ErrorCode::kOutOfTravel) && (detail & 0x7Fu) < 3) {
    const std::string axis = std::string("on ") + "XYZ"[detail & 3u];
    return (detail & motion::kUndecidedTravel) != 0
               ? axis + ": a line too close to the edge to prove inside (docs/motion.md)"
               : axis;
  }
  if (error == protocol::ErrorName(ErrorCode::kPlannerRefused) && detail < 256) {
    return StatusMessage(static_cast<Status>(detail));
  }
  if (error == protocol::ErrorName(ErrorCode::kOutputFailed) && detail < 256) {
    return hal::IoStatusName(static_cast<hal::IoStatus>(detail));
  }
  if (error == protocol::ErrorName(ErrorCode::kDimsMismatch)) return "axis count";
  return "detail " + std::to_string(detail);
}

std::string DecodeDeviceError(const std::string& message) {
  static const std::regex kDetail("([a-z][a-z ]*[a-z]) \\(detail ([0-9]+)\\)");
  std::string out;
  auto begin = message.cbegin();
  for (std::smatch m; std::regex_search(begin, message.cend(), m, kDetail); begin = m[0].second) {
    out.append(begin, m[0].first);
    out += m[1].str() + " (" + DetailInWords(m[1].str(), std::stoul(m[2].str())) + ")";
  }
  out.append(begin, message.cend());
  return out;
}

// A device moves at most one step per axis per tick.
void CheckSpeedAgainstTicks(const StreamJob& job, std::uint32_t tick_hz, const StreamOptions& o) {
  if (job.config.max_rate > tick_hz) {
    throw InputError("--speed " + FormatNumber(o.speed) + " " + o.units + "/s is " +
                     std::to_string(job.config.max_rate) + " steps/s, more than the device's " +
                     std::to_string(tick_hz) +
                     " ticks/s (one step per tick at most): lower --speed or raise --tick-hz");
  }
}

void ProgressLine::Show(std::uint64_t executed, std::uint64_t total, std::uint64_t frames,
                        double machine_seconds, bool force) {
  if (!enabled_) return;
  const auto now = Clock::now();
  if (!force && shown_ && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const double wall = std::chrono::duration<double>(now - start_).count();
  const int percent = total == 0 ? 100 : static_cast<int>(executed * 100 / total);
  constexpr int kWidth = 24;
  std::string bar(kWidth, '.');
  for (int i = 0; i < percent * kWidth / 100; ++i) bar[static_cast<std::size_t>(i)] = '#';
  // The simulator reports its machine time: show how much faster than
  // real time it runs; a real device runs in real time, so show the rate.
  char rate[64];
  if (machine_seconds > 0) {
    std::snprintf(rate, sizeof rate, "%.1f s machine time, %.0fx real time", machine_seconds,
                  wall > 0 ? machine_seconds / wall : 0.0);
  } else if (schedule_ != nullptr) {
    // The device has been on the next command since the count last changed.
    if (executed != last_executed_ || !shown_) {
      last_executed_ = executed;
      executed_changed_ = now;
    }
    const double running = std::chrono::duration<double>(now - executed_changed_).count();
    std::snprintf(rate, sizeof rate, "%s", DescribeTimeLeft(*schedule_, executed, running).c_str());
  } else {
    std::snprintf(rate, sizeof rate, "%.2f commands/s",
                  wall > 0 ? static_cast<double>(executed) / wall : 0.0);
  }
  const std::string layer = layer_.empty() ? std::string() : layer_ + " ";
  const char* hint = !pause_keys_ ? ""
                     : paused_    ? "  paused — space to resume"
                                  : "  [space: pause]";
  std::fprintf(
      stderr, "\rfdsurf: %s[%s] %3d%%  %llu/%llu commands executed, %llu frames sent, %s%s   ",
      layer.c_str(), bar.c_str(), percent, static_cast<unsigned long long>(executed),
      static_cast<unsigned long long>(total), static_cast<unsigned long long>(frames), rate, hint);
  shown_ = true;
}

std::size_t NextLayerBoundary(const StreamJob& job, std::size_t from) {
  // The first layer needs no pen change: the user put its pen in.
  for (std::size_t k = 1; k < job.layers.size(); ++k) {
    if (job.layers[k].command > from) return job.layers[k].command;
  }
  return job.commands.size();
}

std::string LayerLabel(const StreamJob& job, std::size_t command) {
  if (job.layers.size() < 2) return "";
  const std::size_t index = LayerIndex(job, command);
  return "layer " + std::to_string(index + 1) + "/" + std::to_string(job.layers.size()) + " '" +
         job.layers[index].name + "'";
}

std::string JobContents(const StreamJob& job) {
  std::string what = job.patches.empty() && job.curves.empty()
                         ? std::to_string(job.commands.size()) + " commands"
                         : DescribeDrawing(job.patches.size(), job.curves.size());
  if (job.layers.size() > 1) what += " in " + std::to_string(job.layers.size()) + " layers";
  return what;
}

bool PauseForLayer(bool no_pause, const StreamJob& job, std::size_t command, std::uint64_t executed,
                   const std::function<void()>& service) {
  const std::string layer = LayerLabel(job, command);
  std::fprintf(stderr, "fdsurf: %s: change the pen, then press Enter\n", layer.c_str());
  const bool terminal = ::isatty(STDIN_FILENO) != 0;
  if (no_pause || !terminal) {
    std::fprintf(stderr, "fdsurf: going on without waiting (%s); %llu of %zu commands executed\n",
                 no_pause ? "--no-pause" : "stdin is not a terminal",
                 static_cast<unsigned long long>(executed), job.commands.size());
    return !InterruptGuard::Interrupted();
  }
  if (!WaitForEnter(service)) return false;
  std::fprintf(stderr, "fdsurf: %s: going on\n", layer.c_str());
  return true;
}

void ProgressLine::Finish() {
  if (shown_) std::fputc('\n', stderr);
  shown_ = false;
}

}  // namespace fdsurf::host
