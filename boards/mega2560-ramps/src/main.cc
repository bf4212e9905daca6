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
#include "fdsurf/board/avr_runtime.h"
#include "fdsurf/board/byte_ring.h"
#include "fdsurf/board/uart_transport.h"
#include "fdsurf/device/device.h"
#include "ramps_inputs.h"
#include "ramps_outputs.h"

namespace fdsurf {
namespace mega {
namespace {

/// The step interrupt kicks the watchdog only while the main loop has gone
/// round within this many ticks (or is inside Service(): a frame's
/// validation may take seconds, docs/motion.md), so a hung main loop and a
/// hung interrupt both reset the board.
constexpr uint16_t kHeartbeatTicks = static_cast<uint16_t>(kTickHz / 4);

/// The step interrupt's lock as a type of this file's own: a Device of an
/// internal type is itself internal, so GCC inlines its Tick() and Fill(),
/// each called once, into the interrupt and main() (with the shared type
/// they stayed out of line: 486 bytes more on the Uno, 1 KB on the Mega,
/// and a call in the step interrupt).
struct TickInterruptLock : board::TickInterruptLock {
  TickInterruptLock() {}  // NOLINT(modernize-use-equals-default): const objects
};

board::ByteRing<kTxRing> g_tx;

/// UART0 for the transport: replies go into g_tx, and the data-register-
/// empty interrupt sends them (it turns itself off when the ring is empty;
/// a send turns it on again).
struct Uart0 {
  static void Send(const uint8_t* data, size_t size) {
    for (size_t i = 0; i < size; ++i) {
      while (g_tx.Size() == kTxRing) {
      }
      (void)g_tx.Push(data[i]);
      UCSR0B |= _BV(UDRIE0);
    }
  }
};

board::ByteRing<kRxRing> g_rx;
board::UartTransport<board::ByteRing<kRxRing>, Uart0> g_link(g_rx);
device::Device<kAxes, kQueueCapacity, kLookahead, TickInterruptLock> g_device(kTickHz, kSliceTicks);
RampsSteppers g_steppers;
ServoPen g_pen;
RampsEndstops g_endstops;
board::Heartbeat<kHeartbeatTicks> g_heartbeat;
/// MCUSR at reset (why the board started), saved by SaveResetCause().
volatile uint8_t g_reset_cause = 0;

void StartStepTimer() {
  TCCR3A = 0;
  TCNT3 = 0;
  OCR3A = static_cast<uint16_t>(kTimerClockHz / kTickHz - 1);
  TCCR3B = _BV(WGM32) | _BV(CS31);  // CTC on OCR3A, clock / 8
  TIMSK3 = _BV(OCIE3A);
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

ISR(TIMER1_OVF_vect) { fdsurf::mega::g_pen.OnPeriodStart(); }

ISR(USART0_RX_vect) { (void)fdsurf::mega::g_rx.Push(UDR0); }

ISR(USART0_UDRE_vect) {
  uint8_t byte = 0;
  if (fdsurf::mega::g_tx.Pop(&byte)) {
    UDR0 = byte;
  } else {
    UCSR0B &= static_cast<uint8_t>(~_BV(UDRIE0));
  }
}

ISR(TIMER3_COMPA_vect) {
  using namespace fdsurf::mega;
  // What the previous tick stepped, a whole tick after its pulse.
  g_steppers.EmitStep();
  // A failed output faults the device, which reports it in STATUS.
  (void)g_device.Tick(g_steppers, g_pen);
  g_heartbeat.OnTick();
}

int main() {
  using namespace fdsurf::mega;
  g_reset_cause = fdsurf::board::ResetCause();
  SetSafeOutputs();
  SetUpEndstopPins();
  g_device.set_endstops(&g_endstops);
  fdsurf::board::PaintFreeRam();
  fdsurf::board::StartUart0(kBaud);
  StartStepTimer();
  wdt_enable(WDTO_500MS);
  set_sleep_mode(SLEEP_MODE_IDLE);
  sei();
  for (;;) {
    g_heartbeat.Beat();
    g_heartbeat.set_in_service(true);
    (void)g_device.Service(g_link);  // a UART transport never fails
    g_heartbeat.set_in_service(false);
    g_device.Fill(kFillBatch);
    if (NothingToDo()) {
      sleep_enable();
      sleep_cpu();
      sleep_disable();
    }
  }
}
