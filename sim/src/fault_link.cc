// SPDX-License-Identifier: MIT
#include "fdsurf/sim/fault_link.h"

#include <algorithm>
#include <utility>

namespace fdsurf::sim {

FaultLink::FaultLink(FaultRates rates, uint64_t seed) : rates_(rates), rng_(seed) {}

bool FaultLink::Chance(double rate) {
  // Always draw, so that the random sequence (and every later decision)
  // does not depend on which rates are zero.
  const double u = std::uniform_real_distribution<double>(0.0, 1.0)(rng_);
  return u < rate;
}

void FaultLink::Process(const uint8_t* data, size_t size, std::vector<uint8_t>* out) {
  stats_.bytes_in += size;
  for (size_t i = 0; i < size; ++i) {
    if (data[i] == 0) {
      Frame(out);
    } else {
      partial_.push_back(data[i]);
    }
  }
}

void FaultLink::Emit(const std::vector<uint8_t>& frame, std::vector<uint8_t>* out) {
  out->insert(out->end(), frame.begin(), frame.end());
  stats_.bytes_out += frame.size();
}

void FaultLink::Frame(std::vector<uint8_t>* out) {
  ++stats_.frames;
  std::vector<uint8_t> frame = std::move(partial_);
  partial_.clear();
  const bool drop = Chance(rates_.drop);
  const bool truncate = Chance(rates_.truncate);
  const bool corrupt = Chance(rates_.corrupt);
  const bool duplicate = Chance(rates_.duplicate);
  const bool reorder = Chance(rates_.reorder);
  const uint64_t r1 = rng_();
  const uint64_t r2 = rng_();
  if (drop) {
    ++stats_.dropped;
    return;
  }
  if (truncate && !frame.empty()) {
    ++stats_.truncated;
    frame.resize(static_cast<size_t>(r1 % frame.size()));
  }
  if (corrupt && !frame.empty()) {
    ++stats_.corrupted;
    frame[static_cast<size_t>(r2 % frame.size())] ^= static_cast<uint8_t>(1u << ((r2 >> 32) % 8));
  }
  frame.push_back(0);
  std::vector<std::vector<uint8_t>> ready;
  ready.push_back(frame);
  if (duplicate) {
    ++stats_.duplicated;
    ready.push_back(frame);
  }
  if (reorder && held_.empty()) {
    ++stats_.reordered;
    held_ = std::move(ready);
    return;
  }
  for (const auto& f : ready) {
    Emit(f, out);
  }
  for (const auto& f : held_) {
    Emit(f, out);
  }
  held_.clear();
}

void FaultLink::Flush(std::vector<uint8_t>* out) {
  for (const auto& f : held_) {
    Emit(f, out);
  }
  held_.clear();
}

void Pipe::Write(const uint8_t* data, size_t size, uint64_t now_us) {
  for (size_t i = 0; i < size; ++i) {
    bytes_.emplace_back(now_us + latency_us_, data[i]);
  }
}

size_t Pipe::Read(uint8_t* data, size_t capacity, uint64_t now_us) {
  size_t n = 0;
  while (n < capacity && !bytes_.empty() && bytes_.front().first <= now_us) {
    data[n++] = bytes_.front().second;
    bytes_.pop_front();
  }
  return n;
}

std::optional<uint64_t> Pipe::next_arrival_us() const {
  if (bytes_.empty()) {
    return std::nullopt;
  }
  return bytes_.front().first;
}

}  // namespace fdsurf::sim
