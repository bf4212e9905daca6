// SPDX-License-Identifier: MIT
// Framing: COBS-encoded frames, each followed by a 0x00 delimiter.
//
// Consistent Overhead Byte Stuffing (S. Cheshire and M. Baker, "Consistent
// Overhead Byte Stuffing", SIGCOMM 1997 / IEEE/ACM Trans. Networking 7(2),
// 1999) removes every 0x00 from a frame at a cost of at most one byte per 254,
// so 0x00 can delimit frames: after any garbage the decoder is back in step at
// the next 0x00.
//
// A decoded frame is
//
//   type u8 | seq u16 LE | body (0..kMaxFrameBytes - 7 bytes) | crc32 u32 LE
//
// where the CRC-32 (crc32.h) covers type, seq and body. Protocol version 2
// folds the session id into it: the CRC field holds the CRC XOR
// SessionTag(session), so a frame of another session fails the check and is
// dropped like a corrupt one (HELLO, which opens a session, uses session 0:
// the plain CRC). docs/protocol.md has the details and a worked example.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/protocol/crc32.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf {
namespace protocol {

/// Bytes of a decoded frame besides its body: type, seq and CRC.
constexpr size_t kFrameOverheadBytes = 7;
/// Largest body a frame carries.
constexpr size_t kMaxBodyBytes = kMaxFrameBytes - kFrameOverheadBytes;

/// Largest size on the wire (COBS code bytes and the delimiter included) of
/// a frame whose decoded size is `decoded_size`.
constexpr size_t MaxEncodedFrameBytes(size_t decoded_size) {
  return decoded_size + decoded_size / 254 + 2;
}
/// Largest size on the wire of any frame.
constexpr size_t kMaxEncodedFrameBytes = MaxEncodedFrameBytes(kMaxFrameBytes);

/// What the CRC of a frame of session `session` is XORed with: 0 for session
/// 0 (the plain CRC), and distinct for distinct sessions (multiplication by
/// an odd constant is a bijection of the 32-bit integers).
constexpr uint32_t SessionTag(uint32_t session) {
  return static_cast<uint32_t>(session * 0x9E3779B1u);
}

/// COBS-encodes `size` bytes into `out` and appends the 0x00 delimiter.
/// Returns the number of bytes written, or 0 if they do not fit in
/// `capacity` (MaxEncodedFrameBytes(size) always fits). The encoding follows
/// the reference encoder of the paper: a block of 254 non-zero bytes that
/// ends the data is not followed by an empty block.
size_t CobsEncode(const uint8_t* data, size_t size, uint8_t* out, size_t capacity);

/// Decodes one COBS frame `data` (without its delimiter, so it contains no
/// 0x00) into `out`. Returns the decoded size, or -1 if `data` is not valid
/// COBS (a 0x00 inside, a block running past the end) or the result does not
/// fit in `capacity`.
int32_t CobsDecode(const uint8_t* data, size_t size, uint8_t* out, size_t capacity);

/// Writes one frame into a caller buffer, COBS-encoding on the fly (no
/// intermediate copy): Begin(), the body bytes, then Finish(). Every write
/// checks the capacity; on overflow the encoder remembers the failure and
/// Finish() returns 0.
class FrameEncoder {
 public:
  FrameEncoder(uint8_t* out, size_t capacity);

  /// Starts a frame: type and sequence number (or token), and the session
  /// whose tag the CRC carries (0: the plain CRC).
  void Begin(uint8_t type, uint16_t seq, uint32_t session = 0);
  /// Appends body bytes.
  void Put(uint8_t byte);
  void PutU16(uint16_t value);
  void PutU32(uint32_t value);
  /// Unsigned LEB128: 7 bits per byte, low group first, high bit = more.
  void PutVarint(uint64_t value);
  /// Zigzag (0, -1, 1, -2, ... → 0, 1, 2, 3, ...) then LEB128.
  void PutSignedVarint(int64_t value);

