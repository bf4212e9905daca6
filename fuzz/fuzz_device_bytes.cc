// SPDX-License-Identifier: MIT
// libFuzzer target: the device (Device<2>) fed the input as raw link bytes,
// with the main loop and the step timer running between chunks of it, then
// until idle (bounded). Exercises the COBS/CRC framing, the reply path and
// whatever valid frames survive mutation (the seed corpus holds real
// sessions); checks no crash, no sanitizer report, no fault, every reply
// decodes, and the work budget (device_harness.h).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "device_harness.h"

namespace {

// Bytes fed between two rounds of Fill()/Tick(), and the ticks of each
// round; at most kFinalTicks afterwards.
constexpr std::size_t kChunk = 16;
constexpr std::uint32_t kTicksPerChunk = 8;
constexpr std::uint32_t kFinalTicks = 20000;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto harness = std::make_unique<fdsurf::fuzz::DeviceHarness>();
  for (std::size_t at = 0; at < size; at += kChunk) {
    harness->Feed(data + at, std::min(kChunk, size - at));
    harness->Drain();
    harness->Run(kTicksPerChunk);
  }
  harness->Run(kFinalTicks);
  harness->Drain();
  return 0;
}
