// Cortex-M port of the test image for QEMU: a minimal vector table and reset
// handler, ARM semihosting (bkpt 0xAB) for output and the exit status.
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "../image/image.h"
#include "../image/port.h"

extern "C" {
// Linker script symbols (targets/link/arm-common.ld).
extern uint32_t __data_load[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern uint32_t __stack_limit[];
extern uint32_t __stack_top[];
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();

void fdsurf_reset_handler();
void fdsurf_fault_handler();
__attribute__((noinline, used)) void fdsurf_image_mark();
}

namespace {

constexpr uint32_t kStackPaint = 0xA5A5A5A5u;

// SYS_WRITE0, SYS_EXIT and the exit reasons of the semihosting specification.
constexpr uint32_t kSysWrite0 = 0x04;
constexpr uint32_t kSysExit = 0x18;
constexpr uint32_t kApplicationExit = 0x20026;
constexpr uint32_t kRunTimeErrorUnknown = 0x20023;

uint32_t Semihost(uint32_t operation, const void* argument) {
  register uint32_t r0 __asm__("r0") = operation;
  register const void* r1 __asm__("r1") = argument;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

// Output is sent a line at a time: one semihosting trap per line.
char g_line[128];
size_t g_line_length = 0;

void Flush() {
  g_line[g_line_length] = '\0';
  Semihost(kSysWrite0, g_line);
  g_line_length = 0;
}

}  // namespace

namespace fdsurf {
namespace image {

void PortPutChar(char c) {
  g_line[g_line_length++] = c;
  if (c == '\n' || g_line_length == sizeof g_line - 1) Flush();
}

void PortReadRom(void* to, const void* from, size_t n) { memcpy(to, from, n); }

void PortMark() { fdsurf_image_mark(); }

uint32_t PortStackUsed() {
  const uint32_t* p = __stack_limit;
  while (p < __stack_top && *p == kStackPaint) ++p;
  return static_cast<uint32_t>(reinterpret_cast<uintptr_t>(__stack_top) -
                               reinterpret_cast<uintptr_t>(p));
}

void PortExit(int status) {
  if (g_line_length != 0) Flush();
  Semihost(kSysExit, reinterpret_cast<const void*>(static_cast<uintptr_t>(
                         status == 0 ? kApplicationExit : kRunTimeErrorUnknown)));
  for (;;) {
  }
}

}  // namespace image
}  // namespace fdsurf

// The instruction-counting plugin (targets/sim/qemu_insn_count.c) records its
// counter each time this function's first instruction executes.
void fdsurf_image_mark() { __asm__ volatile("" ::: "memory"); }

void fdsurf_fault_handler() { fdsurf::image::PortExit(99); }

void fdsurf_reset_handler() {
#if defined(__ARM_FP)
  // Full access to CP10 and CP11 (the FPU) before any float instruction.
  volatile uint32_t* const cpacr = reinterpret_cast<volatile uint32_t*>(0xE000ED88u);
  *cpacr |= 0xFu << 20;
  __asm__ volatile("dsb\n\tisb" ::: "memory");
#endif
  for (uint32_t *from = __data_load, *to = __data_start; to < __data_end;) *to++ = *from++;
  for (uint32_t* p = __bss_start; p < __bss_end; ++p) *p = 0;
  // Paint the stack below this frame, for PortStackUsed.
  uint32_t* sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (uint32_t* p = __stack_limit; p < sp - 16; ++p) *p = kStackPaint;
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  fdsurf::image::PortExit(fdsurf::image::RunImage(false));
}

// Initial stack pointer, reset, and the fault vectors (NMI, HardFault,
// MemManage, BusFault, UsageFault): a fault ends the run with status 99
// instead of hanging.
__attribute__((section(".vectors"), used)) void (*const kVectorTable[])() = {
    reinterpret_cast<void (*)()>(__stack_top),
    fdsurf_reset_handler,
    fdsurf_fault_handler,
    fdsurf_fault_handler,
    fdsurf_fault_handler,
    fdsurf_fault_handler,
    fdsurf_fault_handler,
};
