// SPDX-License-Identifier: MIT
// The port functions of the ARM and RISC-V test images (targets/port/port.h),
// on semihosting: the report a line at a time, the exit status, the painted
// stack's high-water mark.
#include "semihosting.h"

#include "../image/port.h"

extern "C" void* memcpy(void* to, const void* from, size_t n);

namespace fdsurf {
namespace image {
namespace {

using semihosting::Semihost;

// Output is sent a line at a time: one semihosting trap per line.
char g_line[128];
size_t g_line_length = 0;

void Flush() {
  g_line[g_line_length] = '\0';
  Semihost(semihosting::kSysWrite0, g_line);
  g_line_length = 0;
}

}  // namespace

void PortPutChar(char c) {
  g_line[g_line_length++] = c;
  if (c == '\n' || g_line_length == sizeof g_line - 1) Flush();
}

void PortReadRom(void* to, const void* from, size_t n) { memcpy(to, from, n); }

void PortMark() { fdsurf_image_mark(); }

uint32_t PortStackUsed() {
  const uint32_t* p = __stack_limit;
  while (p < __stack_top && *p == semihosting::kStackPaint) ++p;
  return static_cast<uint32_t>(reinterpret_cast<uintptr_t>(__stack_top) -
                               reinterpret_cast<uintptr_t>(p));
}

void PortExit(int status) {
  if (g_line_length != 0) Flush();
  Semihost(semihosting::kSysExit,
           reinterpret_cast<const void*>(static_cast<uintptr_t>(
               status == 0 ? semihosting::kApplicationExit : semihosting::kRunTimeErrorUnknown)));
  for (;;) {
  }
}

}  // namespace image
}  // namespace fdsurf

void fdsurf_image_mark() { __asm__ volatile("" ::: "memory"); }
