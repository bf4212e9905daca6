// SPDX-License-Identifier: MIT
// The fdsurf plotter firmware on a BBC micro:bit v1 (nRF51822, Cortex-M0,
// 16 MHz, 16 KB RAM): the protocol on UART0 (the interface chip's serial
// pins, 115200 8N1, receive interrupt into a ring, polled send), the step
// tick from TIMER0's compare interrupt, step/dir/enable on edge-connector
// pins (pins.h), the pen as a hobby servo's pulses from TIMER1 (servo_pwm.h)
// or, built with FDSURF_MICROBIT_SERVO=0, as a line, and X/Y min endstops on
// two more pins (endstop_pins.h). The main loop only
// services the link and fills the lookahead buffer; Device::Tick() runs in
// the timer interrupt.
#include <stddef.h>
#include <stdint.h>

#include "board_stats.h"
#include "endstop_pins.h"
#include "fdsurf/board/byte_ring.h"
#include "fdsurf/board/uart_transport.h"
#include "fdsurf/device/device.h"
#include "nrf51.h"
#include "pins.h"
#include "servo_pwm.h"

#ifndef FDSURF_MICROBIT_TICK_HZ
#define FDSURF_MICROBIT_TICK_HZ 12500
#endif
// Ticks per slice: the tick runs the motion profile's choice (64-bit) once
// a slice and only adds in between (docs/motion.md, "Slices").
#ifndef FDSURF_MICROBIT_SLICE_TICKS
#define FDSURF_MICROBIT_SLICE_TICKS 16
#endif
// 1: the pen is a hobby servo on edge P1 (the default); 0: a line on P0.
#ifndef FDSURF_MICROBIT_SERVO
#define FDSURF_MICROBIT_SERVO 1
#endif
#ifndef FDSURF_MICROBIT_SERVO_UP_US
#define FDSURF_MICROBIT_SERVO_UP_US 1000
#endif
#ifndef FDSURF_MICROBIT_SERVO_DOWN_US
#define FDSURF_MICROBIT_SERVO_DOWN_US 2000
#endif

// Abstract HAL bases name it in their vtables; it is never called.
extern "C" void __cxa_pure_virtual() {
  for (;;) {
  }
}

extern "C" {
fdsurf::board::BoardStats fdsurf_board_stats;
void fdsurf_board_main();
void fdsurf_board_uart_irq();
void fdsurf_board_timer_irq();
void fdsurf_board_servo_irq();
// The pen this image drives, for the QEMU harness (host/run_qemu.py reads it
// from the ELF): {0, 0, 0} a line on pins::kPen, {1, up, down} a servo on
// pins::kServo with the image's widths in µs.
extern const uint32_t fdsurf_board_pen[3];
}

namespace fdsurf {
namespace board {
namespace {

using nrf51::Reg;

/// The step tick (HELLO reports it; README.md says why this rate).
constexpr uint32_t kTickHz = FDSURF_MICROBIT_TICK_HZ;
constexpr uint32_t kTickPeriod = nrf51::kTimerHz / kTickHz;
static_assert(nrf51::kTimerHz % kTickHz == 0, "a whole number of 16 MHz counts per tick");

/// The pen servo's pulses for pen up and down (µs, every 20 ms), until a
/// CONFIG gives others (hal::ServoPen).
constexpr bool kServoPen = FDSURF_MICROBIT_SERVO != 0;
constexpr uint16_t kServoUpUs = FDSURF_MICROBIT_SERVO_UP_US;
constexpr uint16_t kServoDownUs = FDSURF_MICROBIT_SERVO_DOWN_US;
static_assert(kServoUpUs >= hal::kServoMinPulseUs && kServoUpUs <= hal::kServoMaxPulseUs &&
                  kServoDownUs >= hal::kServoMinPulseUs && kServoDownUs <= hal::kServoMaxPulseUs &&
                  kServoUpUs != kServoDownUs,
              "servo pulses from 500 to 2500 us, up and down different");

// Interrupt priorities (0 highest): the servo's edges, then the step tick,
// then the UART's receive (a byte waits in the 6-byte FIFO meanwhile). The
// servo's handler is ~40 instructions twice per 20 ms, the only thing that
// can delay a tick; a tick (up to ~460 cycles) could otherwise stretch a
// servo pulse by ~30 µs.
constexpr uint32_t kServoPriority = 0;
constexpr uint32_t kTickPriority = 1;
constexpr uint32_t kUartPriority = 2;

/// Masks the step tick's and the UART's interrupts (TIMER0, UART0, in the
/// NVIC) while it lives, restoring the previous state: the Device's
/// InterruptLock (fdsurf/device/device.h). Not PRIMASK: the servo's
/// interrupt must stay free to run, and a masked section (some take
/// ~15 µs) would stretch or cut its pulse (the M0 has no BASEPRI). The UART
/// is masked too, as PRIMASK did: its handler drains every byte QEMU has
/// (a burst of dozens), which inside a section delayed a tick by 53 µs.
/// dsb + isb: no instruction after the constructor runs before the mask.
class TickLock {
 public:
  TickLock() : was_enabled_(nrf51::Reg(nrf51::kNvicIser) & kBits) {
    nrf51::Reg(nrf51::kNvicIcer) = kBits;
    __asm__ volatile("dsb\n\tisb" : : : "memory");
  }
  ~TickLock() {
    __asm__ volatile("" : : : "memory");
    nrf51::Reg(nrf51::kNvicIser) = was_enabled_;
  }
  TickLock(const TickLock&) = delete;
  TickLock& operator=(const TickLock&) = delete;

