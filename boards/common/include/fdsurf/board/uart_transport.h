// SPDX-License-Identifier: MIT
// The device's end of a UART link as a hal::Transport: received bytes come
// from a ByteRing that the receive interrupt fills; sent bytes go to the
// board's `Uart::Send(data, size)`, which may wait for the line (a reply is
// a few dozen bytes; the step timer interrupt runs meanwhile).
//
//   struct Uart { static void Send(const uint8_t* data, size_t size); };
//   board::ByteRing<64> rx;              // ISR: rx.Push(UDR0)
//   board::UartTransport<board::ByteRing<64>, Uart> link(rx);
//   for (;;) { device.Service(link); device.Fill(); }
//
// A UART cannot tell that the other end went away, so this transport never
// reports kDisconnected: the host's link protocol resynchronises instead.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "fdsurf/board/byte_ring.h"
#include "fdsurf/hal/transport.h"

namespace fdsurf {
namespace board {

template <class Ring, class Uart>
class UartTransport final : public hal::Transport {
 public:
  explicit UartTransport(Ring& rx) : rx_(rx) {}
  ~UartTransport() = default;

 private:
  hal::IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t) override {
    if (data == nullptr && size > 0) return hal::IoStatus::kInvalidArgument;
    Uart::Send(data, size);
    return hal::IoStatus::kOk;
  }

  // Never waits: the main loop has the motion to feed.
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

  Ring& rx_;
};

}  // namespace board
}  // namespace fdsurf
