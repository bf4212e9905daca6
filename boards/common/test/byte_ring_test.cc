// SPDX-License-Identifier: MIT
// The UART ring and transport on the host: order, the full ring, wrap-around
// of the byte-wide indices, and the transport's reads.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "fdsurf/board/byte_ring.h"
#include "fdsurf/board/uart_transport.h"

namespace fdsurf::board {
namespace {

TEST(ByteRing, KeepsOrderAcrossManyWrapsOfTheIndices) {
  ByteRing<8> ring;
  std::uint8_t expected = 0;
  std::uint8_t next = 0;
  // 3 in, 2 out, 2000 times: the indices wrap past 255 many times.
  for (int round = 0; round < 2000; ++round) {
    for (int k = 0; k < 3; ++k) {
      if (ring.Size() < 8) {
        ASSERT_TRUE(ring.Push(next++));
      }
    }
    for (int k = 0; k < 2; ++k) {
      std::uint8_t byte = 0;
      ASSERT_TRUE(ring.Pop(&byte));
      ASSERT_EQ(byte, expected++);
    }
  }
  EXPECT_EQ(ring.overruns(), 0);
}

TEST(ByteRing, AFullRingDropsAndCountsTheByte) {
  ByteRing<4> ring;
  for (std::uint8_t b = 1; b <= 4; ++b) EXPECT_TRUE(ring.Push(b));
  EXPECT_EQ(ring.Size(), 4);
  EXPECT_FALSE(ring.Push(5));
  EXPECT_EQ(ring.overruns(), 1);
  std::uint8_t byte = 0;
  for (std::uint8_t b = 1; b <= 4; ++b) {
    ASSERT_TRUE(ring.Pop(&byte));
    EXPECT_EQ(byte, b);  // the dropped 5 never appears
  }
  EXPECT_FALSE(ring.Pop(&byte));
  EXPECT_TRUE(ring.Empty());
}

TEST(ByteRing, TheLargestRingHoldsAllItsBytes) {
  ByteRing<128> ring;
  for (int k = 0; k < 128; ++k) ASSERT_TRUE(ring.Push(static_cast<std::uint8_t>(k)));
  EXPECT_FALSE(ring.Push(0));
  EXPECT_EQ(ring.Size(), 128);
}

TEST(ByteRing, ASixteenBitIndexHoldsALargeRingAcrossWraps) {
  ByteRing<2048, std::uint16_t> ring;
  for (int k = 0; k < 2048; ++k) ASSERT_TRUE(ring.Push(static_cast<std::uint8_t>(k * 7)));
  EXPECT_FALSE(ring.Push(0));
  EXPECT_EQ(ring.Size(), 2048);
  // 40 rounds of 2000 bytes: the 16-bit indices wrap past 65535.
  std::uint32_t in = 2048;
  std::uint32_t out = 0;
  for (int round = 0; round < 40; ++round) {
    std::uint8_t byte = 0;
    for (int k = 0; k < 2000; ++k) {
      ASSERT_TRUE(ring.Pop(&byte));
      ASSERT_EQ(byte, static_cast<std::uint8_t>(out++ * 7));
    }
    for (int k = 0; k < 2000; ++k) ASSERT_TRUE(ring.Push(static_cast<std::uint8_t>(in++ * 7)));
  }
  EXPECT_EQ(ring.overruns(), 1);
}

std::vector<std::uint8_t> g_sent;
struct RecordingUart {
  static void Send(const std::uint8_t* data, std::size_t size) {
    for (std::size_t k = 0; k < size; ++k) g_sent.push_back(data[k]);
  }
};

TEST(UartTransport, ReadsWhatTheRingHoldsAndNeverWaits) {
  ByteRing<16> rx;
  UartTransport<ByteRing<16>, RecordingUart> link(rx);
  std::uint8_t buffer[4];
  std::size_t got = 99;
  EXPECT_EQ(link.Read(buffer, sizeof buffer, &got, 1000), hal::IoStatus::kTimeout);
  EXPECT_EQ(got, 0u);
  for (std::uint8_t b = 10; b < 16; ++b) ASSERT_TRUE(rx.Push(b));
  ASSERT_EQ(link.Read(buffer, sizeof buffer, &got, 0), hal::IoStatus::kOk);
  ASSERT_EQ(got, 4u);
  EXPECT_EQ(buffer[0], 10);
  EXPECT_EQ(buffer[3], 13);
  ASSERT_EQ(link.Read(buffer, sizeof buffer, &got, 0), hal::IoStatus::kOk);
  EXPECT_EQ(got, 2u);
  EXPECT_EQ(buffer[1], 15);
  EXPECT_EQ(link.Read(nullptr, 4, &got, 0), hal::IoStatus::kInvalidArgument);
}

TEST(UartTransport, WritesGoToTheUart) {
  ByteRing<16> rx;
  UartTransport<ByteRing<16>, RecordingUart> link(rx);
  g_sent.clear();
  const std::uint8_t frame[] = {1, 2, 3, 0};
  ASSERT_EQ(link.Write(frame, sizeof frame, 100), hal::IoStatus::kOk);
  EXPECT_EQ(g_sent, std::vector<std::uint8_t>(frame, frame + 4));
  EXPECT_EQ(link.Write(nullptr, 1, 100), hal::IoStatus::kInvalidArgument);
}

}  // namespace
}  // namespace fdsurf::board