 private:
  static constexpr uint32_t kBits = (1u << nrf51::kTimerIrq) | (1u << nrf51::kUartIrq);
  uint32_t was_enabled_;
};

/// Busy-waits about `loops` × 6 cycles on the M0 (2 nops, subs, a taken
/// branch), 4 instructions = 256 ns under QEMU -icount shift=6.
inline void Delay(uint32_t loops) {
  __asm__ volatile("1:\n\tnop\n\tnop\n\tsub %0, #1\n\tbne 1b" : "+l"(loops) : : "cc");
}

// A4988: STEP high ≥ 1 µs, DIR set-up ≥ 200 ns; DRV8825: 1.9 µs and 650 ns.
// 8 loops: 3.0 µs on the board, 2.05 µs under QEMU; 3 loops: 1.1 µs, 768 ns.
constexpr uint32_t kStepHighLoops = 8;
constexpr uint32_t kDirSetupLoops = 3;

/// The interface chip's UART: polled send (a reply is a few dozen bytes;
/// the timer interrupt runs meanwhile).
struct Uart {
  static void Send(const uint8_t* data, size_t size) {
    for (size_t i = 0; i < size; ++i) {
      Reg(nrf51::kUartEventsTxdRdy) = 0;
      Reg(nrf51::kUartTxd) = data[i];
      // One byte takes 87 µs at 115200 baud; the bound only keeps a stuck
      // peripheral from hanging the loop.
      for (uint32_t wait = 0; wait < 100000u && Reg(nrf51::kUartEventsTxdRdy) == 0; ++wait) {
      }
    }
  }
};

/// STEP/DIR/ENABLE of two A4988/DRV8825 drivers and the PEN line, driven
/// one tick late: what Device::Tick() asks for is recorded, and Emit(),
/// first thing in the next tick interrupt, drives it. The pins then change a
/// fixed time after each compare, however long the tick's computation took
/// (from ~150 to ~700 cycles of the 800-cycle period: the turn caps'
/// bookkeeping varies), so consecutive moves stay a whole tick apart.
class PinOutputs final : public hal::StepDirOutputs, public hal::PenOutput {
 public:
  PinOutputs() : hal::StepDirOutputs(2) {}
  ~PinOutputs() = default;

  /// Drives what the previous tick recorded, in the order the device asked:
  /// the pen, the enable line, the directions (then their set-up time), the
  /// STEP pulses.
  void Emit() {
    if (pen_set_) Reg(pen_down_ ? nrf51::kGpioOutSet : nrf51::kGpioOutClr) = pins::Bit(pins::kPen);
    if (enable_set_) {
      Reg(enabled_ ? nrf51::kGpioOutClr : nrf51::kGpioOutSet) = pins::Bit(pins::kEnable);
    }
    if (directions_set_) {
      Reg(nrf51::kGpioOutSet) = negative_bits_;
      Reg(nrf51::kGpioOutClr) = (pins::kDirBits[0] | pins::kDirBits[1]) & ~negative_bits_;
      Delay(kDirSetupLoops);
    }
    if (step_bits_ != 0) {
      Reg(nrf51::kGpioOutSet) = step_bits_;
      Delay(kStepHighLoops);
      Reg(nrf51::kGpioOutClr) = step_bits_;
    }
    pen_set_ = enable_set_ = directions_set_ = false;
    step_bits_ = 0;
  }

