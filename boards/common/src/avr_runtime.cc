// SPDX-License-Identifier: MIT
// The AVR images' start-up code and runtime hooks (fdsurf/board/avr_runtime.h).
#include "fdsurf/board/avr_runtime.h"

extern "C" {
// avr-libc's linker script: the first free byte after .data and .bss.
extern char __heap_start;

// The abstract HAL bases' vtables name it; every board class overrides all.
void __cxa_pure_virtual() {
  for (;;) {
  }
}

// Before .bss is cleared and the constructors run: keep why the board
// reset (in GPIOR0 until main() picks it up) and stop a watchdog that is
// still running from before the reset, so that it cannot reset the board
// again while it starts (it stays on at its shortest period after firing).
void SaveResetCause() __attribute__((naked, used, section(".init3")));
void SaveResetCause() {
  GPIOR0 = MCUSR;
  MCUSR = 0;
  wdt_disable();
}
}

namespace fdsurf {
namespace board {

void PaintFreeRam() {
  uint8_t* const sp = reinterpret_cast<uint8_t*>(SP);
  for (uint8_t* p = reinterpret_cast<uint8_t*>(&__heap_start); p < sp - 32; ++p) *p = kStackPaint;
}

}  // namespace board
}  // namespace fdsurf
