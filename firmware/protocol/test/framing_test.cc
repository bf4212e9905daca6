// SPDX-License-Identifier: MIT
// CRC-32 and COBS framing of the device protocol (firmware/include/fdsurf/protocol).
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "fdsurf/protocol/crc32.h"
#include "fdsurf/protocol/frame.h"

namespace fdsurf::protocol {
namespace {

using Bytes = std::vector<uint8_t>;

// An independent CRC-32: one bit at a time, straight from the definition
// (reflected input and output, polynomial 0x04C11DB7 reflected = 0xEDB88320).
uint32_t BitwiseCrc32(const Bytes& data) {
  uint32_t crc = 0xFFFFFFFFu;
  for (uint8_t byte : data) {
    for (int bit = 0; bit < 8; ++bit) {
      const bool feedback = ((crc ^ (byte >> bit)) & 1u) != 0;
      crc >>= 1;
      if (feedback) {
        crc ^= 0xEDB88320u;
      }
    }
  }
  return ~crc;
}

Bytes RandomBytes(std::mt19937_64& rng, size_t size, int zero_percent) {
  Bytes out(size);
  for (auto& b : out) {
    b = (rng() % 100) < static_cast<uint64_t>(zero_percent) ? 0 : static_cast<uint8_t>(rng());
  }
  return out;
}

Bytes Encode(const Bytes& data) {
  Bytes out(MaxEncodedFrameBytes(data.size()));
  out.resize(CobsEncode(data.data(), data.size(), out.data(), out.size()));
  return out;
}

Bytes Decode(const Bytes& encoded) {  // without the delimiter
  Bytes out(encoded.size() + 1);
  const int32_t n = CobsDecode(encoded.data(), encoded.size(), out.data(), out.size());
  EXPECT_GE(n, 0);
  out.resize(n < 0 ? 0 : static_cast<size_t>(n));
  return out;
}

Bytes Range(int first, int last) {  // inclusive
  Bytes out;
  for (int v = first; v <= last; ++v) {
    out.push_back(static_cast<uint8_t>(v));
  }
  return out;
}

Bytes Cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) {
    out.insert(out.end(), p.begin(), p.end());
  }
  return out;
}

TEST(Crc32, PublishedCheckValue) {
  const Bytes check = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(ComputeCrc32(check.data(), check.size()), 0xCBF43926u);
  EXPECT_EQ(BitwiseCrc32(check), 0xCBF43926u);
  EXPECT_EQ(ComputeCrc32(nullptr, 0), 0u);
}

TEST(Crc32, MatchesBitwiseDefinitionOnRandomData) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    const Bytes data = RandomBytes(rng, rng() % 300, 10);
    ASSERT_EQ(ComputeCrc32(data.data(), data.size()), BitwiseCrc32(data)) << "trial " << trial;
  }
}

TEST(Crc32, IncrementalEqualsWhole) {
  std::mt19937_64 rng(8);
  const Bytes data = RandomBytes(rng, 1000, 5);
  for (size_t split : {size_t{0}, size_t{1}, size_t{17}, size_t{999}, size_t{1000}}) {
    Crc32 crc;
    crc.Update(data.data(), split);
    for (size_t i = split; i < data.size(); ++i) {
      crc.Update(data[i]);
    }
    EXPECT_EQ(crc.Value(), ComputeCrc32(data.data(), data.size()));
  }
}

// The encoding examples of the Wikipedia article "Consistent Overhead Byte
// Stuffing" (section "Encoding examples"), which follow Cheshire & Baker's
// reference encoder; the trailing 00 is the frame delimiter.
TEST(Cobs, KnownVectors) {
  struct Vector {
    Bytes data;
    Bytes encoded;
  };
  const std::vector<Vector> vectors = {
      {{}, {0x01, 0x00}},
      {{0x00}, {0x01, 0x01, 0x00}},
      {{0x00, 0x00}, {0x01, 0x01, 0x01, 0x00}},
      {{0x00, 0x11, 0x00}, {0x01, 0x02, 0x11, 0x01, 0x00}},
      {{0x11, 0x22, 0x00, 0x33}, {0x03, 0x11, 0x22, 0x02, 0x33, 0x00}},
      {{0x11, 0x22, 0x33, 0x44}, {0x05, 0x11, 0x22, 0x33, 0x44, 0x00}},
      {{0x11, 0x00, 0x00, 0x00}, {0x02, 0x11, 0x01, 0x01, 0x01, 0x00}},
      {Range(0x01, 0xFE), Cat({{0xFF}, Range(0x01, 0xFE), {0x00}})},
      {Cat({{0x00}, Range(0x01, 0xFE)}), Cat({{0x01, 0xFF}, Range(0x01, 0xFE), {0x00}})},
      {Range(0x01, 0xFF), Cat({{0xFF}, Range(0x01, 0xFE), {0x02, 0xFF, 0x00}})},
      {Cat({Range(0x02, 0xFF), {0x00}}), Cat({{0xFF}, Range(0x02, 0xFF), {0x01, 0x01, 0x00}})},
      {Cat({Range(0x03, 0xFF), {0x00, 0x01}}),
       Cat({{0xFE}, Range(0x03, 0xFF), {0x02, 0x01, 0x00}})},
  };
  for (size_t i = 0; i < vectors.size(); ++i) {
    EXPECT_EQ(Encode(vectors[i].data), vectors[i].encoded) << "vector " << i;
    const Bytes body(vectors[i].encoded.begin(), vectors[i].encoded.end() - 1);
    EXPECT_EQ(Decode(body), vectors[i].data) << "vector " << i;
  }
}

