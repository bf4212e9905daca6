// SPDX-License-Identifier: MIT
// The fdsurf firmware for an Arduino Uno with a CNC Shield v3: the Device
// without a planner (it takes PREPARED_CURVE, MOVE, PEN, HOME and MOTORS;
// the host plans, `fdsurf stream --prepare-on-host`) on the USART, the step
// tick from Timer1's compare interrupt (as Grbl's stepper), the pen servo
// on Timer2, and the hardware watchdog. README.md has the pin map and the
// figures.
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <stddef.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/board/byte_ring.h"
#include "fdsurf/device/device.h"
#include "servo_pwm.h"
#include "shield_inputs.h"
#include "shield_outputs.h"

#if FDSURF_DEVICE_PLANNER || FDSURF_DEVICE_WIDE_TABLES
#error "the Uno image links fdsurf_core_prepared (no planner, 64-bit tables): only that fits"
#endif

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
namespace uno {
namespace {

/// The value the free RAM is painted with at start; the stack's high-water
/// mark is the lowest address that no longer holds it (the simavr harness
/// reads it, boards/mega2560-ramps/host/board_measures.h).
constexpr uint8_t kStackPaint = 0xA5;
/// The step interrupt kicks the watchdog only while the main loop has gone
/// round within this many ticks (or is inside Service()), so a hung main
/// loop and a hung interrupt both reset the board.
constexpr uint16_t kHeartbeatTicks = static_cast<uint16_t>(kTickHz / 4);

/// Masks the step interrupt (all interrupts: SREG's I bit) while it lives.
struct TickInterruptLock {
  TickInterruptLock() : sreg_(SREG) { cli(); }
  ~TickInterruptLock() { SREG = sreg_; }
  TickInterruptLock(const TickInterruptLock&) = delete;
  TickInterruptLock& operator=(const TickInterruptLock&) = delete;
  uint8_t sreg_;
};

board::ByteRing<kRxRing> g_rx;
device::Device<kAxes, kQueueCapacity, kLookahead, TickInterruptLock,
               protocol::kMaxPreparedFrameBytes, kReplyBytes>
    g_device(kTickHz);
ShieldSteppers g_steppers;
ShieldEndstops g_endstops;
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
  TCCR1A = 0;
  TCNT1 = 0;
  OCR1A = static_cast<uint16_t>(kTimerClockHz / kTickHz - 1);
  TCCR1B = _BV(WGM12) | _BV(CS11);  // CTC on OCR1A, clock / 8
  TIMSK1 = _BV(OCIE1A);
}

/// Transmission is polled: a reply is a few dozen bytes, the step interrupt
/// runs while the main loop waits, and a transmit ring would cost RAM that
/// the stack needs.
void Send(const uint8_t* data, size_t size) {
  for (size_t i = 0; i < size; ++i) {
    while ((UCSR0A & _BV(UDRE0)) == 0) {
    }
    UDR0 = data[i];
  }
}

/// What Device::Service() does with a hal::Transport, without its 64-byte
/// buffer on the stack (the deepest path, a PREPARED_CURVE's check inside
/// OnByte() with the step interrupt on top, leaves the stack no 64 bytes to
/// spare; README.md, "RAM"): the bytes the ring holds (at most a ring's
/// worth, so that Fill() is not starved) go to the Device one by one, and
/// its replies out through 16 bytes.
void ServiceLink() {
  uint8_t byte = 0;
  for (uint8_t n = 0; n < kRxRing && g_rx.Pop(&byte); ++n) g_device.OnByte(byte);
  uint8_t out[16];
  for (size_t n = g_device.ReadOutput(out, sizeof out); n != 0;
       n = g_device.ReadOutput(out, sizeof out)) {
    Send(out, n);
  }
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

ServoPen g_pen;

void SetSafeOutputs() {
  // EN high (released) before the pins become outputs: the drivers' own
  // pull-downs hold them enabled until then.
  PORTB |= _BV(PB0);
  DDRB |= _BV(PB0);
  // STEP and DIR low, Z's too (the job never drives Z).
  PORTD &= static_cast<uint8_t>(~(_BV(PD2) | _BV(PD3) | _BV(PD4) | _BV(PD5) | _BV(PD6) | _BV(PD7)));
  DDRD |= _BV(PD2) | _BV(PD3) | _BV(PD4) | _BV(PD5) | _BV(PD6) | _BV(PD7);
  ServoPen::Start();
}

}  // namespace uno
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

ISR(TIMER2_COMPA_vect) { fdsurf::uno::g_pen.OnCompare(); }

// A byte that finds the ring full is lost (the link protocol resends its
// frame); the count of them, saturating at 255, is kept in GPIOR1, a
// general-purpose I/O register that costs no RAM, where the simavr harness
// reads it (rx_overruns).
ISR(USART_RX_vect) {
  if (!fdsurf::uno::g_rx.Push(UDR0)) {
    const uint8_t lost = GPIOR1;
    if (lost != 0xFFu) GPIOR1 = static_cast<uint8_t>(lost + 1u);
  }
}

ISR(TIMER1_COMPA_vect) {
  using namespace fdsurf::uno;
  // A failed output faults the device, which reports it in STATUS.
  (void)g_device.Tick(g_steppers, g_pen);
  const uint16_t since = g_ticks_since_heartbeat;
  if (since < kHeartbeatTicks || g_in_service) wdt_reset();
  if (since != 0xFFFFu) g_ticks_since_heartbeat = static_cast<uint16_t>(since + 1);
}

int main() {
  using namespace fdsurf::uno;
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
    ServiceLink();
    g_in_service = false;
    g_device.Fill(kFillBatch);
    if (NothingToDo()) {
      sleep_enable();
      sleep_cpu();
      sleep_disable();
    }
  }
}
