// SPDX-License-Identifier: MIT
// A test-only stand-in for the Arduino AVR core's Arduino.h (not a core):
// the same avr-libc headers, typedefs and macros that could clash with a
// library's names (min, max, abs, round, bit, HIGH, DEC, byte, ...), and a
// Serial that writes to USART0 without interrupts, so tests/package/
// arduino_sketch.sh can compile a sketch as the IDE does and run it under
// simavr. arduino_main.cpp calls setup() and loop() once, then reports exit 0.
#pragma once

#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/pgmspace.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define HIGH 0x1
#define LOW 0x0
#define INPUT 0x0
#define OUTPUT 0x1
#define INPUT_PULLUP 0x2
#define PI 3.1415926535897932384626433832795
#define HALF_PI 1.5707963267948966192313216916398
#define TWO_PI 6.283185307179586476925286766559
#define DEG_TO_RAD 0.017453292519943295769236907684886
#define SERIAL 0x0
#define DISPLAY 0x1
#define LSBFIRST 0
#define MSBFIRST 1
#define CHANGE 1
#define FALLING 2
#define RISING 3
#define DEFAULT 1
#define EXTERNAL 0
#define DEC 10
#define HEX 16
#define OCT 8
#define BIN 2
#define min(a, b) ((a) < (b) ? (a) : (b))
#define max(a, b) ((a) > (b) ? (a) : (b))
#define abs(x) ((x) > 0 ? (x) : -(x))
#define constrain(amt, low, high) ((amt) < (low) ? (low) : ((amt) > (high) ? (high) : (amt)))
#define round(x) ((x) >= 0 ? (long)((x) + 0.5) : (long)((x)-0.5))
#define radians(deg) ((deg)*DEG_TO_RAD)
#define sq(x) ((x) * (x))
#define lowByte(w) ((uint8_t)((w)&0xff))
#define highByte(w) ((uint8_t)((w) >> 8))
#define bit(b) (1UL << (b))
typedef unsigned int word;
typedef bool boolean;
typedef uint8_t byte;

void setup(void);
void loop(void);

class ShimSerial {
 public:
  void begin(unsigned long baud);
  void write(uint8_t c);
  void print(const char* s);
  void print(char c) { write(static_cast<uint8_t>(c)); }
  void print(long n);
  void print(unsigned long n);
  void print(int n) { print(static_cast<long>(n)); }
  void print(unsigned int n) { print(static_cast<unsigned long>(n)); }
  template <typename T>
  void println(T value) {
    print(value);
    print("\r\n");
  }
  void flush();
};
extern ShimSerial Serial;
