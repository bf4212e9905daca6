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
#include "fdsurf/board/avr_runtime.h"
#include "fdsurf/board/byte_ring.h"
#include "fdsurf/device/device.h"
#include "servo_pwm.h"
#include "shield_inputs.h"
#include "shield_outputs.h"

#if FDSURF_DEVICE_PLANNER || FDSURF_DEVICE_WIDE_TABLES
#error "the Uno image links fdsurf_core_prepared (no planner, 64-bit tables): only that fits"
#endif

namespace fdsurf {
namespace uno {
namespace {

/// The step interrupt kicks the watchdog only while the main loop has gone
/// round within this many ticks (or is inside Service()), so a hung main
/// loop and a hung interrupt both reset the board.
constexpr uint16_t kHeartbeatTicks = static_cast<uint16_t>(kTickHz / 4);

/// The step interrupt's lock as a type of this file's own: a Device of an
/// internal type is itself internal, so GCC inlines its Tick() and Fill(),
/// each called once, into the interrupt and main() (with the shared type
/// they stayed out of line: 486 bytes more on the Uno, 1 KB on the Mega,
/// and a call in the step interrupt).
struct TickInterruptLock : board::TickInterruptLock {
  TickInterruptLock() {}  // NOLINT(modernize-use-equals-default): const objects
};

board::ByteRing<kRxRing> g_rx;
device::Device<kAxes, kQueueCapacity, kLookahead, TickInterruptLock,
               protocol::kMaxPreparedFrameBytes, kReplyBytes>
    g_device(kTickHz, kSliceTicks);
ShieldSteppers g_steppers;
ShieldEndstops g_endstops;
board::Heartbeat<kHeartbeatTicks> g_heartbeat;
/// MCUSR at reset (why the board started), saved by SaveResetCause().
volatile uint8_t g_reset_cause = 0;

void StartStepTimer() {
  TCCR1A = 0;
  TCNT1 = 0;
  OCR1A = static_cast<uint16_t>(kTimerClockHz / kTickHz - 1);
  TCCR1B = _BV(WGM12) | _BV(CS11);  // CTC on OCR1A, clock / 8
  TIMSK1 = _BV(OCIE1A);
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
    board::SendUart0(out, n);
  }
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

ISR(TIMER2_COMPB_vect) { fdsurf::uno::g_pen.OnCompare(); }

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
  // What the previous tick stepped, a whole tick after its pulse.
  g_steppers.EmitStep();
  // A failed output faults the device, which reports it in STATUS.
  (void)g_device.Tick(g_steppers, g_pen);
  g_heartbeat.OnTick();
}

int main() {
  using namespace fdsurf::uno;
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
    ServiceLink();
    g_heartbeat.set_in_service(false);
    g_device.Fill(kFillBatch);
    if (NothingToDo()) {
      sleep_enable();
      sleep_cpu();
      sleep_disable();
    }
  }
}
