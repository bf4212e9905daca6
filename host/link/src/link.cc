// SPDX-License-Identifier: MIT
#include "fdsurf/host/link.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <limits>
#include <random>
#include <utility>

#include "fdsurf/status.h"

namespace fdsurf::host {
namespace {

using protocol::ErrorCode;
using protocol::MessageType;

const char* TypeName(MessageType type) {
  switch (type) {
    case MessageType::kHello:
      return "hello";
    case MessageType::kStatusQuery:
      return "status query";
    case MessageType::kStop:
      return "stop";
    case MessageType::kPause:
      return "pause";
    case MessageType::kResume:
      return "resume";
    case MessageType::kHalt:
      return "halt";
    case MessageType::kConfig:
      return "config";
    case MessageType::kPatch:
      return "patch";
    case MessageType::kCurve:
      return "curve";
    case MessageType::kMove:
      return "move";
    case MessageType::kPen:
      return "pen";
    case MessageType::kHome:
      return "home";
    case MessageType::kMotors:
      return "motors";
    default:
      return "frame";
  }
}

const char* const kAxisNames[] = {"x", "y", "z"};

// CONFIG's fields by index (docs/protocol.md, CONFIG).
const char* const kConfigFieldNames[] = {"axes",
                                         "steps_per_meter[x]",
                                         "steps_per_meter[y]",
                                         "steps_per_meter[z]",
                                         "travel_steps[x]",
                                         "travel_steps[y]",
                                         "travel_steps[z]",
                                         "max_rate",
                                         "accel",
                                         "pen_delay_ms",
                                         "travel_rate",
                                         "axis_accel[x]",
                                         "axis_accel[y]",
                                         "axis_accel[z]",
                                         "servo_up_us",
                                         "servo_down_us",
                                         "flags"};
static_assert(std::size(kConfigFieldNames) == protocol::kConfigFieldCount &&
                  protocol::kConfigFieldTravelRate == 10 && protocol::kConfigFieldAxisAccel == 11 &&
                  protocol::kConfigFieldServoUp == 14 && protocol::kConfigFieldFlags == 16,
              "a name for every CONFIG field, in wire order");

// The name of field `index` of a command body (docs/protocol.md numbers them).
std::string FieldName(MessageType type, uint8_t index) {
  namespace p = protocol;
  auto axis = [](int a) { return std::string(a < 3 ? kAxisNames[a] : "?"); };
  switch (type) {
    case MessageType::kConfig:
      if (index < p::kConfigFieldCount) {
        return kConfigFieldNames[index];
      }
      break;
    case MessageType::kPatch: {
      const std::array<const char*, 6> head = {"basis",   "dims",         "lines_s",
                                               "lines_t", "tolerance_q8", "skip_lines"};
      if (index < p::kPatchFieldGeometry) {
        return head[index];
      }
      const int g = index - p::kPatchFieldGeometry;
      if (g < 16 * protocol::kMaxAxes) {
        return "geometry " + axis(g / 16) + "[" + std::to_string(g % 16 / 4) + "][" +
               std::to_string(g % 4) + "]";
      }
      break;
    }
    case MessageType::kCurve: {
      const std::array<const char*, 3> head = {"basis", "dims", "tolerance_q8"};
      if (index < p::kCurveFieldGeometry) {
        return head[index];
      }
      const int g = index - p::kCurveFieldGeometry;
      if (g < 4 * protocol::kMaxAxes) {
        return "geometry " + axis(g / 4) + "[" + std::to_string(g % 4) + "]";
      }
      break;
    }
    case MessageType::kMove:
      if (index < p::kMoveFieldCount) {
        return "target[" + axis(index) + "]";
      }
      break;
    case MessageType::kPen:
      if (index == p::kPenFieldDown) {
        return "down";
      }
      break;
    case MessageType::kHome: {
      const std::array<const char*, 4> fields = {"axes", "toward_max", "rate", "backoff"};
      if (index < p::kHomeFieldCount) {
        return fields[index];
      }
      break;
    }
    case MessageType::kMotors:
      if (index == p::kMotorsFieldEnabled) {
        return "enabled";
      }
      break;
    default:
      break;
  }
  return "end of body";
}

}  // namespace

// A session id no other host is likely to have chosen: 32 random bits.
uint32_t RandomSession() {
  std::random_device device;
  const auto clock =
      static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  uint32_t session = 0;
  while (session == 0) {
    session = static_cast<uint32_t>(device()) ^ static_cast<uint32_t>(clock * 0x9E3779B97F4A7C15u);
  }
  return session;
}

HostLink::HostLink(HostLinkOptions options) : options_(options) {
  options_.window = std::clamp<uint16_t>(options_.window, 1, 0x7FFF);
  options_.retransmit_timeout_us = std::max<uint64_t>(options_.retransmit_timeout_us, 1);
  options_.max_retransmit_timeout_us =
      std::max(options_.max_retransmit_timeout_us, options_.retransmit_timeout_us);
  rto_us_ = options_.retransmit_timeout_us;
  session_ = options_.session != 0 ? options_.session : RandomSession();
  decoder_.set_session(session_);
}

protocol::DecodeResult HostLink::Enqueue(const protocol::Command& command, std::string label) {
  const protocol::DecodeResult result = protocol::ValidateFields(command);
  if (!result.ok()) {
    return result;
  }
  Pending pending;
  pending.type = command.type;
  pending.body.resize(protocol::kMaxBodyBytes);
  pending.body.resize(
      protocol::EncodeCommandBody(command, pending.body.data(), pending.body.size()));
  pending.label = std::move(label);
  queue_.push_back(std::move(pending));
  ++enqueued_;
  return result;
}

void HostLink::OnBytes(const uint8_t* data, size_t size, uint64_t now_us) {
  stats_.bytes_received += size;
  for (size_t i = 0; i < size; ++i) {
    if (!decoder_.OnByte(data[i])) {
      continue;
    }
    protocol::Reply reply;
    if (!protocol::DecodeReply(decoder_.frame(), &reply).ok()) {
      ++stats_.bad_replies;
      continue;
    }
    // A plain CRC is not of this session: only a device that predates
    // sessions, refusing the HELLO's version, is believed without the tag.
    if (!decoder_.frame().in_session && (reply.type != MessageType::kError ||
                                         reply.body.error.code != ErrorCode::kUnsupportedVersion)) {
      ++stats_.sessionless_replies;
      continue;
    }
    ++stats_.frames_received;
    if (state_ != State::kFailed) {
      HandleReply(reply, now_us);
    }
  }
}

void HostLink::HandleReply(const protocol::Reply& reply, uint64_t now_us) {
  switch (reply.type) {
    case MessageType::kHelloReply:
      HandleHelloReply(reply, now_us);
      return;
    case MessageType::kError:
      HandleError(reply, now_us);
      return;
    default:
      break;
  }
  if (state_ != State::kRunning) {
    return;  // left over from before a Resume(): the handshake decides
  }
  switch (reply.type) {
    case MessageType::kAck: {
      ++stats_.acks;
      const uint16_t before = base_seq_;
      if (Acknowledge(reply.body.ack.next_seq, reply.body.ack.credits, now_us) &&
          before == base_seq_) {
        ++stats_.duplicate_acks;
      }
      if (stop_sent_ && reply.seq == stop_token_) {
        stop_acked_ = true;
      }
      if (control_sent_ && reply.seq == control_token_) {
        control_acked_ = true;
      }
      return;
    }
    case MessageType::kNak: {
      ++stats_.naks;
      const protocol::Nak& nak = reply.body.nak;
      if (!Acknowledge(nak.next_seq, nak.credits, now_us)) {
        return;
      }
      if (nak.reason == ErrorCode::kQueueFull) {
        // The device refused base_seq_ for want of credit and drops what
        // follows: send again from there once credit is back.
        ++stats_.queue_full_naks;
        next_send_ = 0;
      } else if (!fast_retransmit_done_) {
        probe_ = false;
        // Go back to the device's next_seq at once. The other frames of
        // the old window still draw NAKs for the same seq; only the first
        // rewinds (per acknowledged position), else every stale NAK would
        // resend the whole window again.
        fast_retransmit_done_ = true;
        next_send_ = 0;
      }
      return;
    }
    case MessageType::kStatusReport: {
      if (!status_outstanding_ || reply.seq != status_token_) {
        return;  // an old query's answer
      }
      status_outstanding_ = false;
      Progress(now_us);
      status_ = reply.body.status;
      if (status_->state != protocol::DeviceState::kStopping) {
        waiting_for_rest_ = false;  // at rest (or running): try again
      }
      Acknowledge(status_->next_seq, status_->credits, now_us);
      if (status_->state == protocol::DeviceState::kFault) Fail(FaultMessage(*status_));
      return;
    }
    default:
      return;
  }
}

std::string HostLink::FaultMessage(const protocol::StatusReport& status) {
  if (status.error == protocol::ErrorCode::kEndstopHit) {
    // The axis and which end, and where it stopped: the position the
    // device reports is the last step it made.
    const unsigned axis = status.error_detail & 3u;
    if (axis < protocol::kMaxAxes) {
      const bool max = (status.error_detail & protocol::kEndstopHitMax) != 0;
      return std::string("device fault: ") + "XYZ"[axis] + (max ? " max" : " min") +
             " endstop hit during motion at step " + std::to_string(status.position[axis]) +
             ": the position is lost; home the machine (fdsurf machine home) before the next "
             "job";
    }
  }
  return "device fault: " + std::string(protocol::ErrorName(status.error)) + " (detail " +
         std::to_string(status.error_detail) + ")";
}

void HostLink::HandleHelloReply(const protocol::Reply& reply, uint64_t now_us) {
  if (state_ != State::kHandshake || !hello_sent_ || reply.seq != hello_token_) {
    return;
  }
  const protocol::HelloReply& h = reply.body.hello;
  hello_ = h;
  if (h.version != protocol::kProtocolVersion) {
    Fail("protocol version mismatch: device speaks " + std::to_string(h.version) + ", host " +
         std::to_string(protocol::kProtocolVersion));
    return;
  }
  if (!session_started_) {
    session_started_ = true;
    if (options_.new_session && h.next_seq != 0) {
      Fail("device did not start a new session (next_seq " + std::to_string(h.next_seq) + ")");
      return;
    }
    base_seq_ = h.next_seq;
  } else if (!Acknowledge(h.next_seq, h.credits, now_us)) {
    Fail("device lost the session on resume: it expects seq " + std::to_string(h.next_seq) +
         ", the host's unacknowledged commands start at seq " + std::to_string(base_seq_));
    return;
  }
  credits_ = h.credits;
  next_send_ = 0;
  Progress(now_us);
  probe_ = false;
  fast_retransmit_done_ = false;
  state_ = State::kRunning;
}

bool HostLink::Acknowledge(uint16_t next_seq, uint8_t credits, uint64_t now_us) {
  const size_t advance = static_cast<uint16_t>(next_seq - base_seq_);
  if (advance > sent_) {
    return false;  // behind base_seq_ (stale) or beyond anything sent (bogus)
  }
  if (advance > 0) {
    queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(advance));
    base_seq_ = next_seq;
    next_send_ = next_send_ > advance ? next_send_ - advance : 0;
    sent_ -= advance;
    Progress(now_us);
    probe_ = false;
    stopped_wait_started_ = false;
    fast_retransmit_done_ = false;
    progress_us_ = now_us;
  }
  credits_ = credits;
  return true;
}

