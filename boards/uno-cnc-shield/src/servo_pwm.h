// SPDX-License-Identifier: MIT
// The pen as a hobby servo on D11 = PB3 = OC2A (Grbl 1.1's spindle PWM pin,
// which Grbl's servo forks drive a pen lift from), made by Timer2.
//
// Timer2 is 8 bits wide. Fast PWM at clock / 1024 would give one pulse every
// 16.4 ms (61 Hz) in steps of 64 us: a 1000..2000 us servo would have 16
// positions. Instead Timer2 runs in fast PWM (mode 3, TOP = 255) at
// clock / 256: one count is 16 us, one timer period 4.096 ms, long enough
// for any pulse of 500..2500 us. The output OC2A is connected (non-
// inverting: set at BOTTOM, cleared at the compare match) for one timer
// period in five, so the servo sees one pulse every 20.48 ms (48.8 Hz), in
// steps of 16 us (a 1000..2000 us servo has 63 positions). Both edges come
// from the timer's hardware: no interrupt latency moves them.
//
// The gating runs in TIMER2_COMPB_vect, at count kGateCount of every
// period (OC2B stays disconnected: PD3 is Y's STEP), after any pulse's
// compare match, when the pin is low either way: it connects OC2A for the
// period that follows (and loads the width the pen wants), or disconnects
// it (the pin is then PORTB3 = 0). It has until the next BOTTOM, 512 us
// after it, to do so; the step interrupt, the longest section with
// interrupts masked, takes 0.16 ms at most (2 533 cycles measured).
//
// A pen change takes effect at the next gating: at most one pulse period
// and the 512 us from the gating to BOTTOM, 20.99 ms (24.08 ms when the
// gating ran at the pulse's compare). A change just after the gating is not
// written to OCR2A for the pulse about to start: that pulse could then
// begin under half a tick after the step the same interrupt pulsed, and the
// recording's events would be closer than the device promises (one move or
// pen change a tick).
#pragma once

#include <avr/io.h>
#include <stdint.h>

#include "board_config.h"
#include "fdsurf/board/servo_widths.h"
#include "fdsurf/hal/outputs.h"

namespace fdsurf {
namespace uno {

class ServoPen final : public hal::PenOutput {
 public:
  /// Timer2 periods between two pulses: 5 x 4.096 ms = 20.48 ms.
  static constexpr uint8_t kPeriodsPerPulse = 5;
  /// One Timer2 count (clock / 256), microseconds.
  static constexpr uint16_t kCountUs = 16;
  /// OCR2B: where the gating runs, past the longest pulse (2500 us, count
  /// 156) and 32 counts (512 us) before BOTTOM.
  static constexpr uint8_t kGateCount = 224;

  ServoPen() = default;
  ~ServoPen() = default;

  /// OCR2A for a pulse of `us` microseconds (500..2500), to the nearest
  /// count: the pulse is OCR2A + 1 counts long.
  static constexpr uint8_t CompareFor(uint16_t us) {
    return static_cast<uint8_t>((us + kCountUs / 2) / kCountUs - 1);
  }

  /// Starts Timer2 with OC2A disconnected (the pin low); the first pulse,
  /// "pen up", starts within 20.5 ms. Called once, from SetSafeOutputs().
  static void Start() {
    PORTB &= static_cast<uint8_t>(~_BV(PB3));
    DDRB |= _BV(PB3);
    OCR2A = CompareFor(kServoUpUs);
    OCR2B = kGateCount;
    TCNT2 = 0;
    TCCR2A = _BV(WGM21) | _BV(WGM20);
    TCCR2B = _BV(CS22) | _BV(CS21);
    TIFR2 = _BV(TOV2) | _BV(OCF2A) | _BV(OCF2B);
    TIMSK2 = _BV(OCIE2B);
  }

  /// Call from TIMER2_COMPB_vect.
  void OnCompare() {
    // One gating a period: a compare without an overflow since the last one
    // is the same period's again.
    if ((TIFR2 & _BV(TOV2)) == 0) return;
    TIFR2 = _BV(TOV2);
    if (++phase_ == kPeriodsPerPulse) phase_ = 0;
    if (phase_ != kPeriodsPerPulse - 1) {
      TCCR2A = _BV(WGM21) | _BV(WGM20);  // OC2A off: the pin stays low
      return;
    }
    // Past every width's compare: no compare ahead in this period, for
    // simavr, which applies an OCR2A write at once.
    OCR2A = next_compare_;
    TCCR2A = _BV(COM2A1) | _BV(WGM21) | _BV(WGM20);
  }

 private:
  // Runs in the step interrupt, which the compare interrupt cannot cut
  // into (and the other way round): one byte, taken at the next pulse.
  hal::IoStatus DoSetPen(bool down) override {
    widths_.set_down(down);
    next_compare_ = CompareFor(widths_.WidthUs());
    return hal::IoStatus::kOk;
  }
  // Also from the step interrupt (Device::Tick), before any pen change; the
  // pen moves to the new width of the state it is in. Both 0: the image's.
  hal::IoStatus DoConfigureServo(uint16_t up_us, uint16_t down_us) override {
    widths_.Configure(up_us, down_us);
    return DoSetPen(widths_.down());
  }
  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }

  volatile uint8_t next_compare_ = CompareFor(kServoUpUs);
  uint8_t phase_ = 0;
  board::ServoWidths<kServoUpUs, kServoDownUs> widths_;
};

}  // namespace uno
}  // namespace fdsurf