  /// Appends the CRC and the delimiter. Returns the encoded size, or 0 if
  /// the frame did not fit in the buffer or its decoded size exceeds
  /// kMaxFrameBytes.
  size_t Finish();

 private:
  void Raw(uint8_t byte);  // COBS-encodes one decoded byte

  uint8_t* out_;
  size_t capacity_;
  size_t pos_ = 0;       // next output position
  size_t code_pos_ = 0;  // where the current block's code byte goes
  uint8_t code_ = 1;     // 1 + data bytes in the current block
  bool overflow_ = false;
  size_t decoded_ = 0;  // decoded bytes so far
  uint32_t tag_ = 0;    // SessionTag of the frame's session
  Crc32 crc_;
};

/// A complete, CRC-checked frame. `body` points into the decoder's buffer
/// and stays valid until the next byte is fed.
struct Frame {
  uint8_t type;  ///< raw, may be a type this code does not know
  uint16_t seq;
  const uint8_t* body;
  size_t body_size;
  /// The CRC carried the decoder's session tag (FrameDecoder::set_session);
  /// false: it was the plain CRC (session 0), which only HELLO uses (and the
  /// version-mismatch ERROR of a device that predates sessions).
  bool in_session;
};

/// What the decoder dropped, and why. Drops are silent otherwise.
struct FrameDecoderStats {
  uint32_t frames;       ///< valid frames delivered
  uint32_t crc_errors;   ///< CRC mismatch (corrupt, or a frame of another session)
  uint32_t overlong;     ///< more than the buffer (or kMaxFrameBytes) decoded bytes
  uint32_t cobs_errors;  ///< a COBS block ran into the delimiter
  uint32_t runts;        ///< shorter than type + seq + CRC (7 bytes), but not empty
};

/// Decodes a byte stream one byte at a time into a caller-owned buffer.
/// Empty frames (0x00 0x00) are ignored, so a sender may send a lone 0x00
/// to flush a half-received frame at the other end.
class FrameDecoder {
 public:
  /// `buffer` must outlive the decoder. Frames longer than
  /// min(capacity, kMaxFrameBytes) decoded bytes are dropped as overlong.
  FrameDecoder(uint8_t* buffer, size_t capacity);

  /// Feeds one byte. Returns true when it completed a valid frame, which
  /// frame() then describes.
  bool OnByte(uint8_t byte);
  FDSURF_NODISCARD const Frame& frame() const { return frame_; }

  /// Forgets any partly received frame (e.g. after a reconnect). Counters stay.
  void Reset();
  /// The session whose frames are delivered (with in_session set), besides
  /// frames with the plain CRC. 0 (the default): plain CRC only.
  void set_session(uint32_t session) { tag_ = SessionTag(session); }
  FDSURF_NODISCARD const FrameDecoderStats& stats() const { return stats_; }

 private:
  bool EndOfFrame();
  void Append(uint8_t byte);

  uint8_t* buffer_;
  size_t capacity_;
  size_t size_ = 0;        // decoded bytes in buffer_
  uint8_t remaining_ = 0;  // data bytes left in the current block; 0: next is a code
  uint8_t code_ = 0;       // the current block's code byte; 0 before the first
  bool started_ = false;   // bytes seen since the last delimiter
  bool overflow_ = false;
  uint32_t tag_ = 0;
  Frame frame_;
  FrameDecoderStats stats_ = {0, 0, 0, 0, 0};
};

/// A FrameDecoder with its buffer inside (Pigweed's DecoderBuffer idea).
template <size_t kCapacity = kMaxFrameBytes>
class FrameDecoderBuffer : public FrameDecoder {
 public:
  FrameDecoderBuffer() : FrameDecoder(storage_, kCapacity) {}
  FrameDecoderBuffer(const FrameDecoderBuffer&) = delete;
  FrameDecoderBuffer& operator=(const FrameDecoderBuffer&) = delete;

 private:
  uint8_t storage_[kCapacity];
};

}  // namespace protocol
}  // namespace fdsurf
