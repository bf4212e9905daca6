// SPDX-License-Identifier: MIT
#include "fdsurf/protocol/frame.h"

namespace fdsurf {
namespace protocol {

size_t CobsEncode(const uint8_t* data, size_t size, uint8_t* out, size_t capacity) {
  if (capacity == 0) {
    return 0;
  }
  size_t pos = 1;
  size_t code_pos = 0;
  uint8_t code = 1;
  for (size_t i = 0; i < size; ++i) {
    if (code == 0xFF) {  // a full block is only closed when more data follows
      out[code_pos] = code;
      if (pos >= capacity) {
        return 0;
      }
      code_pos = pos++;
      code = 1;
    }
    if (data[i] == 0) {
      out[code_pos] = code;
      if (pos >= capacity) {
        return 0;
      }
      code_pos = pos++;
      code = 1;
    } else {
      if (pos >= capacity) {
        return 0;
      }
      out[pos++] = data[i];
      ++code;
    }
  }
  out[code_pos] = code;
  if (pos >= capacity) {
    return 0;
  }
  out[pos++] = 0;
  return pos;
}

int32_t CobsDecode(const uint8_t* data, size_t size, uint8_t* out, size_t capacity) {
  size_t in = 0;
  size_t decoded = 0;
  while (in < size) {
    const uint8_t code = data[in++];
    if (code == 0) {
      return -1;
    }
    for (uint8_t k = 1; k < code; ++k) {
      if (in >= size || data[in] == 0 || decoded >= capacity) {
        return -1;
      }
      out[decoded++] = data[in++];
    }
    // Every block but a full one stands for its data and a zero; the zero
    // after the last block is the one the encoder appended implicitly.
    if (code != 0xFF && in < size) {
      if (decoded >= capacity) {
        return -1;
      }
      out[decoded++] = 0;
    }
  }
  return static_cast<int32_t>(decoded);
}

FrameEncoder::FrameEncoder(uint8_t* out, size_t capacity) : out_(out), capacity_(capacity) {}

void FrameEncoder::Raw(uint8_t byte) {
  ++decoded_;
  if (overflow_) {
    return;
  }
  if (code_ == 0xFF) {
    out_[code_pos_] = code_;
    if (pos_ >= capacity_) {
      overflow_ = true;
      return;
    }
    code_pos_ = pos_++;
    code_ = 1;
  }
  if (pos_ >= capacity_) {
    overflow_ = true;
    return;
  }
  if (byte == 0) {
    out_[code_pos_] = code_;
    code_pos_ = pos_++;
    code_ = 1;
  } else {
    out_[pos_++] = byte;
    ++code_;
  }
}

void FrameEncoder::Begin(uint8_t type, uint16_t seq, uint32_t session) {
  crc_ = Crc32();
  tag_ = SessionTag(session);
  decoded_ = 0;
  code_ = 1;
  code_pos_ = 0;
  pos_ = 1;  // out_[0] is the first block's code byte
  overflow_ = capacity_ < 2;
  Put(type);
  PutU16(seq);
}

void FrameEncoder::Put(uint8_t byte) {
  crc_.Update(byte);
  Raw(byte);
}

void FrameEncoder::PutU16(uint16_t value) {
  Put(static_cast<uint8_t>(value & 0xFFu));
  Put(static_cast<uint8_t>(value >> 8));
}

void FrameEncoder::PutU32(uint32_t value) {
  for (int shift = 0; shift < 32; shift += 8) {
    Put(static_cast<uint8_t>((value >> shift) & 0xFFu));
  }
}

void FrameEncoder::PutVarint(uint64_t value) {
  while (value >= 0x80u) {
    Put(static_cast<uint8_t>((value & 0x7Fu) | 0x80u));
    value >>= 7;
  }
  Put(static_cast<uint8_t>(value));
}

void FrameEncoder::PutSignedVarint(int64_t value) {
  // Zigzag without shifting a negative number: -1 → 1, 1 → 2, -2 → 3, ...
  const uint64_t magnitude_twice = static_cast<uint64_t>(value) << 1;
  PutVarint(value < 0 ? ~magnitude_twice : magnitude_twice);
}

size_t FrameEncoder::Finish() {
  const uint32_t crc = crc_.Value() ^ tag_;
  for (int shift = 0; shift < 32; shift += 8) {
    Raw(static_cast<uint8_t>((crc >> shift) & 0xFFu));
  }
  if (overflow_ || decoded_ > kMaxFrameBytes) {
    return 0;
  }
  out_[code_pos_] = code_;
  if (pos_ >= capacity_) {
    return 0;
  }
  out_[pos_++] = 0;
  return pos_;
}

FrameDecoder::FrameDecoder(uint8_t* buffer, size_t capacity)
    : buffer_(buffer),
      capacity_(capacity < kMaxFrameBytes ? capacity : kMaxFrameBytes),
      frame_{0, 0, buffer, 0, false} {}

void FrameDecoder::Reset() {
  size_ = 0;
  remaining_ = 0;
  code_ = 0;
  started_ = false;
  overflow_ = false;
}

bool FrameDecoder::OnByte(uint8_t byte) {
  if (byte == 0) {
    const bool complete = EndOfFrame();
    Reset();
    return complete;
  }
  started_ = true;
  if (remaining_ == 0) {
    // A code byte. The block before it stands for a trailing zero unless it
    // was full (code 0xFF); the very first block has nothing before it.
    if (code_ != 0 && code_ != 0xFF) {
      Append(0);
    }
    code_ = byte;
    remaining_ = static_cast<uint8_t>(byte - 1);
    return false;
  }
  Append(byte);
  --remaining_;
  return false;
}

void FrameDecoder::Append(uint8_t byte) {
  if (size_ < capacity_) {
    buffer_[size_++] = byte;
  } else {
    overflow_ = true;  // size_ stays put: no wrap-around on long garbage
  }
}

bool FrameDecoder::EndOfFrame() {
  if (!started_) {
    return false;  // an empty frame: a flush, not an error
  }
  if (overflow_) {
    ++stats_.overlong;
    return false;
  }
  if (remaining_ != 0) {
    ++stats_.cobs_errors;
    return false;
  }
  if (size_ < kFrameOverheadBytes) {
    ++stats_.runts;
    return false;
  }
  const size_t payload = size_ - 4;
  const uint32_t received = static_cast<uint32_t>(buffer_[payload]) |
                            static_cast<uint32_t>(buffer_[payload + 1]) << 8 |
                            static_cast<uint32_t>(buffer_[payload + 2]) << 16 |
                            static_cast<uint32_t>(buffer_[payload + 3]) << 24;
  const uint32_t tag = ComputeCrc32(buffer_, payload) ^ received;
  if (tag != tag_ && tag != 0) {
    ++stats_.crc_errors;
    return false;
  }
  frame_.in_session = tag == tag_;
  ++stats_.frames;
  frame_.type = buffer_[0];
  frame_.seq = static_cast<uint16_t>(static_cast<uint16_t>(buffer_[2]) << 8 | buffer_[1]);
  frame_.body = buffer_ + 3;
  frame_.body_size = payload - 3;
  return true;
}

}  // namespace protocol
}  // namespace fdsurf
