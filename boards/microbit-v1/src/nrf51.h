// SPDX-License-Identifier: MIT
// The few nRF51822 registers the micro:bit v1 board port uses, from the
// nRF51 Series Reference Manual v3.0 (GPIO, UART, TIMER, CLOCK chapters) and
// the nRF51822 Product Specification (the peripheral and interrupt numbers),
// plus the Cortex-M0 NVIC (ARMv6-M Architecture Reference Manual).
#pragma once

#include <stdint.h>

namespace fdsurf {
namespace board {
namespace nrf51 {

inline volatile uint32_t& Reg(uint32_t address) {
  return *reinterpret_cast<volatile uint32_t*>(address);
}

// CLOCK (peripheral 0): the 16 MHz crystal, so that TIMER0 and the UART
// baud rate are accurate (the internal RC oscillator is only within a few %).
constexpr uint32_t kClock = 0x40000000u;
constexpr uint32_t kClockTasksHfclkStart = kClock + 0x000u;
constexpr uint32_t kClockEventsHfclkStarted = kClock + 0x100u;

// UART0 (peripheral 2, interrupt 2).
constexpr uint32_t kUart = 0x40002000u;
constexpr uint32_t kUartTasksStartRx = kUart + 0x000u;
constexpr uint32_t kUartTasksStartTx = kUart + 0x008u;
constexpr uint32_t kUartEventsRxdRdy = kUart + 0x108u;
constexpr uint32_t kUartEventsTxdRdy = kUart + 0x11Cu;
constexpr uint32_t kUartEventsError = kUart + 0x124u;
constexpr uint32_t kUartIntenSet = kUart + 0x304u;
constexpr uint32_t kUartErrorSrc = kUart + 0x480u;
constexpr uint32_t kUartEnable = kUart + 0x500u;
constexpr uint32_t kUartPselRts = kUart + 0x508u;
constexpr uint32_t kUartPselTxd = kUart + 0x50Cu;
constexpr uint32_t kUartPselCts = kUart + 0x510u;
constexpr uint32_t kUartPselRxd = kUart + 0x514u;
constexpr uint32_t kUartRxd = kUart + 0x518u;
constexpr uint32_t kUartTxd = kUart + 0x51Cu;
constexpr uint32_t kUartBaudrate = kUart + 0x524u;
constexpr uint32_t kUartConfig = kUart + 0x56Cu;
constexpr uint32_t kUartEnableValue = 4u;          // ENABLE = Enabled
constexpr uint32_t kUartBaud115200 = 0x01D7E000u;  // BAUDRATE = Baud115200
constexpr uint32_t kUartIntRxdRdy = 1u << 2;       // INTEN.RXDRDY
constexpr uint32_t kUartIntError = 1u << 9;        // INTEN.ERROR
constexpr uint32_t kUartPinDisconnected = 0xFFFFFFFFu;
constexpr uint32_t kUartIrq = 2u;

// TIMER0 (peripheral 8, interrupt 8): 32-bit, 16 MHz with prescaler 0.
constexpr uint32_t kTimer = 0x40008000u;
constexpr uint32_t kTimerTasksStart = kTimer + 0x000u;
constexpr uint32_t kTimerTasksClear = kTimer + 0x00Cu;
inline constexpr uint32_t TimerTasksCapture(uint32_t n) { return kTimer + 0x040u + 4u * n; }
inline constexpr uint32_t TimerEventsCompare(uint32_t n) { return kTimer + 0x140u + 4u * n; }
inline constexpr uint32_t TimerCc(uint32_t n) { return kTimer + 0x540u + 4u * n; }
constexpr uint32_t kTimerIntenSet = kTimer + 0x304u;
constexpr uint32_t kTimerMode = kTimer + 0x504u;       // 0: timer
constexpr uint32_t kTimerBitmode = kTimer + 0x508u;    // 3: 32 bit
constexpr uint32_t kTimerPrescaler = kTimer + 0x510u;  // f = 16 MHz / 2^PRESCALER
constexpr uint32_t kTimerIntCompare0 = 1u << 16;
constexpr uint32_t kTimerIrq = 8u;
constexpr uint32_t kTimerHz = 16000000u;

// TIMER1 (peripheral 9, interrupt 9): at most 16-bit on the nRF51 (TIMER0
// alone counts 32 bits); the same register layout as TIMER0.
constexpr uint32_t kTimer1 = 0x40009000u;
constexpr uint32_t kTimer1TasksStart = kTimer1 + 0x000u;
constexpr uint32_t kTimer1TasksClear = kTimer1 + 0x00Cu;
inline constexpr uint32_t Timer1TasksCapture(uint32_t n) { return kTimer1 + 0x040u + 4u * n; }
inline constexpr uint32_t Timer1EventsCompare(uint32_t n) { return kTimer1 + 0x140u + 4u * n; }
inline constexpr uint32_t Timer1Cc(uint32_t n) { return kTimer1 + 0x540u + 4u * n; }
constexpr uint32_t kTimer1IntenSet = kTimer1 + 0x304u;
constexpr uint32_t kTimer1Mode = kTimer1 + 0x504u;
constexpr uint32_t kTimer1Bitmode = kTimer1 + 0x508u;    // 0: 16 bit
constexpr uint32_t kTimer1Prescaler = kTimer1 + 0x510u;  // 4: 1 MHz
constexpr uint32_t kTimerIntCompare1 = 1u << 17;
constexpr uint32_t kTimer1Irq = 9u;

// GPIO (P0.00 .. P0.31).
constexpr uint32_t kGpio = 0x50000000u;
constexpr uint32_t kGpioOut = kGpio + 0x504u;
constexpr uint32_t kGpioOutSet = kGpio + 0x508u;
constexpr uint32_t kGpioOutClr = kGpio + 0x50Cu;
constexpr uint32_t kGpioIn = kGpio + 0x510u;
constexpr uint32_t kGpioDirSet = kGpio + 0x518u;
inline constexpr uint32_t GpioPinCnf(uint32_t pin) { return kGpio + 0x700u + 4u * pin; }
// PIN_CNF: DIR output, input buffer disconnected, no pull, drive S0S1.
constexpr uint32_t kPinCnfOutput = 0x00000003u;
// PIN_CNF: DIR input, input buffer connected, pull-up (the UART's RXD).
constexpr uint32_t kPinCnfInputPullUp = 0x0000000Cu;

// NVIC (ARMv6-M): set-enable, clear-enable, clear-pending, priority (2 bits, [7:6]).
constexpr uint32_t kNvicIser = 0xE000E100u;
constexpr uint32_t kNvicIcer = 0xE000E180u;
constexpr uint32_t kNvicIcpr = 0xE000E280u;
inline constexpr uint32_t NvicIpr(uint32_t irq) { return 0xE000E400u + 4u * (irq / 4u); }

inline void EnableIrq(uint32_t irq, uint32_t priority) {
  const uint32_t shift = 8u * (irq % 4u) + 6u;
  Reg(NvicIpr(irq)) = (Reg(NvicIpr(irq)) & ~(3u << shift)) | ((priority & 3u) << shift);
  Reg(kNvicIcpr) = 1u << irq;
  Reg(kNvicIser) = 1u << irq;
}

}  // namespace nrf51
}  // namespace board
}  // namespace fdsurf
