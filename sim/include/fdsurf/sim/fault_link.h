// SPDX-License-Identifier: MIT
// Fault injection for byte streams of 0x00-delimited frames, and a minimal
// in-memory pipe with latency, for testing the device protocol in virtual
// time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <random>
#include <vector>
#include "fdsurf/config/nodiscard.h"

namespace fdsurf::sim {

/// Per-frame probabilities, each in [0, 1], drawn independently per frame
/// (a frame may be both corrupted and duplicated, for instance).
struct FaultRates {
  double drop = 0;       ///< the frame vanishes
  double corrupt = 0;    ///< one random bit of one random byte flips
  double duplicate = 0;  ///< the frame goes out twice
  double reorder = 0;    ///< the frame is held back and goes out after the next one
  double truncate = 0;   ///< the frame loses a random tail (its delimiter stays)

  /// All five at the same rate.
  static FaultRates All(double rate) { return {rate, rate, rate, rate, rate}; }
};

struct FaultStats {
  uint64_t frames = 0;  ///< frames (delimiters) seen on input
  uint64_t dropped = 0;
  uint64_t corrupted = 0;
  uint64_t duplicated = 0;
  uint64_t reordered = 0;
  uint64_t truncated = 0;
  uint64_t bytes_in = 0;
  uint64_t bytes_out = 0;
};

/// One direction of a faulty link. Splits the input at 0x00 delimiters and
/// applies faults per frame, deterministically for a given seed. Bytes after
/// the last delimiter wait for the rest of their frame.
///
/// Order of decisions per frame: drop; else truncate, then corrupt (the
/// corruption hits the bytes left); then duplicate; then reorder (the frame,
/// and its duplicate, wait for the next frame that is not dropped).
///
/// Corruption never touches the delimiter, but may flip a byte to 0x00,
/// which splits the frame in two on the wire: the receiver then drops two
/// bad frames (CRC or COBS error) instead of one, which exercises the
/// resynchronisation. Truncation keeps at least zero and at most all but one
/// byte of the frame, then the delimiter.
class FaultLink {
 public:
  FaultLink(FaultRates rates, uint64_t seed);

  /// Passes `size` bytes through and appends the (faulted) output to `out`.
  void Process(const uint8_t* data, size_t size, std::vector<uint8_t>* out);
  /// Releases a frame held for reordering (e.g. at the end of a test).
  void Flush(std::vector<uint8_t>* out);

  /// Changes the rates from now on (e.g. a "disconnect": drop = 1).
  void set_rates(FaultRates rates) { rates_ = rates; }
  FDSURF_NODISCARD const FaultStats& stats() const { return stats_; }

 private:
  void Frame(std::vector<uint8_t>* out);  // handles partial_ + its delimiter
  bool Chance(double rate);
  void Emit(const std::vector<uint8_t>& frame, std::vector<uint8_t>* out);

  FaultRates rates_;
  std::mt19937_64 rng_;
  std::vector<uint8_t> partial_;            // the frame being collected
  std::vector<std::vector<uint8_t>> held_;  // frames (with delimiters) held back
  FaultStats stats_;
};

/// An in-memory byte pipe: bytes written at time t become readable at
/// t + latency_us, in order.
class Pipe {
 public:
  explicit Pipe(uint64_t latency_us = 0) : latency_us_(latency_us) {}

  void Write(const uint8_t* data, size_t size, uint64_t now_us);
  /// Reads up to `capacity` bytes that have arrived by `now_us`.
  size_t Read(uint8_t* data, size_t capacity, uint64_t now_us);
  /// Bytes written and not yet read (arrived or not).
  FDSURF_NODISCARD size_t pending() const { return bytes_.size(); }
  /// When the next unread byte arrives, if any.
  FDSURF_NODISCARD std::optional<uint64_t> next_arrival_us() const;

 private:
  uint64_t latency_us_;
  std::deque<std::pair<uint64_t, uint8_t>> bytes_;  // (arrival time, byte)
};

}  // namespace fdsurf::sim
