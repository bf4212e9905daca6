// SPDX-License-Identifier: MIT
// The device's end of the link: frames in, replies out, sequencing,
// acknowledgements and credits. docs/protocol.md gives the rules; in short:
//
//  - A sequenced command whose seq is the expected one (next_seq) is decoded,
//    validated and offered to the sink; if the sink accepts it, next_seq
//    advances and the reply is ACK(next_seq, credits). Refused (invalid, or
//    the sink says no) → ERROR(seq, code, field or detail), next_seq stays.
//  - A seq up to 0x8000 behind next_seq is a duplicate of an accepted
//    command: ACK(next_seq, credits) again, never re-executed. This is what
//    makes delivery exactly-once in order.
//  - A seq ahead of next_seq (something before it was lost) → NAK(next_seq,
//    credits, kOutOfOrder), dropped; the host goes back to next_seq.
//  - The expected seq with no credit left → NAK(next_seq, 0, kQueueFull).
//  - HELLO, STATUS_QUERY, STOP, PAUSE, RESUME and HALT are answered at once
//    and echo their token.
//  - Sessions (protocol version 2): a new-session HELLO names the session;
//    every other frame, both ways, carries its tag in the CRC (frame.h). A
//    frame of another session fails the CRC check and is dropped unanswered;
//    so is any frame but HELLO before the first session. A resume HELLO for
//    a session the device does not have is refused (kUnknownSession).
//
// Header-only, templated on the sink, so the freestanding core needs no
// virtual functions. The link does no I/O and needs no clock: feed it bytes
// with OnByte() and drain its replies with ReadOutput().
//
// The Sink concept (duck-typed; the device's command queue implements it):
//
//   // Queue `command` (already validated by the codec) for execution, or
//   // refuse it. Return ErrorCode::kNone to accept; otherwise the code for
//   // the ERROR reply, with *detail its detail byte (a field index for
//   // kBadField, the fdsurf::Status for kPlannerRefused, else 0). Called at
//   // most once per sequence number and only when Credits() > 0.
//   protocol::ErrorCode Accept(const protocol::Command& command, uint8_t* detail);
//   uint8_t Credits() const;        // free command slots now
//   uint8_t QueueCapacity() const;  // command slots in all, >= 1
//   uint32_t TickHz() const;        // motion ticks per second
//   uint8_t MaxAxes() const;        // 2 or 3
//   uint8_t Features() const;       // HelloReply::features (kFeature... bits)
//   // Everything but next_seq (the link sets that).
//   void FillStatus(protocol::StatusReport* report) const;
//   void Stop();   // STOP: stop motion, drop the queue
//   void Pause();  // PAUSE: come to rest along the path, keep the queue, hold
//   void Resume(); // RESUME: go on after a pause (nothing if not paused)
//   void Halt();   // HALT: stop at once, drop everything, motors off
//   void Reset();  // new session: drop the queue and all state (HELLO flag)
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/frame.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf {
namespace protocol {

/// What the device link did, since construction.
struct DeviceLinkStats {
  uint32_t commands_accepted;  ///< sink accepted, next_seq advanced
  uint32_t duplicates;         ///< already accepted seq, re-acknowledged
  uint32_t out_of_order;       ///< seq ahead of next_seq, NAKed
  uint32_t queue_full;         ///< expected seq without credit, NAKed
  uint32_t errors;             ///< ERROR replies sent
  uint32_t hellos;             ///< HELLOs answered (new session or resume)
  uint32_t status_queries;
  uint32_t stops;
  uint32_t pauses;           ///< PAUSE frames handled (repeats included)
  uint32_t resumes;          ///< RESUME frames handled
  uint32_t halts;            ///< HALT frames handled
  uint32_t replies_dropped;  ///< no room in the output buffer
  /// Frames with the plain CRC that need a session (all but HELLO), or any
  /// frame but HELLO before the first session: dropped unanswered. Frames of
  /// another session are counted as CRC errors (frame_stats()).
  uint32_t sessionless;
};

/// Whether `seq` lies in the 0x8000 sequence numbers before `next`
/// (RFC 1982 serial-number arithmetic on 16 bits).
inline bool SeqBefore(uint16_t seq, uint16_t next) {
  const uint16_t behind = static_cast<uint16_t>(next - seq);
  return behind != 0 && behind <= 0x8000u;
}

/// `kOutputCapacity`: bytes of encoded replies held until ReadOutput().
/// `kFrameCapacity`: the largest decoded frame taken (kMaxFrameBytes; a
/// small target may lower it to what its commands need, e.g. 200 bytes for
/// 2-D patches, at the cost of refusing larger frames as overlong).
template <typename Sink, size_t kOutputCapacity = 256, size_t kFrameCapacity = kMaxFrameBytes>
class DeviceLink {
 public:
  static_assert(kOutputCapacity >= MaxEncodedFrameBytes(kFrameOverheadBytes + 32),
                "the output buffer must hold the largest reply");

  /// `sink` must outlive the link.
  explicit DeviceLink(Sink* sink) : sink_(sink) {}
  DeviceLink(const DeviceLink&) = delete;
  DeviceLink& operator=(const DeviceLink&) = delete;

  /// Feeds one received byte; a completed frame is handled at once (the sink
  /// may be called) and its reply queued for ReadOutput().
  void OnByte(uint8_t byte) {
    if (decoder_.OnByte(byte)) {
      HandleFrame(decoder_.frame());
    }
  }

  /// Moves up to `capacity` bytes of encoded replies into `data`; returns
  /// how many. Replies are queued whole and come out in order (a small
  /// `capacity` splits one across calls; the byte stream stays intact).
  size_t ReadOutput(uint8_t* data, size_t capacity) {
    size_t n = 0;
    while (n < capacity && out_begin_ < out_end_) {
      data[n++] = out_[out_begin_++];
    }
    if (out_begin_ == out_end_) {
      out_begin_ = 0;
      out_end_ = 0;
    }
    return n;
  }
  /// Bytes waiting in the output buffer.
  FDSURF_NODISCARD size_t OutputPending() const { return out_end_ - out_begin_; }

  /// The sequence number the link expects next.
  FDSURF_NODISCARD uint16_t next_seq() const { return next_seq_; }
  /// The current session (0 before the first new-session HELLO).
  FDSURF_NODISCARD uint32_t session() const { return session_; }
  FDSURF_NODISCARD const DeviceLinkStats& stats() const { return stats_; }
  /// Frames delivered and dropped by the framing layer (CRC, COBS, length).
  FDSURF_NODISCARD const FrameDecoderStats& frame_stats() const { return decoder_.stats(); }

 private:
  void HandleFrame(const Frame& frame) {
    Compact();
    const MessageType type = static_cast<MessageType>(frame.type);
    if (type == MessageType::kHello) {
      HandleHello(frame);
      return;
    }
    if (session_ == 0 || !frame.in_session) {
      ++stats_.sessionless;  // nothing but HELLO outside a session
      return;
    }
    if (IsSequenced(type)) {
      HandleCommand(frame);
      return;
    }
    switch (type) {
      case MessageType::kStatusQuery: {
        const DecodeResult result = DecodeEmpty(frame);
        if (!result.ok()) {
          SendError(frame.seq, result.code, result.field);
          return;
        }
        ++stats_.status_queries;
        StatusReport report = {};
        sink_->FillStatus(&report);
        report.next_seq = next_seq_;
        Emit(EncodeStatusReport(frame.seq, report, out_ + out_end_, kOutputCapacity - out_end_,
                                session_));
        return;
      }
      case MessageType::kStop: {
        const DecodeResult result = DecodeEmpty(frame);
        if (!result.ok()) {
          SendError(frame.seq, result.code, result.field);
          return;
        }
        ++stats_.stops;
        sink_->Stop();
        SendAck(frame.seq);
        return;
      }
      case MessageType::kPause:
      case MessageType::kResume:
      case MessageType::kHalt:
        HandleControl(type, frame);
        return;
      default:
        SendError(frame.seq, ErrorCode::kUnknownType, 0);
        return;
    }
  }

  // PAUSE, RESUME, HALT: empty bodies, idempotent, acknowledged at once
  // (a retransmission after a lost ACK does nothing new).
  void HandleControl(MessageType type, const Frame& frame) {
    const DecodeResult result = DecodeEmpty(frame);
    if (!result.ok()) {
      SendError(frame.seq, result.code, result.field);
      return;
    }
    if (type == MessageType::kPause) {
      ++stats_.pauses;
      sink_->Pause();
    } else if (type == MessageType::kResume) {
      ++stats_.resumes;
      sink_->Resume();
    } else {
      ++stats_.halts;
      sink_->Halt();
    }
    SendAck(frame.seq);
  }

  void HandleHello(const Frame& frame) {
    Hello hello = {0, 0, 0};
    const DecodeResult result = DecodeHello(frame, &hello);
    if (!result.ok()) {
      // For a version mismatch the detail is the version this device speaks.
      // The reply carries the HELLO's session if it got that far (else the
      // plain CRC: a host of another version could not check a tag).
      const uint32_t session = result.code == ErrorCode::kUnsupportedVersion ? 0 : hello.session;
      SendError(frame.seq, result.code,
                result.code == ErrorCode::kUnsupportedVersion ? kProtocolVersion : result.field,
                session);
      return;
    }
    ++stats_.hellos;
    if ((hello.flags & kHelloFlagNewSession) != 0) {
      // A repeat of the HELLO that opened the current session (its reply was
      // lost, or the link duplicated it) changes nothing.
      if (hello.session != session_) {
        sink_->Reset();
        next_seq_ = 0;
        session_ = hello.session;
        decoder_.set_session(session_);
      }
    } else if (hello.session != session_) {
      SendError(frame.seq, ErrorCode::kUnknownSession, 0, hello.session);
      return;
    }
    HelloReply reply;
    reply.version = kProtocolVersion;
    reply.next_seq = next_seq_;
    reply.credits = sink_->Credits();
    reply.queue_capacity = sink_->QueueCapacity();
    reply.tick_hz = sink_->TickHz();
    reply.max_axes = sink_->MaxAxes();
    reply.max_lines = kMaxLines;
    reply.features = sink_->Features();
    Emit(EncodeHelloReply(frame.seq, reply, out_ + out_end_, kOutputCapacity - out_end_, session_));
  }

  void HandleCommand(const Frame& frame) {
    if (frame.seq != next_seq_) {
      if (SeqBefore(frame.seq, next_seq_)) {
        ++stats_.duplicates;  // accepted before: acknowledge, never re-execute
        SendAck(frame.seq);
      } else {
        ++stats_.out_of_order;
        SendNak(frame.seq, ErrorCode::kOutOfOrder);
      }
      return;
    }
    const DecodeResult result = DecodeCommand(frame, &command_);
    if (!result.ok()) {
      SendError(frame.seq, result.code, result.field);
      return;
    }
    if (sink_->Credits() == 0) {
      ++stats_.queue_full;
      SendNak(frame.seq, ErrorCode::kQueueFull);
      return;
    }
    uint8_t detail = 0;
    const ErrorCode code = sink_->Accept(command_, &detail);
    if (code != ErrorCode::kNone) {
      SendError(frame.seq, code, detail);
      return;
    }
    ++stats_.commands_accepted;
    next_seq_ = static_cast<uint16_t>(next_seq_ + 1);
    SendAck(frame.seq);
  }

  void SendAck(uint16_t seq) {
    Emit(EncodeAck(seq, Ack{next_seq_, sink_->Credits()}, out_ + out_end_,
                   kOutputCapacity - out_end_, session_));
  }
  void SendNak(uint16_t seq, ErrorCode reason) {
    Emit(EncodeNak(seq, Nak{next_seq_, sink_->Credits(), reason}, out_ + out_end_,
                   kOutputCapacity - out_end_, session_));
  }
  void SendError(uint16_t seq, ErrorCode code, uint8_t detail) {
    SendError(seq, code, detail, session_);
  }
  void SendError(uint16_t seq, ErrorCode code, uint8_t detail, uint32_t session) {
    ++stats_.errors;
    Emit(EncodeError(ErrorReply{seq, code, detail}, out_ + out_end_, kOutputCapacity - out_end_,
                     session));
  }

  // Replies are encoded straight into the free tail of out_. Before each
  // frame's reply (at most one per frame) the consumed head is reclaimed.
  void Compact() {
    if (out_begin_ > 0) {
      size_t n = 0;
      for (size_t i = out_begin_; i < out_end_; ++i) {
        out_[n++] = out_[i];
      }
      out_begin_ = 0;
      out_end_ = n;
    }
  }
  void Emit(size_t encoded) {
    if (encoded == 0) {
      ++stats_.replies_dropped;  // the host recovers by its retransmit timeout
      return;
    }
    out_end_ += encoded;
  }

  Sink* sink_;
  FrameDecoderBuffer<kFrameCapacity> decoder_;
  Command command_;  // decoding scratch, a member to keep it off small stacks
  uint8_t out_[kOutputCapacity];
  size_t out_begin_ = 0;
  size_t out_end_ = 0;
  uint16_t next_seq_ = 0;
  uint32_t session_ = 0;  // 0: none yet
  DeviceLinkStats stats_ = {};
};

}  // namespace protocol
}  // namespace fdsurf
