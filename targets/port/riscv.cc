// SPDX-License-Identifier: MIT
// RV32 port of the test image for QEMU's virt machine (-bios none): the
// toolchain has no C library, so the start code, the semihosting calls and
// the few memory functions the compiler may call are written here.
#include <stddef.h>
#include <stdint.h>

#include "../image/image.h"
#include "../image/port.h"
#include "semihosting.h"

extern "C" {
// Linker script symbols (targets/link/riscv-virt.ld).
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();

void fdsurf_riscv_main();
void* memcpy(void* to, const void* from, size_t n);
void* memmove(void* to, const void* from, size_t n);
void* memset(void* to, int value, size_t n);
}

// Entry: set the stack pointer, then C++. No trap handler: a trap jumps to
// address 0 and the run times out (every QEMU run is under `timeout`).
__asm__(
    ".section .text.start, \"ax\"\n"
    ".global _start\n"
    "_start:\n"
    "  la sp, __stack_top\n"
    "  call fdsurf_riscv_main\n"
    "1: j 1b\n");

namespace fdsurf {
namespace image {
namespace semihosting {

// The RISC-V semihosting trap: ebreak between two marker instructions, all
// uncompressed and in one aligned group.
__attribute__((noinline)) uint32_t Semihost(uint32_t operation, const void* argument) {
  register uint32_t a0 __asm__("a0") = operation;
  register const void* a1 __asm__("a1") = argument;
  __asm__ volatile(
      ".option push\n"
      ".option norvc\n"
      ".balign 16\n"
      "slli zero, zero, 0x1f\n"
      "ebreak\n"
      "srai zero, zero, 7\n"
      ".option pop\n"
      : "+r"(a0)
      : "r"(a1)
      : "memory");
  return a0;
}

}  // namespace semihosting
}  // namespace image
}  // namespace fdsurf

void* memcpy(void* to, const void* from, size_t n) {
  auto* d = static_cast<unsigned char*>(to);
  const auto* s = static_cast<const unsigned char*>(from);
  while (n-- != 0) *d++ = *s++;
  return to;
}

void* memmove(void* to, const void* from, size_t n) {
  auto* d = static_cast<unsigned char*>(to);
  const auto* s = static_cast<const unsigned char*>(from);
  if (d < s) {
    while (n-- != 0) *d++ = *s++;
  } else {
    while (n-- != 0) d[n] = s[n];
  }
  return to;
}

void* memset(void* to, int value, size_t n) {
  auto* d = static_cast<unsigned char*>(to);
  while (n-- != 0) *d++ = static_cast<unsigned char>(value);
  return to;
}

void fdsurf_riscv_main() {
  for (uint32_t* p = __bss_start; p < __bss_end; ++p) *p = 0;
  uint32_t* sp;
  __asm__ volatile("mv %0, sp" : "=r"(sp));
  for (uint32_t* p = __stack_limit; p < sp - 16; ++p) *p = fdsurf::image::semihosting::kStackPaint;
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  fdsurf::image::PortExit(fdsurf::image::RunImage(false));
}
