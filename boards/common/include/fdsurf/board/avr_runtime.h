// SPDX-License-Identifier: MIT
// What the AVR boards' images share (mega2560-ramps, uno-cnc-shield): the
// lock that masks the step interrupt, the stack paint the simavr harness
// reads, USART0 at 115200 or 250000 bit/s with polled transmission, and
// the watchdog's heartbeat. The start-up code that goes with it (why the
// board reset, __cxa_pure_virtual) is common/src/avr_runtime.cc, which each
// AVR image links.
#pragma once

#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include <stddef.h>
#include <stdint.h>

namespace fdsurf {
namespace board {

/// Masks the step interrupt (all interrupts: SREG's I bit) while it lives.
struct TickInterruptLock {
  TickInterruptLock() : sreg_(SREG) { cli(); }
  ~TickInterruptLock() { SREG = sreg_; }
  TickInterruptLock(const TickInterruptLock&) = delete;
  TickInterruptLock& operator=(const TickInterruptLock&) = delete;
  uint8_t sreg_;
};

/// The value the free RAM is painted with at start; the stack's high-water
/// mark is the lowest address that no longer holds it (the simavr harness
/// reads it, boards/mega2560-ramps/host/board_measures.h).
constexpr uint8_t kStackPaint = 0xA5;

/// Paints the RAM between the end of .data/.bss and 32 bytes below the
/// stack pointer with kStackPaint. Call first thing in main().
void PaintFreeRam();

/// The reset cause (MCUSR) that the start-up code kept in GPIOR0.
inline uint8_t ResetCause() { return GPIOR0; }

/// USART0, 8N1, receive interrupt on. U2X: 16 MHz / (8 (UBRR + 1)): UBRR 16
/// gives 117 647 bit/s for 115200 (+2.1 %, as every Arduino sketch), 7
/// gives 250 000 exactly. `baud`: 115200 or 250000.
inline void StartUart0(uint32_t baud) {
  UCSR0A = _BV(U2X0);
  UBRR0 = baud == 250000 ? 7 : 16;
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

/// Sends on USART0, waiting for the line. Transmission is polled: a reply
/// is a few dozen bytes, the step interrupt runs while the main loop waits,
/// and a transmit ring would cost RAM the stack needs.
inline void SendUart0(const uint8_t* data, size_t size) {
  for (size_t i = 0; i < size; ++i) {
    while ((UCSR0A & _BV(UDRE0)) == 0) {
    }
    UDR0 = data[i];
  }
}

/// The watchdog's heartbeat: the step interrupt kicks the watchdog only
/// while the main loop has gone round within `kTicks` ticks or is inside the
/// link's service (a frame's validation may take long, docs/motion.md), so
/// a hung main loop and a hung interrupt both reset the board.
template <uint16_t kTicks>
class Heartbeat {
 public:
  /// The main loop's round: the count starts again, and the watchdog is kicked.
  void Beat() {
    {
      const TickInterruptLock lock;
      ticks_since_ = 0;
    }
    wdt_reset();
  }
  /// Around the main loop's service of the link.
  void set_in_service(bool in_service) { in_service_ = in_service; }
  /// From the step interrupt, once per tick.
  void OnTick() {
    const uint16_t since = ticks_since_;
    if (since < kTicks || in_service_) wdt_reset();
    if (since != 0xFFFFu) ticks_since_ = static_cast<uint16_t>(since + 1);
  }

 private:
  volatile uint16_t ticks_since_ = 0;
  volatile bool in_service_ = false;
};

}  // namespace board
}  // namespace fdsurf
