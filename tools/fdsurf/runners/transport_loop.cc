// SPDX-License-Identifier: MIT
#include "transport_loop.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/motion/motion_loop.h"
#include "fdsurf/motion/turn_caps.h"
#include "fdsurf/protocol/codec.h"

namespace fdsurf::host {
namespace {

std::string Seconds(std::uint64_t us) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", static_cast<double>(us) * 1e-6);
  return text;
}

const char* StateName(protocol::DeviceState state) {
  switch (state) {
    case protocol::DeviceState::kIdle:
      return "idle";
    case protocol::DeviceState::kRunning:
      return "running";
    case protocol::DeviceState::kStopping:
      return "stopping";
    case protocol::DeviceState::kFault:
      return "fault";
    case protocol::DeviceState::kPaused:
      return "paused";
    case protocol::DeviceState::kHoming:
      return "homing";
  }
  return "unknown";
}

}  // namespace

TransportLoop::TransportLoop(hal::Transport& transport, TransportLoopOptions options)
    : transport_(transport), options_(std::move(options)), link_(LinkOptions()) {}

void TransportLoop::Reconnect() {
  if (!options_.quiet) {
    std::fprintf(stderr, "\nfdsurf: %s; waiting up to %s for it to come back\n",
                 transport_.LastError(), Seconds(options_.reconnect_timeout_ms * 1000ull).c_str());
  }
  // In slices, so that Ctrl-C is noticed while the device is away.
  const std::uint64_t deadline =
      hal::MonotonicClock::Now() + options_.reconnect_timeout_ms * 1000ull;
  while (true) {
    const std::uint64_t now = hal::MonotonicClock::Now();
    const auto slice = static_cast<std::uint32_t>(now >= deadline ? 0 : (deadline - now) / 1000);
    const hal::IoStatus status = transport_.Reconnect(std::min<std::uint32_t>(slice, 250));
    if (status == hal::IoStatus::kOk) break;
    if (status != hal::IoStatus::kTimeout) throw DeviceError(transport_.LastError());
    if (now >= deadline) {
      throw DeviceError(options_.device + ": lost and not back within " +
                        Seconds(options_.reconnect_timeout_ms * 1000ull) + "; gave up");
    }
    if (InterruptGuard::Interrupted()) {
      throw DeviceError(options_.device +
                        ": interrupted while the device was away: STOP could not be sent, so it "
                        "may still be moving");
    }
  }
  ++reconnects_;
  if (!options_.quiet)
    std::fprintf(stderr, "fdsurf: %s is back; resuming\n", options_.device.c_str());
  link_.Resume();
}

void TransportLoop::Turn() {
  const std::uint64_t now = hal::MonotonicClock::Now();
  std::uint8_t in[512];
  std::size_t got = 0;
  hal::IoStatus status = transport_.Read(in, sizeof in, &got, 2);
  if (status == hal::IoStatus::kOk) {
    link_.OnBytes(in, got, now);
    for (std::size_t i = 0; tap_ && i < got; ++i) {
      protocol::Reply reply;
      if (!tap_decoder_.OnByte(in[i]) || !tap_decoder_.frame().in_session) continue;
      if (protocol::DecodeReply(tap_decoder_.frame(), &reply).ok() &&
          reply.type == protocol::MessageType::kStatusReport && reply.seq == rest_token_) {
        rest_report_ = reply.body.status;
      }
    }
  }
  out_.clear();
  link_.Poll(now, &out_);
  if (journal_ != nullptr && link_.status()) journal_->Record(*link_.status());
  if (status != hal::IoStatus::kDisconnected && !out_.empty()) {
    status = transport_.Write(out_.data(), out_.size(), 1000);
  }
  if (status == hal::IoStatus::kDisconnected) {
    Reconnect();
  } else if (status != hal::IoStatus::kOk && status != hal::IoStatus::kTimeout) {
    throw DeviceError(transport_.LastError());
  }
}

bool TransportLoop::Connect() {
  const std::uint64_t start = hal::MonotonicClock::Now();
  while (!link_.Connected()) {
    if (InterruptGuard::Interrupted()) return false;
    if (link_.Failed())
      throw DeviceError(options_.device + ": " + DecodeDeviceError(link_.error()));
    const std::uint64_t waited = hal::MonotonicClock::Now() - start;
    if (waited >= options_.connect_timeout_ms * 1000ull) {
      throw DeviceError(options_.device + ": no answer to HELLO within " + Seconds(waited) + " (" +
                        std::to_string(link_.stats().hellos_sent) +
                        " sent): is it the right port and baud, and is the fdsurf firmware on "
                        "the board? (docs/serial.md)");
    }
    Turn();
  }
  return true;
}