void HostLink::Progress(uint64_t now_us) {
  retries_ = 0;
  rto_us_ = options_.retransmit_timeout_us;
  progress_at_ = now_us;
  progress_known_ = true;
}

void HostLink::HandleError(const protocol::Reply& reply, uint64_t now_us) {
  const protocol::ErrorReply& e = reply.body.error;
  std::string what;
  MessageType type = MessageType::kHello;
  if (state_ == State::kHandshake && hello_sent_ && e.seq == hello_token_) {
    if (e.code == ErrorCode::kUnsupportedVersion) {
      Fail("protocol version mismatch: device speaks " + std::to_string(e.detail) + ", host " +
           std::to_string(protocol::kProtocolVersion));
      return;
    }
    if (e.code == ErrorCode::kUnknownSession) {
      Fail(
          "device lost the session on resume: it does not have this host's session (it was "
          "reset, or another host started a session)");
      return;
    }
    what = "hello";
  } else if (const size_t index = static_cast<uint16_t>(e.seq - base_seq_); index < sent_) {
    // "Stopped": the device decelerates (after a STOP, or after a new
    // session cut the previous host's move short) and takes nothing until
    // it is at rest. Wait for that and send again, for a bounded time.
    if (e.code == ErrorCode::kStopped && index == 0 && !stop_requested_) {
      if (!stopped_wait_started_) {
        stopped_wait_started_ = true;
        stopped_since_us_ = now_us;
        ++stats_.stopped_waits;
      }
      if (now_us - stopped_since_us_ < options_.stopped_wait_us) {
        waiting_for_rest_ = true;
        next_send_ = 0;
        probe_ = false;
        return;
      }
    }
    what = Describe(index);
    type = queue_[index].type;
  } else if (status_outstanding_ && e.seq == status_token_) {
    what = "status query";
  } else if (stop_sent_ && e.seq == stop_token_) {
    what = halt_ ? "halt" : "stop";
  } else if (control_sent_ && e.seq == control_token_) {
    what = TypeName(control_type_);
  } else {
    what = "an unknown frame (seq " + std::to_string(e.seq) + ")";
  }
  std::string message = "device refused " + what + ": " + protocol::ErrorName(e.code);
  if (e.code == ErrorCode::kBadField || e.code == ErrorCode::kBadLength) {
    message += ", field " + std::to_string(e.detail) + " (" + FieldName(type, e.detail) + ")";
  } else if (e.code == ErrorCode::kPlannerRefused) {
    message += ": " + std::string(StatusMessage(static_cast<Status>(e.detail)));
  } else if (e.detail != 0) {
    message += " (detail " + std::to_string(e.detail) + ")";
  }
  Fail(message);
}

