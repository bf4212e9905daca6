// SPDX-License-Identifier: MIT
// A single-producer, single-consumer byte ring for a UART: the receive
// interrupt pushes, the main loop pops (or the other way round for sending).
//
// Lock-free on every core the boards use: each side writes only its own
// index, the indices are single bytes (one load or store even on an 8-bit
// AVR), and the byte is stored before the index that publishes it. The
// capacity is a power of two up to 128, so `head - tail` (mod 256) is the
// fill level without a separate count.
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"

namespace fdsurf {
namespace board {

template <uint8_t kCapacity>
class ByteRing {
 public:
  static_assert(kCapacity >= 2 && kCapacity <= 128 && (kCapacity & (kCapacity - 1)) == 0,
                "a power of two from 2 to 128");

  /// Producer side. False (and the byte is dropped, counted in overruns())
  /// when the ring is full.
  bool Push(uint8_t byte) {
    const uint8_t head = head_;
    if (static_cast<uint8_t>(head - tail_) == kCapacity) {
      if (overruns_ != 0xFFu) overruns_ = static_cast<uint8_t>(overruns_ + 1);
      return false;
    }
    data_[head & (kCapacity - 1)] = byte;
    // The byte is in place before the consumer can see the new head.
    __asm__ __volatile__("" ::: "memory");
    head_ = static_cast<uint8_t>(head + 1);
    return true;
  }

  /// Consumer side. False when the ring is empty.
  bool Pop(uint8_t* byte) {
    const uint8_t tail = tail_;
    if (tail == head_) return false;
    *byte = data_[tail & (kCapacity - 1)];
    __asm__ __volatile__("" ::: "memory");
    tail_ = static_cast<uint8_t>(tail + 1);
    return true;
  }

  /// Bytes waiting (either side may ask; the answer may be stale by the
  /// time it is used, never wrong in the asker's own direction).
  FDSURF_NODISCARD uint8_t Size() const { return static_cast<uint8_t>(head_ - tail_); }
  FDSURF_NODISCARD bool Empty() const { return head_ == tail_; }
  /// Bytes the producer had to drop because the ring was full (saturates).
  FDSURF_NODISCARD uint8_t overruns() const { return overruns_; }

 private:
  volatile uint8_t data_[kCapacity] = {};
  volatile uint8_t head_ = 0;
  volatile uint8_t tail_ = 0;
  volatile uint8_t overruns_ = 0;
};

}  // namespace board
}  // namespace fdsurf