int TransportLoop::Run(const StreamJob& job, ProgressLine* progress) {
  for (std::size_t from = 0;;) {
    const std::size_t to = NextLayerBoundary(job, from);
    progress->SetLayer(LayerLabel(job, from));
    Enqueue(job, &link_, from, to);
    if (!RunToRest(job.commands.size(), progress)) return StopAndReport(job.commands.size());
    if (to == job.commands.size()) {
      if (journal_ != nullptr) journal_->Record(*link_.status(), true);
      return 0;
    }
    // The job lifts the pen before every layer start (stream.cc); the
    // device's own report must agree before anyone reaches for the pen.
    if (link_.status()->pen_down) {
      throw DeviceError(options_.device + ": the pen is down at the end of " +
                        LayerLabel(job, from) + ": not pausing for a pen change");
    }
    if (!PauseForLayer(options_.no_pause, job, to, link_.status()->executed, [this] { Turn(); })) {
      return StopAndReport(job.commands.size());
    }
    // A fresh handshake (a resume HELLO) before the next layer: the link's
    // give-up clock starts again (the pause was no silence of the device's),
    // and a board reset or swapped during the pen change fails here, before
    // anything of the next layer is sent.
    link_.Resume();
    from = to;
  }
}

bool TransportLoop::RunToRest(std::uint64_t total_commands, ProgressLine* progress) {
  std::uint64_t last_progress = 0;
  // Space or 'p' pauses and resumes (the terminal comes back on every way out).
  PauseToggle pause(true, options_.quiet, progress);
  while (!link_.Finished() && !link_.Failed()) {
    if (InterruptGuard::Interrupted()) {
      progress->Finish();
      return false;
    }
    pause.Poll(&link_);
    Turn();
    const std::uint64_t now = hal::MonotonicClock::Now();
    if (now - last_progress > 250'000) {
      last_progress = now;
      progress->Show(link_.status() ? link_.status()->executed : 0, total_commands,
                     link_.stats().frames_sent, 0);
    }
  }
  progress->Finish();
  if (link_.Failed()) throw DeviceError(options_.device + ": " + DecodeDeviceError(link_.error()));
  return true;
}

bool TransportLoop::AtRest(std::uint64_t now_us, std::string* state) {
  if (rest_report_) {
    *state = StateName(rest_report_->state);
    if (rest_report_->state == protocol::DeviceState::kIdle ||
        rest_report_->state == protocol::DeviceState::kFault) {
      return true;
    }
  }
  if (now_us - rest_query_us_ >= 100'000) {
    rest_query_us_ = now_us;
    rest_report_.reset();
    rest_token_ = static_cast<std::uint16_t>(rest_token_ == 0xFFFF ? 0xFF00 : rest_token_ + 1);
    tap_decoder_.set_session(link_.session());
    std::array<std::uint8_t, protocol::kMaxEncodedFrameBytes> frame{};
    const std::size_t size =
        protocol::EncodeStatusQuery(rest_token_, frame.data(), frame.size(), link_.session());
    (void)transport_.Write(frame.data(), size, 100);
  }
  return false;
}

int TransportLoop::StopAndReport(std::uint64_t total_commands) {
  if (!options_.quiet) std::fprintf(stderr, "fdsurf: interrupted: stopping the device\n");
  link_.RequestStop();
  tap_ = true;
  const std::uint64_t deadline = hal::MonotonicClock::Now() + options_.stop_timeout_ms * 1000ull;
  std::string state = "unknown";
  bool rest = false;
  while (hal::MonotonicClock::Now() < deadline && !link_.Failed()) {
    if (InterruptGuard::Again()) return HaltAndReport();
    Turn();
    if (link_.StopAcknowledged() && (rest = AtRest(hal::MonotonicClock::Now(), &state))) break;
  }
  const std::uint64_t executed = rest_report_ ? rest_report_->executed : 0;
  if (journal_ != nullptr && rest_report_) journal_->Record(*rest_report_, true);
  if (!link_.StopAcknowledged()) {
    std::fprintf(stderr,
                 "fdsurf: error: %s did not acknowledge STOP within %s: it may still be moving\n",
                 options_.device.c_str(), Seconds(options_.stop_timeout_ms * 1000ull).c_str());
  } else if (!rest) {
    std::fprintf(stderr,
                 "fdsurf: error: %s acknowledged STOP but was not at rest within %s "
                 "(state %s)\n",
                 options_.device.c_str(), Seconds(options_.stop_timeout_ms * 1000ull).c_str(),
                 state.c_str());
  } else {
    std::fprintf(stderr,
                 "fdsurf: stopped: %s is at rest (%s, pen %s) after %llu of %llu commands "
                 "executed\n",
                 options_.device.c_str(), state.c_str(), rest_report_->pen_down ? "down" : "up",
                 static_cast<unsigned long long>(executed),
                 static_cast<unsigned long long>(total_commands));
  }
  return 130;
}