std::string HostLink::Describe(size_t index) const {
  const Pending& p = queue_[index];
  const std::string seq = "seq " + std::to_string(SeqOf(index));
  if (p.label.empty()) {
    return std::string(TypeName(p.type)) + " " + seq;
  }
  return p.label + " [" + TypeName(p.type) + ", " + seq + "]";
}

void HostLink::Fail(std::string message) {
  if (state_ == State::kFailed) {
    return;
  }
  state_ = State::kFailed;
  error_ = std::move(message);
}

bool HostLink::Timeout(uint64_t now_us, std::vector<uint8_t>* out) {
  ++stats_.timeouts;
  ++retries_;
  rto_us_ = std::min(rto_us_ * 2, options_.max_retransmit_timeout_us);
  if (now_us - progress_at_ < options_.give_up_after_us) {
    return false;
  }
  std::string waiting = "an answer";
  if (state_ == State::kHandshake) {
    waiting = "the hello reply";
  } else if (next_send_ > 0 && !queue_.empty()) {
    waiting = "the acknowledgement of " + Describe(0);
  } else if (status_outstanding_) {
    waiting = "a status report";
  } else if (stop_requested_) {
    waiting = halt_ ? "the acknowledgement of halt" : "the acknowledgement of stop";
  } else if (control_requested_ && !control_acked_) {
    waiting = std::string("the acknowledgement of ") + TypeName(control_type_);
  }
  // Tell the device to stop before giving up, so that it does not go on
  // with the commands it queued (twice: the line is evidently bad).
  if (session_started_) {
    SendStop(out);
    SendStop(out);
  }
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%.1f", static_cast<double>(now_us - progress_at_) * 1e-6);
  Fail("no answer from the device after " + std::to_string(retries_) + " retries in " + seconds +
       " s (waiting for " + waiting + ")");
  return true;
}

