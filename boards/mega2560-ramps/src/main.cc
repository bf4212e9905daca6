// SPDX-License-Identifier: MIT
// The fdsurf firmware for an Arduino Mega 2560 with a RAMPS 1.4 shield: the
// Device (protocol, command queue, path generator, motion loop) on UART0,
// the step tick from Timer3's compare interrupt, the pen servo on Timer1,
// and the hardware watchdog. README.md has the pin map and the figures.
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <stddef.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/board/byte_ring.h"
#include "fdsurf/board/uart_transport.h"
#include "fdsurf/device/device.h"
#include "ramps_inputs.h"
#include "ramps_outputs.h"

extern "C" {
// avr-libc's linker script: the first free byte after .data and .bss.
extern char __heap_start;
// The abstract HAL bases' vtables name it; every class here overrides all.
void __cxa_pure_virtual() {
  for (;;) {
  }
}
}

namespace fdsurf {
namespace mega {
namespace {

/// The value the free RAM is painted with at start; the stack's high-water
/// mark is the lowest address that no longer holds it (the simavr harness
/// reads it, host/README.md).
constexpr uint8_t kStackPaint = 0xA5;
/// The step interrupt kicks the watchdog only while the main loop has gone
/// round within this many ticks (or is inside Service(): a frame's
/// validation may take seconds, docs/motion.md), so a hung main loop and a
/// hung interrupt both reset the board.
constexpr uint16_t kHeartbeatTicks = static_cast<uint16_t>(kTickHz / 4);

/// Masks the step interrupt (all interrupts: SREG's I bit) while it lives.
struct TickInterruptLock {
  TickInterruptLock() : sreg_(SREG) { cli(); }
  ~TickInterruptLock() { SREG = sreg_; }
  TickInterruptLock(const TickInterruptLock&) = delete;
  TickInterruptLock& operator=(const TickInterruptLock&) = delete;
  uint8_t sreg_;
};

/// Transmission is polled: a reply is a few dozen bytes, the step interrupt
/// runs while the main loop waits, and a transmit ring would cost RAM that
/// the validation's stack needs.
struct Uart0 {
  static void Send(const uint8_t* data, size_t size) {
    for (size_t i = 0; i < size; ++i) {
      while ((UCSR0A & _BV(UDRE0)) == 0) {
      }
      UDR0 = data[i];
    }
  }
};

board::ByteRing<kRxRing> g_rx;
board::UartTransport<board::ByteRing<kRxRing>, Uart0> g_link(g_rx);
device::Device<kAxes, kQueueCapacity, kLookahead, TickInterruptLock> g_device(kTickHz);
RampsSteppers g_steppers;
ServoPen g_pen;
RampsEndstops g_endstops;
volatile uint16_t g_ticks_since_heartbeat = 0;
volatile bool g_in_service = false;
/// MCUSR at reset (why the board started), saved by SaveResetCause().
volatile uint8_t g_reset_cause = 0;

void PaintFreeRam() {
  uint8_t* const sp = reinterpret_cast<uint8_t*>(SP);
  for (uint8_t* p = reinterpret_cast<uint8_t*>(&__heap_start); p < sp - 32; ++p) *p = kStackPaint;
}

void StartUart() {
  // U2X: 16 MHz / (8 (UBRR + 1)): 16 -> 117 647 bit/s (+2.1 %, as every
  // Arduino sketch at 115200), 7 -> 250 000 exactly.
  UCSR0A = _BV(U2X0);
  UBRR0 = kBaud == 250000 ? 7 : 16;
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

void StartStepTimer() {
  TCCR3A = 0;
  TCNT3 = 0;
  OCR3A = static_cast<uint16_t>(kTimerClockHz / kTickHz - 1);
  TCCR3B = _BV(WGM32) | _BV(CS31);  // CTC on OCR3A, clock / 8
  TIMSK3 = _BV(OCIE3A);
}

void KeepAlive() {
  {
    const TickInterruptLock lock;
    g_ticks_since_heartbeat = 0;
  }
  wdt_reset();
}

// Nothing to do until the next interrupt (a received byte or a tick): no
// byte waiting, and the lookahead full or nothing left to expand. (Read
// without the lock: a stale answer costs at most one tick's sleep.)
bool NothingToDo() {
  if (!g_rx.Empty()) return false;
  const fdsurf::motion::MotionLoop& motion = g_device.motion();
  return motion.Full() || motion.Stopping() || g_device.Idle();
}

}  // namespace

void SetSafeOutputs() {
  // ENABLE high (released) before the pins become outputs.
  PORTD |= _BV(PD7);
  PORTF = _BV(PF2);
  PORTK |= _BV(PK0);
  DDRD |= _BV(PD7);
  DDRF |= _BV(PF0) | _BV(PF1) | _BV(PF2) | _BV(PF6) | _BV(PF7);
  DDRK |= _BV(PK0);
  PORTL &= static_cast<uint8_t>(~(_BV(PL1) | _BV(PL3)));
  DDRL |= _BV(PL1) | _BV(PL3);
  // The servo: fast PWM, TOP = ICR1 = 40 000 ticks of 0.5 us (20 ms),
  // non-inverting on OC1A, starting at "pen up".
  TCCR1A = _BV(COM1A1) | _BV(WGM11);
  TCCR1B = _BV(WGM13) | _BV(WGM12) | _BV(CS11);
  ICR1 = 40000 - 1;
  OCR1A = ServoPen::CompareFor(kServoUpUs);
  DDRB |= _BV(PB5);
}

}  // namespace mega
}  // namespace fdsurf

// Before .bss is cleared and the constructors run: keep why the board
// reset (in GPIOR0 until main() picks it up) and stop a watchdog that is
// still running from before the reset, so that it cannot reset the board
// again while it starts (it stays on at its shortest period after firing).
extern "C" void SaveResetCause() __attribute__((naked, used, section(".init3")));
extern "C" void SaveResetCause() {
  GPIOR0 = MCUSR;
  MCUSR = 0;
  wdt_disable();
}

ISR(TIMER1_OVF_vect) { fdsurf::mega::g_pen.OnPeriodStart(); }

ISR(USART0_RX_vect) { (void)fdsurf::mega::g_rx.Push(UDR0); }

ISR(TIMER3_COMPA_vect) {
  using namespace fdsurf::mega;
  // A failed output faults the device, which reports it in STATUS.
  (void)g_device.Tick(g_steppers, g_pen);
  const uint16_t since = g_ticks_since_heartbeat;
  if (since < kHeartbeatTicks || g_in_service) wdt_reset();
  if (since != 0xFFFFu) g_ticks_since_heartbeat = static_cast<uint16_t>(since + 1);
}

int main() {
  using namespace fdsurf::mega;
  g_reset_cause = GPIOR0;
  SetSafeOutputs();
  SetUpEndstopPins();
  g_device.set_endstops(&g_endstops);
  PaintFreeRam();
  StartUart();
  StartStepTimer();
  wdt_enable(WDTO_500MS);
  set_sleep_mode(SLEEP_MODE_IDLE);
  sei();
  for (;;) {
    KeepAlive();
    g_in_service = true;
    (void)g_device.Service(g_link);  // a UART transport never fails
    g_in_service = false;
    g_device.Fill(kFillBatch);
    if (NothingToDo()) {
      sleep_enable();
      sleep_cpu();
      sleep_disable();
    }
  }
}
