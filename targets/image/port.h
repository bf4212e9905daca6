// SPDX-License-Identifier: MIT
// What the test image needs from the machine it runs on. Each target has one
// implementation in targets/port/ (host, arm, riscv, avr); the image itself is
// the same C++14 code everywhere, so its output can be compared bit for bit.
#pragma once

#include <stddef.h>
#include <stdint.h>

#if defined(__AVR__)
#include <avr/pgmspace.h>
// Tables live in flash on AVR; reading them goes through PortReadRom.
#define FDSURF_IMAGE_ROM PROGMEM
// A string literal in flash on AVR (2 KB of RAM on the ATmega328P); read it
// with PutString (targets/image/report.h).
#define FDSURF_TEXT(literal) PSTR(literal)
#else
#define FDSURF_IMAGE_ROM
#define FDSURF_TEXT(literal) (literal)
#endif

namespace fdsurf {
namespace image {

/// Writes one byte of the report (semihosting, UART or stdout).
void PortPutChar(char c);

/// Copies n bytes of a FDSURF_IMAGE_ROM table into RAM.
void PortReadRom(void* to, const void* from, size_t n);

/// A measurement marker. The emulator records its cycle or instruction
/// counter each time this runs (targets/sim/): the cost of a measured loop is
/// the difference between the two marks around it.
void PortMark();

/// Bytes of stack used so far (high-water mark of a painted stack), or 0 where
/// it is not measured (the host).
uint32_t PortStackUsed();

/// Ends the run with an exit status the emulator passes on.
[[noreturn]] void PortExit(int status);

}  // namespace image
}  // namespace fdsurf
