// SPDX-License-Identifier: MIT
// The host's end of the device link: a reliable, in-order, exactly-once
// sender of sequenced commands over an unreliable byte stream (go-back-N
// with cumulative ACKs, NAK-triggered fast retransmission, a single-frame
// probe on timeout, timeouts with backoff and a time bound, credit-based flow
// control, a session id of its own; docs/protocol.md).
//
// HostLink does no I/O and reads no clock: every call takes the current time
// in microseconds, Poll() appends the bytes to send now and OnBytes() takes
// what arrived. The same code drives a simulated device in virtual time and
// a USB serial port in real time.
//
//   HostLink link(options);
//   link.Enqueue(command, "patch 3 (teapot.bpt:12)");   // any number
//   while (!link.Finished() && !link.Failed()) {
//     std::vector<uint8_t> out;
//     link.Poll(now_us, &out);     // write `out` to the port
//     link.OnBytes(in, n, now_us); // whatever the port returned
//   }
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/frame.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf::host {

struct HostLinkOptions {
  /// Most commands in flight (sent, not yet acknowledged); the device's
  /// credits may lower it further. 1..0x7FFF.
  uint16_t window = 16;
  /// Time without progress after which the oldest unacknowledged frame is
  /// sent again (alone, as a probe; the rest follows its acknowledgement);
  /// also HELLO, STOP and status queries. The timer runs from the later of
  /// the frame's last transmission and the last acknowledgement that
  /// released a command. Each consecutive timeout doubles it, up to
  /// max_retransmit_timeout_us; progress sets it back.
  uint64_t retransmit_timeout_us = 200'000;
  uint64_t max_retransmit_timeout_us = 400'000;
  /// Time without any progress (an acknowledgement that releases a command,
  /// a matching HELLO_REPLY or STATUS_REPORT) after which the host gives up:
  /// it sends STOP and Failed() says "no answer from the device after N
  /// retries in T s". Bounded by time, not a count of tries, so that losing
  /// many frames in a row on a bad line is survived as long as the device
  /// answers now and then.
  uint64_t give_up_after_us = 30'000'000;
  /// While the device refuses commands with "stopped" (it decelerates from
  /// a stop, or from the previous host's session), wait for it to come to
  /// rest and try again, for at most this long.
  uint64_t stopped_wait_us = 30'000'000;
  /// After a timeout, resend at most this many frames from the oldest
  /// unacknowledged one (the rest follows their acknowledgement) instead of
  /// the whole window; 0: the whole window (go-back-N). A smaller resend
  /// saves bytes on a dead line but recovers slower on a lossy one: a window
  /// resent nearly always gets some acknowledgement back, one frame at 20 %
  /// faults 1 time in 4 (400 commands at 20 %: 7-8 s with 0, 8-10 s with 4,
  /// 18-23 s with 1; docs/protocol.md §6).
  uint16_t timeout_resend_frames = 0;
  /// Status queries while nothing is in flight (waiting for credit or for
  /// the device to finish).
  uint64_t status_interval_us = 50'000;
  /// HELLO with kHelloFlagNewSession: the device drops its queue and starts
  /// at seq 0. Without it the host continues at the device's next_seq (of
  /// the session `session`, which must then be given).
  bool new_session = true;
  /// The session id (protocol version 2): 0 picks a random one (never 0).
  /// Every frame but HELLO carries it folded into its CRC, so frames of
  /// another host's session are neither executed nor believed.
  uint32_t session = 0;
};

struct HostLinkStats {
  uint64_t frames_sent = 0;    ///< every frame: commands, HELLO, queries, STOP
  uint64_t bytes_sent = 0;     ///< on the wire, COBS and delimiters included
  uint64_t commands_sent = 0;  ///< first transmissions of commands
  uint64_t retransmitted = 0;  ///< later transmissions of commands
  uint64_t hellos_sent = 0;
  uint64_t status_queries = 0;
  uint64_t frames_received = 0;  ///< valid (CRC-checked, decodable) replies
  uint64_t bytes_received = 0;
  uint64_t bad_replies = 0;  ///< CRC-valid frames that did not decode
  uint64_t acks = 0;
  uint64_t duplicate_acks = 0;  ///< ACKs that acknowledged nothing new
  uint64_t naks = 0;
  uint64_t queue_full_naks = 0;
  uint64_t timeouts = 0;
  uint64_t sessionless_replies = 0;  ///< plain-CRC replies ignored (not of this session)
  uint64_t stopped_waits = 0;        ///< "stopped" refusals waited out
};

class HostLink {
 public:
  explicit HostLink(HostLinkOptions options = {});

  /// Appends a sequenced command to the job (its seq is assigned here, in
  /// order). `label` names it in error messages ("patch 3 (teapot.bpt:12)").
  /// The command is validated exactly as the device's decoder would: a
  /// result other than ok() means it was not enqueued (the field index is
  /// that of docs/protocol.md).
  [[nodiscard]] protocol::DecodeResult Enqueue(const protocol::Command& command,
                                               std::string label = {});

  /// Takes bytes received from the device.
  void OnBytes(const uint8_t* data, size_t size, uint64_t now_us);

  /// Appends to `out` whatever should be sent now: HELLO until answered,
  /// retransmissions after a timeout or NAK, new commands within the window
  /// and the device's credits, STOP, status queries. The Poll() that gives
  /// up (Failed() afterwards) leaves STOP in `out`: write it before
  /// checking Failed(), as every runner does.
  void Poll(uint64_t now_us, std::vector<uint8_t>* out);

  /// The earliest time at which Poll() will have something to do if no bytes
  /// arrive meanwhile (for event-driven and virtual-time loops); `now_us`
  /// if it has something to do now, UINT64_MAX if nothing is pending.
  FDSURF_NODISCARD uint64_t NextPollUs(uint64_t now_us) const;

  /// After a reconnect: re-handshake with a resume HELLO (no new-session
  /// flag), then continue from the device's next_seq. Drops any partly
  /// received frame. Fails if the device's next_seq is not within what the
  /// host has sent (the device lost the session).
  void Resume();

  /// Sends STOP (repeated until acknowledged) and no further commands.
  void RequestStop();
  FDSURF_NODISCARD bool StopAcknowledged() const { return stop_acked_ && !halt_; }

  /// PAUSE and RESUME (protocol version 3): sent, and repeated every
  /// retransmit timeout until the ACK echoing the token arrives; commands
  /// keep flowing meanwhile (the device queues them while it holds). A new
  /// request replaces one not yet acknowledged. Ignored after a stop.
  void RequestPause();
  void RequestResume();
  /// The last pause or resume request is acknowledged (and was a pause).
  FDSURF_NODISCARD bool PauseAcknowledged() const {
    return control_acked_ && control_type_ == protocol::MessageType::kPause;
  }
  FDSURF_NODISCARD bool ResumeAcknowledged() const {
    return control_acked_ && control_type_ == protocol::MessageType::kResume;
  }
  /// HALT, the emergency stop: sent instead of STOP (also after one), and
  /// repeated until acknowledged; nothing else is sent afterwards.
  void RequestHalt();
  FDSURF_NODISCARD bool HaltAcknowledged() const { return stop_acked_ && halt_; }

  /// Handshake done (a HELLO_REPLY arrived since the last Resume()).
  FDSURF_NODISCARD bool Connected() const { return state_ == State::kRunning; }
  /// Every enqueued command is acknowledged by the device.
  FDSURF_NODISCARD bool AllAcknowledged() const {
    return state_ == State::kRunning && queue_.empty();
  }
  /// All acknowledged and a status report (requested after the last
  /// acknowledgement) shows every command executed and the device idle.
  FDSURF_NODISCARD bool Finished() const;
  FDSURF_NODISCARD bool Failed() const { return state_ == State::kFailed; }
  /// What went wrong, when Failed().
  FDSURF_NODISCARD const std::string& error() const { return error_; }

  FDSURF_NODISCARD const HostLinkStats& stats() const { return stats_; }
  /// Frames the host's decoder dropped (CRC, COBS, overlong).
  FDSURF_NODISCARD const protocol::FrameDecoderStats& frame_stats() const {
    return decoder_.stats();
  }
  FDSURF_NODISCARD const std::optional<protocol::StatusReport>& status() const { return status_; }
  FDSURF_NODISCARD const std::optional<protocol::HelloReply>& hello() const { return hello_; }
  /// Commands enqueued since construction, and acknowledged.
  FDSURF_NODISCARD uint64_t enqueued() const { return enqueued_; }
  FDSURF_NODISCARD uint64_t acknowledged() const { return enqueued_ - queue_.size(); }
  /// This host's session id.
  FDSURF_NODISCARD uint32_t session() const { return session_; }

 private:
  enum class State { kHandshake, kRunning, kFailed };
  struct Pending {
    protocol::MessageType type;
    std::vector<uint8_t> body;
    std::string label;
    uint64_t last_sent_us = 0;
  };

  void HandleReply(const protocol::Reply& reply, uint64_t now_us);
  void HandleHelloReply(const protocol::Reply& reply, uint64_t now_us);
  // Cumulative acknowledgement: every seq before next_seq is accepted.
  // Returns false (and changes nothing) if next_seq is not one the host
  // has sent.
  bool Acknowledge(uint16_t next_seq, uint8_t credits, uint64_t now_us);
  void HandleError(const protocol::Reply& reply, uint64_t now_us);
  void Fail(std::string message);
  // The words of a kFault STATUS (an endstop hit names its axis and step).
  static std::string FaultMessage(const protocol::StatusReport& status);
  void Send(const uint8_t* frame, size_t size, std::vector<uint8_t>* out);
  void SendHello(uint64_t now_us, std::vector<uint8_t>* out);
  void SendStatusQuery(uint64_t now_us, std::vector<uint8_t>* out);
  // Counts a timeout and backs off; returns true (and sends STOP and fails)
  // once nothing progressed for give_up_after_us.
  bool Timeout(uint64_t now_us, std::vector<uint8_t>* out);
  void SendStop(std::vector<uint8_t>* out);
  // PAUSE or RESUME, when one is due; false when giving up.
  bool PollControl(uint64_t now_us, std::vector<uint8_t>* out);
  // NextPollUs() for the commands, status queries and the give-up clock.
  FDSURF_NODISCARD uint64_t NextCommandPollUs(uint64_t now_us) const;
  void Progress(uint64_t now_us);
  FDSURF_NODISCARD std::string Describe(size_t index) const;
  FDSURF_NODISCARD uint16_t SeqOf(size_t index) const {
    return static_cast<uint16_t>(base_seq_ + index);
  }
  FDSURF_NODISCARD size_t SendLimit() const;
  FDSURF_NODISCARD uint64_t Rto() const { return rto_us_; }
  FDSURF_NODISCARD uint64_t RetransmitTimerStart() const;

  HostLinkOptions options_;
  uint32_t session_ = 0;
  State state_ = State::kHandshake;
  std::string error_;
  bool session_started_ = false;  // a handshake has set base_seq_

  // Unacknowledged commands; queue_[i] has seq base_seq_ + i.
  std::deque<Pending> queue_;
  uint16_t base_seq_ = 0;
  size_t next_send_ = 0;  // queue_ index of the next frame to transmit
  size_t sent_ = 0;       // queue_ entries transmitted at least once
  uint8_t credits_ = 0;
  bool fast_retransmit_done_ = false;  // one NAK rewind per base_seq_
  uint64_t progress_us_ = 0;           // when base_seq_ last advanced

  uint16_t next_token_ = 1;
  uint16_t hello_token_ = 0;
  uint64_t hello_sent_us_ = 0;
  bool hello_sent_ = false;
  bool resume_ = false;

  uint16_t status_token_ = 0;
  bool status_outstanding_ = false;
  uint64_t status_sent_us_ = 0;
  bool status_fresh_ = false;  // status_ requested after the last acknowledgement

  bool stop_requested_ = false;
  bool stop_acked_ = false;
  uint16_t stop_token_ = 0;
  uint64_t stop_sent_us_ = 0;
  bool stop_sent_ = false;
  bool halt_ = false;  // the stop is a HALT

  bool control_requested_ = false;  // a PAUSE or RESUME is wanted
  protocol::MessageType control_type_ = protocol::MessageType::kPause;
  bool control_sent_ = false;
  bool control_acked_ = false;
  uint16_t control_token_ = 0;
  uint64_t control_sent_us_ = 0;

  int retries_ = 0;           // consecutive timeouts without progress
  uint64_t rto_us_ = 0;       // the retransmit timeout now (backed off)
  uint64_t progress_at_ = 0;  // last progress, for give_up_after_us
  bool progress_known_ = false;
  bool probe_ = false;             // after a timeout: resend only the oldest frame
  bool waiting_for_rest_ = false;  // the device said "stopped": poll until it is not
  uint64_t stopped_since_us_ = 0;
  bool stopped_wait_started_ = false;
  uint64_t enqueued_ = 0;

  std::optional<protocol::StatusReport> status_;
  std::optional<protocol::HelloReply> hello_;
  protocol::FrameDecoderBuffer<protocol::kMaxFrameBytes> decoder_;
  HostLinkStats stats_;
};

}  // namespace fdsurf::host
