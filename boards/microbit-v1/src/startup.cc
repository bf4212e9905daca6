// SPDX-License-Identifier: MIT
// Reset and the vector table of the micro:bit v1 image (nRF51822: the 16
// Cortex-M0 system vectors, then its 32 peripheral interrupts). The reset
// handler copies .data, clears .bss, paints the free RAM for the stack
// high-water measurement, runs the static constructors and calls
// fdsurf_board_main(). No semihosting: this image runs on the board.
#include <stdint.h>

#include "board_stats.h"
#include "nrf51.h"
#include "pins.h"

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

void fdsurf_board_reset();
void fdsurf_board_fault();
void fdsurf_board_main();
void fdsurf_board_uart_irq();
void fdsurf_board_timer_irq();
void fdsurf_board_servo_irq();
extern fdsurf::board::BoardStats fdsurf_board_stats;
}

void fdsurf_board_reset() {
  for (uint32_t *from = __data_load, *to = __data_start; to < __data_end;) *to++ = *from++;
  for (uint32_t* p = __bss_start; p < __bss_end; ++p) *p = 0;
  // Paint everything between .bss and this frame: the lowest word that is
  // no longer the paint at the end of a run is the stack's high-water.
  uint32_t* sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (uint32_t* p = __stack_limit; p < sp - 16; ++p) *p = fdsurf::board::kStackPaint;
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  fdsurf_board_main();
  for (;;) {
  }
}

// Any fault or unexpected interrupt: release the motors (ENABLE is active
// low), lower the pen line and the servo pin, record the exception number, and stop.
void fdsurf_board_fault() {
  __asm__ volatile("cpsid i" ::: "memory");
  using fdsurf::board::nrf51::Reg;
  Reg(fdsurf::board::nrf51::kGpioOutSet) = fdsurf::board::pins::Bit(fdsurf::board::pins::kEnable);
  // No more servo pulses (its interrupt is masked now): the pin low, not
  // stuck high; a PEN line goes up.
  Reg(fdsurf::board::nrf51::kGpioOutClr) = fdsurf::board::pins::Bit(fdsurf::board::pins::kServo) |
                                           fdsurf::board::pins::Bit(fdsurf::board::pins::kPen);
  uint32_t ipsr;
  __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
  fdsurf_board_stats.fault = ipsr == 0 ? 0xFFu : ipsr;
  for (;;) {
  }
}

#define FAULT fdsurf_board_fault
// Entry 0 is the initial stack pointer, 1 the reset handler, 2..15 the
// system exceptions, then the nRF51 interrupts 0..31 (UART0 is 2, TIMER0 8, TIMER1 9).
// The linker script keeps .vectors at address 0.
// clang-format off
__attribute__((section(".vectors"), used)) void (*const kVectorTable[16 + 32])() = {
    reinterpret_cast<void (*)()>(__stack_top), fdsurf_board_reset,
    FAULT, FAULT, FAULT, FAULT, FAULT, FAULT, FAULT,          // NMI .. 8
    FAULT, FAULT, FAULT, FAULT, FAULT, FAULT, FAULT,          // 9 .. SysTick
    FAULT, FAULT, fdsurf_board_uart_irq, FAULT,               // POWER_CLOCK, RADIO, UART0, SPI0/TWI0
    FAULT, FAULT, FAULT, FAULT,                               // SPI1/TWI1, -, GPIOTE, ADC
    fdsurf_board_timer_irq, fdsurf_board_servo_irq, FAULT, FAULT,  // TIMER0, TIMER1, TIMER2, RTC0
    FAULT, FAULT, FAULT, FAULT, FAULT, FAULT, FAULT, FAULT,   // 12 .. 19
    FAULT, FAULT, FAULT, FAULT, FAULT, FAULT, FAULT, FAULT,   // 20 .. 27
    FAULT, FAULT, FAULT, FAULT,                               // 28 .. 31
};
// clang-format on
#undef FAULT