void TransportLoop::set_journal(JobJournal* journal) {
  journal_ = journal;
  if (journal_ != nullptr) {
    journal_->SetSession(link_.session());
    journal_->Flush();
  }
}

std::optional<std::uint32_t> TransportLoop::FinishOldSession(std::uint32_t session) {
  HostLinkOptions options = LinkOptions();
  options.new_session = false;
  options.session = session;
  HostLink old(options);
  const std::uint64_t deadline =
      hal::MonotonicClock::Now() + options_.reconnect_timeout_ms * 1000ull;
  std::vector<std::uint8_t> out;
  while (!old.Failed() && hal::MonotonicClock::Now() < deadline && !InterruptGuard::Interrupted()) {
    const std::uint64_t now = hal::MonotonicClock::Now();
    std::uint8_t in[512];
    std::size_t got = 0;
    if (transport_.Read(in, sizeof in, &got, 2) == hal::IoStatus::kOk) old.OnBytes(in, got, now);
    out.clear();
    old.Poll(now, &out);
    if (!out.empty()) (void)transport_.Write(out.data(), out.size(), 1000);
    // Nothing enqueued: Finished() once a report shows the device idle.
    const auto& status = old.status();
    if (old.Connected() && status && status->state == protocol::DeviceState::kIdle &&
        status->queued == 0) {
      return status->executed;
    }
    if (old.Connected() && status && status->state == protocol::DeviceState::kPaused) {
      old.RequestResume();  // a paused device would never finish
    }
  }
  return std::nullopt;
}

StreamJob JobWithJournal(const StreamOptions& o, const StreamJob& job, const StreamJob& fitted,
                         std::optional<std::uint32_t> old_executed, TransportLoop* loop,
                         std::optional<JobJournal>* journal) {
  if (o.resume_state == nullptr) {
    if (o.journal.empty()) return fitted;
    journal->emplace(o.journal, job, 0, 0);
    loop->set_journal(&**journal);
    return fitted;
  }
  const JournalState& state = *o.resume_state;
  const std::size_t executed = old_executed ? JobExecuted(state, *old_executed) : state.executed;
  if (!o.quiet) {
    std::fprintf(stderr, "fdsurf: resuming %s: %zu of %zu commands executed (%s)\n",
                 o.resume.c_str(), executed, fitted.commands.size(),
                 old_executed ? "as the device reports it"
                              : "as the journal says: the device does not have the session");
  }
  std::size_t prefix = 0;
  StreamJob rest = ResumedJob(fitted, executed, &prefix);
  journal->emplace(o.journal.empty() ? o.resume : o.journal, job, executed, prefix);
  loop->set_journal(&**journal);
  return rest;
}

int RunKeepingJournal(TransportLoop* loop, const StreamJob& job, ProgressLine* progress,
                      std::optional<JobJournal>* journal) {
  try {
    return loop->Run(job, progress);
  } catch (const DeviceError& e) {
    if (!journal->has_value()) throw;
    JobJournal& kept = **journal;
    kept.Flush();
    const JournalState& state = kept.state();
    throw DeviceError(std::string(e.what()) + "\nfdsurf: the journal " + kept.path() + " records " +
                      std::to_string(state.executed) + " of " + std::to_string(state.commands) +
                      " job commands executed; if the device was reset or lost power, home it "
                      "(fdsurf machine home), then run the same command with --resume " +
                      kept.path());
  }
}

int TransportLoop::HaltAndReport() {
  if (!options_.quiet) std::fprintf(stderr, "\nfdsurf: interrupted again: halting the device\n");
  link_.RequestHalt();
  const std::uint64_t deadline = hal::MonotonicClock::Now() + options_.halt_timeout_ms * 1000ull;
  while (hal::MonotonicClock::Now() < deadline && !link_.Failed() && !link_.HaltAcknowledged()) {
    Turn();
  }
  if (link_.HaltAcknowledged()) {
    std::fprintf(stderr,
                 "fdsurf: halted: %s stopped at once with the pen lifted and the motors "
                 "disabled (the position may be lost: home before the next job)\n",
                 options_.device.c_str());
  } else {
    std::fprintf(stderr,
                 "fdsurf: error: %s did not acknowledge HALT within %s: it may still be moving\n",
                 options_.device.c_str(), Seconds(options_.halt_timeout_ms * 1000ull).c_str());
  }
  return 130;
}

std::uint32_t Milliseconds(double seconds) {
  return static_cast<std::uint32_t>(std::ceil(std::clamp(seconds, 0.0, 4.0e6) * 1000.0));
}