void HostLink::SendStop(std::vector<uint8_t>* out) {
  stop_token_ = next_token_++;
  std::array<uint8_t, protocol::kMaxEncodedFrameBytes> frame{};
  Send(frame.data(),
       halt_ ? protocol::EncodeHalt(stop_token_, frame.data(), frame.size(), session_)
             : protocol::EncodeStop(stop_token_, frame.data(), frame.size(), session_),
       out);
}

bool HostLink::PollControl(uint64_t now_us, std::vector<uint8_t>* out) {
  if (!control_requested_ || control_acked_) {
    return true;
  }
  if (control_sent_ && now_us - control_sent_us_ < Rto()) {
    return true;
  }
  if (control_sent_ && Timeout(now_us, out)) {
    return false;
  }
  // One token per request: an ACK of any of its transmissions counts.
  if (!control_sent_) {
    control_token_ = next_token_++;
  }
  std::array<uint8_t, protocol::kMaxEncodedFrameBytes> frame{};
  const size_t size =
      control_type_ == MessageType::kPause
          ? protocol::EncodePause(control_token_, frame.data(), frame.size(), session_)
          : protocol::EncodeResume(control_token_, frame.data(), frame.size(), session_);
  Send(frame.data(), size, out);
  control_sent_ = true;
  control_sent_us_ = now_us;
  return true;
}