TEST(Cobs, RoundTripRandomPayloads) {
  std::mt19937_64 rng(11);
  std::vector<Bytes> payloads = {Bytes(600, 0), Bytes(254, 0x55), Bytes(255, 0x55),
                                 Bytes(508, 0x55), Bytes(509, 0x01)};
  for (int trial = 0; trial < 3000; ++trial) {
    payloads.push_back(RandomBytes(rng, rng() % 700, static_cast<int>(rng() % 101)));
  }
  for (const Bytes& data : payloads) {
    const Bytes encoded = Encode(data);
    ASSERT_FALSE(encoded.empty());
    ASSERT_LE(encoded.size(), MaxEncodedFrameBytes(data.size()));
    ASSERT_EQ(encoded.back(), 0);
    for (size_t k = 0; k + 1 < encoded.size(); ++k) {
      ASSERT_NE(encoded[k], 0) << "a zero inside the frame";
    }
    ASSERT_EQ(Decode(Bytes(encoded.begin(), encoded.end() - 1)), data);
  }
}

TEST(Cobs, RefusesWhatDoesNotFit) {
  const Bytes data(300, 7);
  Bytes out(MaxEncodedFrameBytes(data.size()));
  for (size_t capacity = 0; capacity < out.size(); ++capacity) {
    const size_t n = CobsEncode(data.data(), data.size(), out.data(), capacity);
    EXPECT_TRUE(n == 0 || n <= capacity) << capacity;
  }
  const Bytes bad = {0x05, 0x11, 0x22};  // block runs past the end
  Bytes sink(10);
  EXPECT_EQ(CobsDecode(bad.data(), bad.size(), sink.data(), sink.size()), -1);
}

// Builds a wire frame with FrameEncoder.
Bytes WireFrame(uint8_t type, uint16_t seq, const Bytes& body) {
  Bytes out(kMaxEncodedFrameBytes + 8);
  FrameEncoder encoder(out.data(), out.size());
  encoder.Begin(type, seq);
  for (uint8_t b : body) {
    encoder.Put(b);
  }
  out.resize(encoder.Finish());
  return out;
}

TEST(FrameEncoder, EqualsCobsOfTheDecodedFrame) {
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 500; ++trial) {
    const Bytes body = RandomBytes(rng, rng() % (kMaxBodyBytes + 1), static_cast<int>(rng() % 60));
    const auto type = static_cast<uint8_t>(rng());
    const auto seq = static_cast<uint16_t>(rng());
    Bytes decoded =
        Cat({{type, static_cast<uint8_t>(seq & 0xFF), static_cast<uint8_t>(seq >> 8)}, body});
    const uint32_t crc = BitwiseCrc32(decoded);
    for (int shift = 0; shift < 32; shift += 8) {
      decoded.push_back(static_cast<uint8_t>(crc >> shift));
    }
    ASSERT_EQ(WireFrame(type, seq, body), Encode(decoded));
  }
}

TEST(FrameEncoder, RefusesOverlongAndTooSmallBuffers) {
  Bytes out(2000);
  FrameEncoder encoder(out.data(), out.size());
  encoder.Begin(0x11, 1);
  for (size_t i = 0; i < kMaxBodyBytes + 1; ++i) {
    encoder.Put(1);
  }
  EXPECT_EQ(encoder.Finish(), 0u) << "decoded size above kMaxFrameBytes";

  const Bytes body(100, 3);
  const size_t needed = WireFrame(0x11, 1, body).size();
  for (size_t capacity = 0; capacity < needed; ++capacity) {
    FrameEncoder small(out.data(), capacity);
    small.Begin(0x11, 1);
    for (uint8_t b : body) {
      small.Put(b);
    }
    EXPECT_EQ(small.Finish(), 0u) << capacity;
  }
}

struct Collected {
  std::vector<Frame> frames;
  std::vector<Bytes> bodies;
};

Collected Feed(FrameDecoder* decoder, const Bytes& stream) {
  Collected c;
  for (uint8_t b : stream) {
    if (decoder->OnByte(b)) {
      c.frames.push_back(decoder->frame());
      c.bodies.emplace_back(decoder->frame().body,
                            decoder->frame().body + decoder->frame().body_size);
    }
  }
  return c;
}

TEST(FrameDecoder, DeliversValidFramesOneByteAtATime) {
  FrameDecoderBuffer<> decoder;
  const Bytes body = {0x00, 0x01, 0x00, 0xFF};
  const Collected c = Feed(&decoder, Cat({WireFrame(0x13, 0xBEEF, body), WireFrame(0x14, 2, {})}));
  ASSERT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(c.frames[0].type, 0x13);
  EXPECT_EQ(c.frames[0].seq, 0xBEEF);
  EXPECT_EQ(c.bodies[0], body);
  EXPECT_EQ(c.frames[1].type, 0x14);
  EXPECT_TRUE(c.bodies[1].empty());
  EXPECT_EQ(decoder.stats().frames, 2u);
}

