// SPDX-License-Identifier: MIT
// Cortex-M port of the test image for QEMU: a minimal vector table and reset
// handler, ARM semihosting (bkpt 0xAB) for output and the exit status.
#include <stddef.h>
#include <stdint.h>

#include "../image/image.h"
#include "../image/port.h"
#include "semihosting.h"

extern "C" {
// Linker script symbols (targets/link/arm-common.ld).
extern uint32_t __data_load[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();

void fdsurf_reset_handler();
void fdsurf_fault_handler();
}

namespace fdsurf {
namespace image {
namespace semihosting {

uint32_t Semihost(uint32_t operation, const void* argument) {
  register uint32_t r0 __asm__("r0") = operation;
  register const void* r1 __asm__("r1") = argument;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace semihosting
}  // namespace image
}  // namespace fdsurf

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
  for (uint32_t* p = __stack_limit; p < sp - 16; ++p) *p = fdsurf::image::semihosting::kStackPaint;
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