void HostLink::Send(const uint8_t* frame, size_t size, std::vector<uint8_t>* out) {
  out->insert(out->end(), frame, frame + size);
  ++stats_.frames_sent;
  stats_.bytes_sent += size;
}

void HostLink::SendHello(uint64_t now_us, std::vector<uint8_t>* out) {
  hello_token_ = next_token_++;
  const bool fresh = !session_started_ && options_.new_session;
  const protocol::Hello hello{protocol::kProtocolVersion,
                              fresh ? protocol::kHelloFlagNewSession : uint8_t{0}, session_};
  std::array<uint8_t, protocol::kMaxEncodedFrameBytes> frame{};
  Send(frame.data(), protocol::EncodeHello(hello_token_, hello, frame.data(), frame.size()), out);
  hello_sent_ = true;
  hello_sent_us_ = now_us;
  ++stats_.hellos_sent;
}

void HostLink::SendStatusQuery(uint64_t now_us, std::vector<uint8_t>* out) {
  status_token_ = next_token_++;
  std::array<uint8_t, protocol::kMaxEncodedFrameBytes> frame{};
  Send(frame.data(),
       protocol::EncodeStatusQuery(status_token_, frame.data(), frame.size(), session_), out);
  status_outstanding_ = true;
  status_sent_us_ = now_us;
  ++stats_.status_queries;
}

uint64_t HostLink::RetransmitTimerStart() const {
  // The later of the oldest frame's last transmission and the last
  // acknowledgement that released something (RFC 6298, 5.3): on a slow line
  // a frame may wait in the port's buffer longer than the timeout while ACKs
  // for the frames before it keep arriving.
  return std::max(queue_.front().last_sent_us, progress_us_);
}

size_t HostLink::SendLimit() const {
  if (waiting_for_rest_) {
    return 0;
  }
  // After a timeout only the oldest frame goes (a probe): a window of patch
  // frames resent into a dead or lossy line is wasted; once the probe is
  // acknowledged, the rest follows (go-back-N from the device's next_seq).
  return std::min<size_t>({queue_.size(), options_.window, credits_,
                           probe_ ? size_t{options_.timeout_resend_frames} : SIZE_MAX});
}

