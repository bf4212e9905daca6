// SPDX-License-Identifier: MIT
// The micro:bit's receive ring and the hal::Transport over it: as
// boards/common's ByteRing and UartTransport, but with 16-bit indices so that
// the ring can hold more than 128 bytes (a 16-bit load or store is single-copy
// atomic on the Cortex-M0, so the ring stays lock-free).
//
// Why: the M0 validates a PATCH frame in up to ~80 ms (measured under QEMU,
// README.md), during which 115200 baud brings ~950 bytes; with the common
// 128-byte ring the rest was dropped (482 bytes in a 5-command job, each
// loss a NAK or a timeout and a resend).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/transport.h"

namespace fdsurf {
namespace board {

/// Single producer (the UART interrupt), single consumer (the main loop).
template <uint16_t kCapacity>
class RxRing {
 public:
  static_assert(kCapacity >= 2 && kCapacity <= 32768 && (kCapacity & (kCapacity - 1)) == 0,
                "a power of two from 2 to 32768");

  /// Producer side. False (the byte is dropped) when the ring is full.
  bool Push(uint8_t byte) {
    const uint16_t head = head_;
    if (static_cast<uint16_t>(head - tail_) == kCapacity) return false;
    data_[head & (kCapacity - 1)] = byte;
    __asm__ __volatile__("" ::: "memory");  // the byte before the index
    head_ = static_cast<uint16_t>(head + 1);
    return true;
  }

  /// Consumer side. False when the ring is empty.
  bool Pop(uint8_t* byte) {
    const uint16_t tail = tail_;
    if (tail == head_) return false;
    *byte = data_[tail & (kCapacity - 1)];
    __asm__ __volatile__("" ::: "memory");
    tail_ = static_cast<uint16_t>(tail + 1);
    return true;
  }

 private:
  volatile uint8_t data_[kCapacity] = {};
  volatile uint16_t head_ = 0;
  volatile uint16_t tail_ = 0;
};

/// The device's end of the UART: reads never wait, writes go to
/// `Uart::Send(data, size)`. A UART cannot see the other end leave, so this
/// never reports kDisconnected (the link protocol resynchronises).
template <uint16_t kRxCapacity, class Uart>
class RingTransport final : public hal::Transport {
 public:
  explicit RingTransport(RxRing<kRxCapacity>& rx) : rx_(rx) {}
  ~RingTransport() = default;

 private:
  hal::IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t) override {
    if (data == nullptr && size > 0) return hal::IoStatus::kInvalidArgument;
    Uart::Send(data, size);
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received, uint32_t) override {
    if (received == nullptr) return hal::IoStatus::kInvalidArgument;
    *received = 0;
    if (data == nullptr || capacity == 0) return hal::IoStatus::kInvalidArgument;
    size_t n = 0;
    while (n < capacity && rx_.Pop(&data[n])) ++n;
    *received = n;
    return n == 0 ? hal::IoStatus::kTimeout : hal::IoStatus::kOk;
  }
  hal::IoStatus DoReconnect(uint32_t) override { return hal::IoStatus::kOk; }
  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }

  RxRing<kRxCapacity>& rx_;
};

}  // namespace board
}  // namespace fdsurf
