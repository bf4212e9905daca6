// SPDX-License-Identifier: MIT
// The test-only Arduino shim's "core": Serial on USART0 (polled) and a main
// that runs setup() and loop() once, then writes the exit status 0 to GPIOR2
// for the simavr harness (targets/sim/simavr_run.c).
#include <Arduino.h>
#include <avr/sleep.h>

ShimSerial Serial;

void ShimSerial::begin(unsigned long) {
  // 16 MHz, U2X: UBRR 0 is 2 Mbit/s; simavr does not care about the baud rate.
  UCSR0A = _BV(U2X0);
  UBRR0 = 0;
  UCSR0B = _BV(TXEN0);
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
}

void ShimSerial::write(uint8_t c) {
  while ((UCSR0A & _BV(UDRE0)) == 0) {
  }
  UDR0 = c;
}

void ShimSerial::print(const char* s) {
  while (*s != '\0') write(static_cast<uint8_t>(*s++));
}

void ShimSerial::print(unsigned long n) {
  char digits[11];
  int i = 0;
  do {
    digits[i++] = static_cast<char>('0' + n % 10);
    n /= 10;
  } while (n != 0);
  while (i > 0) write(static_cast<uint8_t>(digits[--i]));
}

void ShimSerial::print(long n) {
  if (n < 0) {
    write('-');
    print(0UL - static_cast<unsigned long>(n));
  } else {
    print(static_cast<unsigned long>(n));
  }
}

void ShimSerial::flush() {
  while ((UCSR0A & _BV(TXC0)) == 0 && (UCSR0B & _BV(TXEN0)) != 0 && (UCSR0A & _BV(UDRE0)) == 0) {
  }
}

int main() {
  setup();
  loop();
  Serial.flush();
  GPIOR2 = 0;
  cli();
  sleep_enable();
  for (;;) sleep_cpu();
}
