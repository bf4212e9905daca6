// SPDX-License-Identifier: MIT
// AVR port of the test image for simavr (targets/sim/simavr_run.c): the
// report goes out on USART0, GPIOR1 is the measurement marker, and the exit
// status is written to GPIOR2 before the CPU sleeps with interrupts off.
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/pgmspace.h>
#include <avr/sleep.h>
#include <stddef.h>
#include <stdint.h>

#include "../image/image.h"
#include "../image/port.h"

extern "C" {
// avr-libc's linker script: the first free byte after .data and .bss.
extern char __heap_start;
}

namespace {

constexpr uint8_t kStackPaint = 0xA5;

}  // namespace

namespace fdsurf {
namespace image {

void PortPutChar(char c) {
  while ((UCSR0A & _BV(UDRE0)) == 0) {
  }
  UDR0 = static_cast<uint8_t>(c);
}

void PortReadRom(void* to, const void* from, size_t n) { memcpy_P(to, from, n); }

// The harness timestamps this write with simavr's exact cycle counter.
void PortMark() { GPIOR1 = 1; }

uint32_t PortStackUsed() {
  const uint8_t* p = reinterpret_cast<const uint8_t*>(&__heap_start);
  const uint8_t* const top = reinterpret_cast<const uint8_t*>(RAMEND);
  while (p <= top && *p == kStackPaint) ++p;
  return static_cast<uint32_t>(top - p + 1);
}

void PortExit(int status) {
  while ((UCSR0A & _BV(TXC0)) == 0 && (UCSR0B & _BV(TXEN0)) != 0 && (UCSR0A & _BV(UDRE0)) == 0) {
  }
  GPIOR2 = static_cast<uint8_t>(status);
  cli();
  sleep_enable();
  for (;;) sleep_cpu();
}

}  // namespace image
}  // namespace fdsurf

int main() {
  // Paint the free RAM below this frame, for PortStackUsed.
  uint8_t* const sp = reinterpret_cast<uint8_t*>(SP);
  for (uint8_t* p = reinterpret_cast<uint8_t*>(&__heap_start); p < sp - 16; ++p) *p = kStackPaint;
  // 16 MHz, U2X: UBRR 0 gives 2 Mbit/s, the fastest the USART allows.
  UCSR0A = _BV(U2X0);
  UBRR0 = 0;
  UCSR0B = _BV(TXEN0);
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  fdsurf::image::PortExit(fdsurf::image::RunImage(false));
}