namespace {

// A device ticking slower than the job's speeds: both speed limits lowered
// to one step per tick, in the CONFIG commands too, with a note.
void LowerToTickRate(const StreamJob& job, std::uint32_t tick_hz, const std::string& device,
                     const StreamOptions& o, StreamJob* fitted) {
  if (job.config.max_rate <= tick_hz && job.config.travel_rate <= tick_hz) return;
  fitted->config.max_rate = std::min(job.config.max_rate, tick_hz);
  fitted->config.travel_rate = std::min(job.config.travel_rate, tick_hz);
  for (protocol::Command& command : fitted->commands) {
    if (command.type != protocol::MessageType::kConfig) continue;
    command.body.config.max_rate = fitted->config.max_rate;
    command.body.config.travel_rate = fitted->config.travel_rate;
  }
  if (o.quiet) return;
  if (job.config.max_rate > tick_hz) {
    const double lowered = o.speed * tick_hz / job.config.max_rate;
    std::fprintf(stderr,
                 "fdsurf: note: %s ticks at %u Hz, one step per tick at most: the speed limit is "
                 "lowered from %u to %u steps/s (--speed %g %s/s becomes %.4g %s/s)\n",
                 device.c_str(), tick_hz, job.config.max_rate, tick_hz, o.speed, o.units.c_str(),
                 lowered, o.units.c_str());
  }
  // The pen-up limit is only named when --travel-speed made it differ.
  if (job.config.travel_rate > tick_hz && job.config.travel_rate != job.config.max_rate) {
    const double lowered = o.travel_speed * tick_hz / job.config.travel_rate;
    std::fprintf(stderr,
                 "fdsurf: note: %s ticks at %u Hz: the pen-up speed limit is lowered from %u to "
                 "%u steps/s (--travel-speed %g %s/s becomes %.4g %s/s)\n",
                 device.c_str(), tick_hz, job.config.travel_rate, tick_hz, o.travel_speed,
                 o.units.c_str(), lowered, o.units.c_str());
  }
}

// A device without turn caps (protocol::kFeatureNoTurnCaps) keeps each axis
// within its limit by a top speed at which no turn could need a cap; the
// note says what that speed is for this CONFIG, worked out with the
// firmware's own ToTickLimits() and TurnCaps::TopSpeedNoChordBinds().
void NoteTopSpeedWithoutTurnCaps(const protocol::MachineConfig& config, std::uint32_t tick_hz,
                                 const std::string& device) {
  motion::TickLimits per_tick{};
  if (!motion::ToTickLimits(device::MotionLimitsOf(config, tick_hz), &per_tick) ||
      per_tick.turn_budget == 0) {
    return;
  }
  const std::uint64_t top =
      static_cast<std::uint64_t>(motion::TurnCaps::TopSpeedNoChordBinds(per_tick.turn_budget)) *
          tick_hz >>
      motion::kLengthFracBits;
  if (top >= config.max_rate && top >= config.travel_rate) return;
  std::fprintf(stderr,
               "fdsurf: note: %s has no turn caps: it keeps every axis within its acceleration "
               "limit on any turn by running at %llu steps/s at most (the job's limits: %u "
               "drawing, %u travelling; a higher --axis-accel raises it)\n",
               device.c_str(), static_cast<unsigned long long>(top), config.max_rate,
               config.travel_rate);
}

}  // namespace

StreamJob FitJobToDevice(const StreamJob& job, const protocol::HelloReply& hello,
                         const std::string& device, const StreamOptions& o) {
  if (hello.max_axes < job.config.axes) {
    throw DeviceError(device + ": the device drives " + std::to_string(hello.max_axes) +
                      " axes; the job needs " + std::to_string(job.config.axes) + " (--dims)");
  }
  if ((hello.features & protocol::kFeaturePlanner) == 0) {
    for (const protocol::Command& command : job.commands) {
      if (command.type == protocol::MessageType::kPatch ||
          command.type == protocol::MessageType::kCurve) {
        throw DeviceError(device +
                          ": the device has no planner of its own (it takes PREPARED_CURVE, not "
                          "PATCH or CURVE): stream with --prepare-on-host");
      }
    }
  }
  StreamJob fitted = job;
  if ((hello.features & protocol::kFeature64BitTables) != 0) {
    SplitForSixtyFourBitTables(&fitted);
    const std::size_t more = fitted.commands.size() - job.commands.size();
    if (more > 0 && !o.quiet) {
      std::fprintf(stderr,
                   "fdsurf: note: %s steps 64-bit tables only: %zu more commands send the lines "
                   "it could not hold in pieces\n",
                   device.c_str(), more);
    }
  }
  LowerToTickRate(job, hello.tick_hz, device, o, &fitted);
  if ((hello.features & protocol::kFeatureNoTurnCaps) != 0 && !o.quiet) {
    NoteTopSpeedWithoutTurnCaps(fitted.config, hello.tick_hz, device);
  }
  return fitted;
}

}  // namespace fdsurf::host