TEST(FrameDecoder, LargestFrameFitsAndOneMoreIsOverlong) {
  FrameDecoderBuffer<> decoder;
  const Bytes largest(kMaxBodyBytes, 0x42);
  EXPECT_EQ(Feed(&decoder, WireFrame(0x11, 0, largest)).frames.size(), 1u);
  // A frame one byte too long, built by hand (the encoder refuses it).
  Bytes decoded = Cat({{0x11, 0, 0}, Bytes(kMaxBodyBytes + 1, 0x42)});
  const uint32_t crc = BitwiseCrc32(decoded);
  for (int shift = 0; shift < 32; shift += 8) {
    decoded.push_back(static_cast<uint8_t>(crc >> shift));
  }
  EXPECT_TRUE(Feed(&decoder, Encode(decoded)).frames.empty());
  EXPECT_EQ(decoder.stats().overlong, 1u);
  // A small buffer bounds frames by its own size.
  FrameDecoderBuffer<16> small;
  EXPECT_TRUE(Feed(&small, WireFrame(0x11, 0, Bytes(10, 1))).frames.empty());
  EXPECT_EQ(small.stats().overlong, 1u);
  EXPECT_EQ(Feed(&small, WireFrame(0x11, 0, Bytes(9, 1))).frames.size(), 1u);
}

TEST(FrameDecoder, CountsCrcCobsAndRuntErrors) {
  FrameDecoderBuffer<> decoder;
  Bytes bad_crc = WireFrame(0x14, 3, {1});
  bad_crc[2] ^= 0x10;  // flips a bit of seq: CRC mismatch
  Feed(&decoder, bad_crc);
  EXPECT_EQ(decoder.stats().crc_errors, 1u);
  Feed(&decoder, {0x05, 0x11, 0x22, 0x00});  // block cut short by the delimiter
  EXPECT_EQ(decoder.stats().cobs_errors, 1u);
  Feed(&decoder, {0x03, 0x11, 0x22, 0x00});  // valid COBS, 2 bytes: a runt
  EXPECT_EQ(decoder.stats().runts, 1u);
  Feed(&decoder, {0x00, 0x00, 0x00});  // empty frames are flushes, not errors
  EXPECT_EQ(decoder.stats().runts, 1u);
  EXPECT_EQ(decoder.stats().frames, 0u);
}

TEST(FrameDecoder, ResynchronisesAfterRandomGarbage) {
  std::mt19937_64 rng(13);
  FrameDecoderBuffer<> decoder;
  uint32_t expected = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // Garbage of any length and content (zeros included), then a lone
    // delimiter, then a valid frame: the frame must come through.
    Bytes stream = RandomBytes(rng, rng() % 1500, static_cast<int>(rng() % 20));
    stream.push_back(0);
    const Bytes body = RandomBytes(rng, rng() % 64, 20);
    const auto seq = static_cast<uint16_t>(trial);
    stream = Cat({stream, WireFrame(0x13, seq, body)});
    const Collected c = Feed(&decoder, stream);
    ASSERT_FALSE(c.frames.empty());
    ASSERT_EQ(c.frames.back().seq, seq);
    ASSERT_EQ(c.bodies.back(), body);
    expected += static_cast<uint32_t>(c.frames.size());
  }
  EXPECT_EQ(decoder.stats().frames, expected);
}

// Millions of random bytes (many zeros, so many short frames): the decoder
// must neither crash nor deliver a frame whose CRC does not hold (checked
// again here). Runs under ASan/UBSan in the sanitizer build.
TEST(FrameDecoder, RandomByteFuzz) {
  std::mt19937_64 rng(14);
  FrameDecoderBuffer<> decoder;
  uint64_t delivered = 0;
  for (int block = 0; block < 64; ++block) {
    const Bytes stream = RandomBytes(rng, 1 << 16, block % 8);
    for (uint8_t b : stream) {
      if (decoder.OnByte(b)) {
        const Frame& f = decoder.frame();
        Bytes decoded = {f.type, static_cast<uint8_t>(f.seq), static_cast<uint8_t>(f.seq >> 8)};
        decoded.insert(decoded.end(), f.body, f.body + f.body_size);
        const uint32_t crc = BitwiseCrc32(decoded);
        const uint8_t* c = f.body + f.body_size;
        ASSERT_EQ(crc, static_cast<uint32_t>(c[0] | c[1] << 8 | c[2] << 16) |
                           static_cast<uint32_t>(c[3]) << 24);
        ++delivered;
      }
    }
  }
  const FrameDecoderStats& s = decoder.stats();
  EXPECT_EQ(s.frames, delivered);
  EXPECT_GT(s.crc_errors + s.cobs_errors + s.runts + s.overlong, 1000u);
}

}  // namespace
}  // namespace fdsurf::protocol