void HostLink::Poll(uint64_t now_us, std::vector<uint8_t>* out) {
  const uint64_t rto = Rto();
  if (state_ == State::kFailed) {
    return;
  }
  if (!progress_known_) {
    progress_known_ = true;  // the give-up clock starts with the first Poll
    progress_at_ = now_us;
  }
  if (state_ == State::kHandshake) {
    const bool resend = hello_sent_ && now_us - hello_sent_us_ >= rto;
    if (!hello_sent_ || (resend && !Timeout(now_us, out))) {
      SendHello(now_us, out);
    }
    return;
  }
  if (stop_requested_) {
    if (!stop_acked_ && (!stop_sent_ || now_us - stop_sent_us_ >= rto)) {
      if (stop_sent_ && Timeout(now_us, out)) {
        return;
      }
      SendStop(out);
      stop_sent_ = true;
      stop_sent_us_ = now_us;
    }
    return;  // nothing else after a stop
  }
  if (!PollControl(now_us, out)) {
    return;
  }
  // Retransmit timeout: go back to the oldest unacknowledged frame.
  if (next_send_ > 0 && now_us - RetransmitTimerStart() >= rto) {
    if (Timeout(now_us, out)) {
      return;
    }
    next_send_ = 0;
    probe_ = options_.timeout_resend_frames != 0;
  }
  std::array<uint8_t, protocol::kMaxEncodedFrameBytes> frame{};
  for (const size_t limit = SendLimit(); next_send_ < limit; ++next_send_) {
    Pending& p = queue_[next_send_];
    Send(frame.data(),
         protocol::EncodeFrame(p.type, SeqOf(next_send_), p.body.data(), p.body.size(),
                               frame.data(), frame.size(), session_),
         out);
    p.last_sent_us = now_us;
    if (next_send_ < sent_) {
      ++stats_.retransmitted;
    } else {
      ++stats_.commands_sent;
      sent_ = next_send_ + 1;
    }
  }
  // Nothing in flight (all acknowledged, or waiting for credit): ask.
  if (next_send_ == 0) {
    if (status_outstanding_) {
      if (now_us - status_sent_us_ >= rto && !Timeout(now_us, out)) {
        SendStatusQuery(now_us, out);
      }
    } else if (!Finished() && (stats_.status_queries == 0 ||
                               now_us - status_sent_us_ >= options_.status_interval_us)) {
      SendStatusQuery(now_us, out);
    }
  }
}

uint64_t HostLink::NextPollUs(uint64_t now_us) const {
  constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();
  const uint64_t rto = Rto();
  switch (state_) {
    case State::kFailed:
      return kNever;
    case State::kHandshake:
      return hello_sent_ ? std::max(now_us, hello_sent_us_ + rto) : now_us;
    case State::kRunning:
      break;
  }
  if (stop_requested_) {
    if (stop_acked_) {
      return kNever;
    }
    return stop_sent_ ? std::max(now_us, stop_sent_us_ + rto) : now_us;
  }
  // A PAUSE or RESUME waiting for its ACK is due at its retransmission.
  const uint64_t control_due = !control_requested_ || control_acked_ ? kNever
                               : control_sent_ ? std::max(now_us, control_sent_us_ + rto)
                                               : now_us;
  return std::min(control_due, NextCommandPollUs(now_us));
}

uint64_t HostLink::NextCommandPollUs(uint64_t now_us) const {
  constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();
  const uint64_t rto = Rto();
  if (next_send_ < SendLimit()) {
    return now_us;
  }
  if (next_send_ > 0) {
    return std::max(now_us, RetransmitTimerStart() + rto);
  }
  if (status_outstanding_) {
    return std::max(now_us, status_sent_us_ + rto);
  }
  if (Finished()) {
    return kNever;
  }
  return stats_.status_queries == 0
             ? now_us
             : std::max(now_us, status_sent_us_ + options_.status_interval_us);
}

void HostLink::Resume() {
  if (state_ == State::kFailed) {
    return;
  }
  state_ = State::kHandshake;
  hello_sent_ = false;
  status_outstanding_ = false;
  stop_sent_ = false;
  control_sent_ = false;  // an unacknowledged PAUSE or RESUME goes again
  retries_ = 0;
  rto_us_ = options_.retransmit_timeout_us;
  progress_known_ = false;  // a fresh give-up clock from the next Poll
  probe_ = false;
  decoder_.Reset();
}

void HostLink::RequestStop() { stop_requested_ = true; }

void HostLink::RequestPause() {
  control_requested_ = true;
  control_type_ = MessageType::kPause;
  control_sent_ = false;
  control_acked_ = false;
}

void HostLink::RequestResume() {
  control_requested_ = true;
  control_type_ = MessageType::kResume;
  control_sent_ = false;
  control_acked_ = false;
}

void HostLink::RequestHalt() {
  stop_requested_ = true;
  halt_ = true;
  stop_sent_ = false;
  stop_acked_ = false;
}

bool HostLink::Finished() const {
  if (!AllAcknowledged() || !status_ || status_->next_seq != base_seq_) {
    return false;
  }
  if (status_->state != protocol::DeviceState::kIdle || status_->queued != 0) {
    return false;
  }
  // The executed count is since the device's session began: known only
  // when this host began it.
  return !options_.new_session || status_->executed == static_cast<uint32_t>(enqueued_);
}

}  // namespace fdsurf::host
