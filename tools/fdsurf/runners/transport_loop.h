// SPDX-License-Identifier: MIT
// The real-time loop that the usb and serial runners share: the host link
// over a hal::Transport (read, HostLink::OnBytes, Poll, write), reconnecting
// and resuming after a hang-up, the progress line, and Ctrl-C.
//
//   TransportLoop loop(transport, {"serial /dev/ttyACM0", ...});
//   if (!loop.Connect()) return 130;        // HELLO answered, or DeviceError
//   const StreamJob fitted = FitJobToDevice(job, *loop.link().hello(), ...);
//   return loop.Run(fitted, &progress);     // 0, or 130 after Ctrl-C
//
// A job with layers runs layer by layer: one layer is sent, run until the
// device reports it all executed and itself idle with the pen up, then
// PauseForLayer (runner.h) waits for the pen change while Turn() keeps the
// link serviced, and a resume HELLO precedes the next layer.
//
// Ctrl-C (SIGINT) or SIGTERM (with an InterruptGuard, runner.h), also
// during a pause: the first sends STOP, waits (bounded) for its
// acknowledgement and for the device to report itself at rest, says what
// was executed and makes Run() return 130; a second sends HALT (stop at once,
// pen up, motors off), waits briefly for its acknowledgement, returns 130.
//
// On a terminal, space or 'p' pauses the device (PAUSE: it decelerates along
// the path, lifts the pen and holds) and the same key resumes it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fdsurf/hal/transport.h"
#include "fdsurf/host/link.h"
#include "fdsurf/host/stream.h"
#include "journal.h"
#include "runner.h"

namespace fdsurf::host {

struct TransportLoopOptions {
  /// How messages name the device: "serial /dev/ttyACM0", "usb 1209:0001".
  std::string device;
  /// HELLO is retried (HostLink's retransmission) for this long: a board
  /// reset by opening its port is silent for 1-2 s first.
  std::uint32_t connect_timeout_ms = 10'000;
  /// How long a device that hung up may take to come back.
  std::uint32_t reconnect_timeout_ms = 30'000;
  /// After Ctrl-C: how long to wait for STOP's acknowledgement and for rest.
  std::uint32_t stop_timeout_ms = 10'000;
  /// After a second Ctrl-C: how long to wait for HALT's acknowledgement.
  std::uint32_t halt_timeout_ms = 2'000;
  bool quiet = false;
  /// Go on between layers without waiting for Enter (--no-pause).
  bool no_pause = false;
};

class TransportLoop {
 public:
  TransportLoop(hal::Transport& transport, TransportLoopOptions options);

  /// Sends HELLO until the device answers. Returns false after Ctrl-C.
  /// Throws DeviceError naming the device when nothing answers within
  /// connect_timeout_ms ("serial /dev/ttyACM0: no answer to HELLO within
  /// 10.0 s (7 sent): ..."), or the transport fails or stays away.
  bool Connect();

  /// Runs the job to the end, layer by layer with a pause for the pen
  /// change between them: 0, or 130 after Ctrl-C (see the top of this
  /// file). Throws DeviceError as Connect() does, when the device refuses
  /// the job, and when it reports the pen down at a layer's end.
  int Run(const StreamJob& job, ProgressLine* progress);

  /// Records the device's progress in `journal` (not owned; nullptr: none)
  /// from now on, and once more at the end, at a stop and at a halt.
  void set_journal(JobJournal* journal);

  /// Before Connect(), for --resume: a resume HELLO for `session` (the
  /// interrupted run's); if the device still has it, waits (at most
  /// reconnect_timeout_ms) until it has executed everything it accepted and
  /// returns its executed count: exact, where the journal may lag. nullopt
  /// when the device does not have the session (reset, power loss).
  std::optional<std::uint32_t> FinishOldSession(std::uint32_t session);

  FDSURF_NODISCARD HostLink& link() { return link_; }
  FDSURF_NODISCARD std::uint64_t reconnects() const { return reconnects_; }
  void set_reconnect_timeout_ms(std::uint32_t ms) { options_.reconnect_timeout_ms = ms; }
  void set_no_pause(bool no_pause) { options_.no_pause = no_pause; }

 private:
  // One turn: read (up to 2 ms), hand the bytes over, poll, write;
  // reconnects and resumes after a hang-up.
  void Turn();
  void Reconnect();
  // Turns until everything enqueued is executed and the device idle: false
  // after Ctrl-C; DeviceError when the link failed.
  bool RunToRest(std::uint64_t total_commands, ProgressLine* progress);
  // After Ctrl-C: STOP, then status until the device is at rest.
  int StopAndReport(std::uint64_t total_commands);
  // After a second Ctrl-C: HALT until acknowledged (briefly); 130.
  int HaltAndReport();
  // Status queries of our own after STOP (HostLink sends nothing more):
  // true once a report says the device is idle or faulted.
  bool AtRest(std::uint64_t now_us, std::string* state);

  hal::Transport& transport_;
  TransportLoopOptions options_;
  HostLink link_;
  std::vector<std::uint8_t> out_;
  std::uint64_t reconnects_ = 0;
  // The rest query after STOP.
  bool tap_ = false;
  protocol::FrameDecoderBuffer<protocol::kMaxFrameBytes> tap_decoder_;
  std::uint16_t rest_token_ = 0xFF00;
  std::uint64_t rest_query_us_ = 0;
  std::optional<protocol::StatusReport> rest_report_;
  JobJournal* journal_ = nullptr;
};

/// The job a usb or serial run sends, and its journal: with --resume the
/// rest of `fitted` after what the device or the journal says was executed
/// (ResumedJob; says so on stderr), else `fitted`; with --journal or
/// --resume a journal (of `job`, the job as planned) in `*journal`, given to
/// `loop`. `old_executed`: FinishOldSession's answer.
StreamJob JobWithJournal(const StreamOptions& o, const StreamJob& job, const StreamJob& fitted,
                         std::optional<std::uint32_t> old_executed, TransportLoop* loop,
                         std::optional<JobJournal>* journal);

/// `loop->Run(job, progress)`. When the device is lost mid-job (a
/// DeviceError: unplugged and not back, reset or powered off, so that it no
/// longer has the session) and a journal is kept, writes the journal once
/// more and adds to the error what it records and how to go on: home the
/// machine if it lost its position, then the same command with --resume.
int RunKeepingJournal(TransportLoop* loop, const StreamJob& job, ProgressLine* progress,
                      std::optional<JobJournal>* journal);

/// Seconds (an option) as whole milliseconds, rounded up.
std::uint32_t Milliseconds(double seconds);

/// The job as the device can run it: a device that ticks slower than the
/// job's speed needs (max_rate or travel_rate steps/s over HELLO's tick_hz)
/// gets that speed limit lowered to its tick rate, with a note on stderr
/// (unless quiet) that names the device and both speeds; a device of 64-bit
/// tables (protocol::kFeature64BitTables) gets every PREPARED_CURVE it could
/// not take in pieces (SplitForSixtyFourBitTables). DeviceError when the
/// device drives fewer axes than the job needs, or has no planner and the
/// job has PATCH or CURVE commands.
StreamJob FitJobToDevice(const StreamJob& job, const protocol::HelloReply& hello,
                         const std::string& device, const StreamOptions& o);

}  // namespace fdsurf::host
