// SPDX-License-Identifier: MIT
// A single-producer, single-consumer byte ring for a UART: the receive
// interrupt pushes, the main loop pops (or the other way round for sending).
//
// Lock-free: each side writes only its own index, an index is loaded and
// stored in one instruction, and the byte is stored before the index that
// publishes it. `Index` is uint8_t by default, which every core loads in one
// instruction (an 8-bit AVR too), for rings of up to 128 bytes; uint16_t
// allows rings of up to 32768 bytes on a core whose 16-bit loads and stores
// are single instructions (any 32-bit core; NOT an AVR, where a 16-bit index
// could be read half old, half new). The capacity is a power of two at most
// half the index's range, so `head - tail` (mod the range) is the fill level
// without a separate count.
//
// How big: the main loop reads nothing while it validates a command, so the
// ring must hold what the line brings meanwhile, or the overflow is lost and
// the link protocol resends it (a NAK or a timeout). At 115200 baud that is
// 11.5 bytes per millisecond of validation.
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"

namespace fdsurf {
namespace board {

template <uint16_t kCapacity, class Index = uint8_t>
class ByteRing {
 public:
  static_assert(sizeof(Index) == 1 || sizeof(Index) == 2, "a uint8_t or uint16_t index");
  static_assert(static_cast<Index>(-1) > 0, "an unsigned index");
  static_assert(kCapacity >= 2 && (kCapacity & (kCapacity - 1)) == 0 &&
                    kCapacity <= (1u << (8 * sizeof(Index) - 1)),
                "a power of two from 2 to half the index's range");
  static constexpr uint16_t kBytes = kCapacity;

  /// Producer side. False (and the byte is dropped, counted in overruns())
  /// when the ring is full.
  bool Push(uint8_t byte) {
    const Index head = head_;
    if (static_cast<Index>(head - tail_) == kCapacity) {
      if (overruns_ != 0xFFu) overruns_ = static_cast<uint8_t>(overruns_ + 1);
      return false;
    }
    data_[head & (kCapacity - 1)] = byte;
    // The byte is in place before the consumer can see the new head.
    __asm__ __volatile__("" ::: "memory");
    head_ = static_cast<Index>(head + 1);
    return true;
  }

  /// Consumer side. False when the ring is empty.
  bool Pop(uint8_t* byte) {
    const Index tail = tail_;
    if (tail == head_) return false;
    *byte = data_[tail & (kCapacity - 1)];
    __asm__ __volatile__("" ::: "memory");
    tail_ = static_cast<Index>(tail + 1);
    return true;
  }

  /// Bytes waiting (either side may ask; the answer may be stale by the
  /// time it is used, never wrong in the asker's own direction).
  FDSURF_NODISCARD Index Size() const { return static_cast<Index>(head_ - tail_); }
  FDSURF_NODISCARD bool Empty() const { return head_ == tail_; }
  /// Bytes the producer had to drop because the ring was full (saturates).
  FDSURF_NODISCARD uint8_t overruns() const { return overruns_; }

 private:
  volatile uint8_t data_[kCapacity] = {};
  volatile Index head_ = 0;
  volatile Index tail_ = 0;
  volatile uint8_t overruns_ = 0;
};

}  // namespace board
}  // namespace fdsurf