 private:
  hal::IoStatus DoSetEnabled(bool enabled) override {
    enabled_ = enabled;
    enable_set_ = true;
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoSetDirections(uint8_t negative_mask) override {
    if ((negative_mask & ~axis_bits()) != 0) return hal::IoStatus::kInvalidArgument;
    uint32_t negative = 0;
    for (int a = 0; a < 2; ++a) {
      if ((negative_mask >> a) & 1u) negative |= pins::kDirBits[a];
    }
    negative_bits_ = negative;
    directions_set_ = true;
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoStep(uint8_t axis_mask) override {
    if ((axis_mask & ~axis_bits()) != 0) return hal::IoStatus::kInvalidArgument;
    step_bits_ |=
        ((axis_mask & 1u) ? pins::kStepBits[0] : 0u) | ((axis_mask & 2u) ? pins::kStepBits[1] : 0u);
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoSetPen(bool down) override {
    pen_down_ = down;
    pen_set_ = true;
    return hal::IoStatus::kOk;
  }
  const char* DoLastError() const override { return ""; }

  // Recorded by the tick, driven by the next one's Emit().
  uint32_t negative_bits_ = 0;
  uint32_t step_bits_ = 0;
  bool enabled_ = false;
  bool pen_down_ = false;
  bool enable_set_ = false;
  bool directions_set_ = false;
  bool pen_set_ = false;
};

// 256 lookahead entries hold the braking distance up to ~110 mm/s at
// 2000 mm/s² and 0.0125 mm steps (v²/2a = 225 steps); the motion loop's
// walk over the buffer at each pen event costs ~32 cycles per entry in the
// tick (README.md, measures), so a longer buffer costs late ticks there.
constexpr int kLookahead = 256;
// The M0 validates a PATCH in up to ~80 ms (README.md), while 115200 baud
// brings ~950 bytes: a 128-byte ring dropped 482 bytes of a 5-command job,
// each loss a NAK or a timeout and a resend. 2 KB holds them all.
constexpr uint16_t kRxRingBytes = 2048;
using RxRing = ByteRing<kRxRingBytes, uint16_t>;
using BoardDevice = device::Device<2, 8, kLookahead, TickLock>;
// Entries Device::Fill() may push before the main loop services the link
// again. Unbounded, a round never ended while the motion used entries
// faster than the main loop made them (about 4 100 cycles a point, with the
// 20 kHz tick taking 55 % of the core: 1 750 points a second against 8 000
// steps a second asked on the whole teapot), and the 2 KB ring dropped
// 5 393 received bytes (a 7.8 s round). 64 points are about 40 ms of the
// main loop's share of the core, well within the 178 ms the ring holds.
constexpr uint16_t kFillBatch = 64;

RxRing g_rx;
BoardDevice g_device(kTickHz, FDSURF_MICROBIT_SLICE_TICKS);
PinOutputs g_outputs;
PinEndstops g_endstops;
TimerPwm g_servo_pwm(pins::kServo);
hal::ServoPen g_servo_pen(g_servo_pwm, kServoUpUs, kServoDownUs);
uint32_t g_next_compare;

/// The pen Device::Tick() drives: the servo, or PinOutputs' PEN line.
hal::PenOutput& Pen() {
  if (kServoPen) return g_servo_pen;
  return g_outputs;
}

uint32_t CaptureTimer(uint32_t channel) {
  Reg(nrf51::TimerTasksCapture(channel)) = 1;
  return Reg(nrf51::TimerCc(channel));
}

void SetUpPins() {
  // Levels first (drivers disabled, everything else low), then outputs.
  Reg(nrf51::kGpioOutClr) = pins::kOutputBits;
  Reg(nrf51::kGpioOutSet) = pins::Bit(pins::kEnable);
  const uint32_t outputs[] = {pins::kXStep, pins::kXDir,   pins::kYStep,
                              pins::kYDir,  pins::kEnable, pins::kPen};
  for (uint32_t pin : outputs) Reg(nrf51::GpioPinCnf(pin)) = nrf51::kPinCnfOutput;
  Reg(nrf51::kGpioDirSet) = pins::kOutputBits;
}

void SetUpClock() {
  Reg(nrf51::kClockEventsHfclkStarted) = 0;
  Reg(nrf51::kClockTasksHfclkStart) = 1;
  // The crystal starts in < 1 ms; the bound keeps a board without one going.
  for (uint32_t wait = 0; wait < 200000u && Reg(nrf51::kClockEventsHfclkStarted) == 0; ++wait) {
  }
}

void SetUpUart() {
  Reg(nrf51::GpioPinCnf(pins::kUartRx)) = nrf51::kPinCnfInputPullUp;
  Reg(nrf51::GpioPinCnf(pins::kUartTx)) = nrf51::kPinCnfOutput;
  Reg(nrf51::kGpioOutSet) = pins::Bit(pins::kUartTx);  // idle high
  Reg(nrf51::kUartPselTxd) = pins::kUartTx;
  Reg(nrf51::kUartPselRxd) = pins::kUartRx;
  Reg(nrf51::kUartPselRts) = nrf51::kUartPinDisconnected;
  Reg(nrf51::kUartPselCts) = nrf51::kUartPinDisconnected;
  Reg(nrf51::kUartConfig) = 0;  // no parity, no flow control
  Reg(nrf51::kUartBaudrate) = nrf51::kUartBaud115200;
  Reg(nrf51::kUartEnable) = nrf51::kUartEnableValue;
  Reg(nrf51::kUartEventsRxdRdy) = 0;
  Reg(nrf51::kUartEventsError) = 0;
  Reg(nrf51::kUartTasksStartRx) = 1;
  Reg(nrf51::kUartTasksStartTx) = 1;
  Reg(nrf51::kUartIntenSet) = nrf51::kUartIntRxdRdy | nrf51::kUartIntError;
  nrf51::EnableIrq(nrf51::kUartIrq, kUartPriority);
}

// Free-running 32-bit counter, CC[0] moved one period ahead at each tick:
// the schedule never drifts, and the lateness of each tick is exact.
// CC[1] is the interrupt's capture, CC[2] the main loop's.
void SetUpTimer() {
  Reg(nrf51::kTimerMode) = 0;
  Reg(nrf51::kTimerBitmode) = 3;
  Reg(nrf51::kTimerPrescaler) = 0;
  Reg(nrf51::kTimerTasksClear) = 1;
  g_next_compare = kTickPeriod;
  Reg(nrf51::TimerCc(0)) = g_next_compare;
  Reg(nrf51::TimerEventsCompare(0)) = 0;
  Reg(nrf51::kTimerIntenSet) = nrf51::kTimerIntCompare0;
  nrf51::EnableIrq(nrf51::kTimerIrq, kTickPriority);
  Reg(nrf51::kTimerTasksStart) = 1;
}

void AddCycles(uint32_t* low, uint32_t* high, uint32_t cycles) {
  const uint32_t sum = *low + cycles;
  if (sum < *low) ++*high;
  *low = sum;
}

// One main-loop round: bytes in, replies out, lookahead filled. Measured
// when it did work.
void ServiceOnce(hal::Transport& link) {
  BoardStats& stats = fdsurf_board_stats;
  uint32_t start, tick_cycles_before, entries_before, rx_before;
  {
    const TickLock lock;
    start = CaptureTimer(2);
    tick_cycles_before = stats.tick_cycles_low;
    entries_before = g_device.motion().Count() + g_device.motion().moves();
    rx_before = stats.rx_bytes;
  }
  (void)g_device.Service(link);
  g_device.Fill(kFillBatch);
  const TickLock lock;
  const uint32_t elapsed = CaptureTimer(2) - start - (stats.tick_cycles_low - tick_cycles_before);
  const uint32_t entries = g_device.motion().Count() + g_device.motion().moves() - entries_before;
  if (entries == 0 && stats.rx_bytes == rx_before) return;
  AddCycles(&stats.work_cycles_low, &stats.work_cycles_high, elapsed);
  stats.points += entries;
  if (elapsed > stats.max_work_cycles) stats.max_work_cycles = elapsed;
}

}  // namespace
}  // namespace board
}  // namespace fdsurf

void fdsurf_board_uart_irq() {
  using namespace fdsurf::board;
  BoardStats& stats = fdsurf_board_stats;
  if (Reg(nrf51::kUartEventsError) != 0) {
    Reg(nrf51::kUartEventsError) = 0;
    Reg(nrf51::kUartErrorSrc) = Reg(nrf51::kUartErrorSrc);  // write 1 to clear
    ++stats.uart_errors;
  }
  while (Reg(nrf51::kUartEventsRxdRdy) != 0) {
    // The event is cleared before RXD is read (Reference Manual, UART).
    Reg(nrf51::kUartEventsRxdRdy) = 0;
    const uint8_t byte = static_cast<uint8_t>(Reg(nrf51::kUartRxd));
    ++stats.rx_bytes;
    if (!g_rx.Push(byte)) ++stats.rx_overruns;
  }
}

void fdsurf_board_timer_irq() {
  using namespace fdsurf::board;
  BoardStats& stats = fdsurf_board_stats;
  Reg(nrf51::TimerEventsCompare(0)) = 0;
  const uint32_t entry = CaptureTimer(1);
  const uint32_t lateness = entry - g_next_compare;
  if (lateness >= kTickPeriod) {
    // The next slot has passed too: re-arm from now.
    ++stats.missed_ticks;
    g_next_compare = entry + kTickPeriod;
  } else {
    g_next_compare += kTickPeriod;
  }
  Reg(nrf51::TimerCc(0)) = g_next_compare;
  // The next compare is most of a period away, so this loses no real event;
  // QEMU's nrf51 timer raises a stale COMPARE[0] on the CC[0] write, which
  // would re-enter this handler at once (seen as ticks a period early).
  Reg(nrf51::TimerEventsCompare(0)) = 0;
  if (lateness > kTickPeriod / 2) {
    ++stats.late_ticks;
    if (g_device.motion().speed() != 0) ++stats.late_moving_ticks;
  }
  if (lateness > stats.max_lateness) stats.max_lateness = lateness;
  g_outputs.Emit();  // the previous tick's outputs, at a fixed time after the compare
  const uint32_t moves = g_device.motion().moves();
  (void)g_device.Tick(g_outputs, Pen());
  const uint32_t cycles = CaptureTimer(1) - entry;
  ++stats.ticks;
  AddCycles(&stats.tick_cycles_low, &stats.tick_cycles_high, cycles);
  if (cycles > stats.max_tick_cycles) stats.max_tick_cycles = cycles;
  if (g_device.motion().moves() != moves) {
    ++stats.stepping_ticks;
    if (cycles > stats.max_stepping_tick_cycles) stats.max_stepping_tick_cycles = cycles;
  }
}

void fdsurf_board_servo_irq() {
  using namespace fdsurf::board;
  g_servo_pwm.OnInterrupt();
  fdsurf_board_stats.servo_periods = g_servo_pwm.periods();
  fdsurf_board_stats.servo_max_lateness_us = g_servo_pwm.max_lateness_us();
}

__attribute__((used)) const uint32_t fdsurf_board_pen[3] = {
    fdsurf::board::kServoPen ? 1u : 0u, fdsurf::board::kServoPen ? fdsurf::board::kServoUpUs : 0u,
    fdsurf::board::kServoPen ? fdsurf::board::kServoDownUs : 0u};

void fdsurf_board_main() {
  using namespace fdsurf::board;
  fdsurf_board_stats.magic = kBoardStatsMagic;
  fdsurf_board_stats.tick_hz = kTickHz;
  SetUpPins();
  SetUpEndstopPins();
  g_device.set_endstops(&g_endstops);
  SetUpClock();
  SetUpUart();
  UartTransport<RxRing, Uart> link(g_rx);
  if (kServoPen) {
    // Pen up from the first period on (hal::ServoPen::Start cannot fail on
    // this PWM: 20 ms and the image's widths are within its range).
    g_servo_pwm.Start(kServoPriority);
    (void)g_servo_pen.Start();
  }
  SetUpTimer();
  for (;;) ServiceOnce(link);
}
