// SPDX-License-Identifier: MIT
// The AVR boards fdsurf_simavr_board runs (--board): for each one, the
// simavr part, the registers and vectors its measures read, the pins its
// waveform records and the pins of its simulated carriage. The pins are the
// firmware's (boards/<board>/src/); the register addresses and vector
// numbers are the data-space ones of avr-libc's io headers (iom2560.h,
// iom328p.h).
#pragma once

#include <cstdint>
#include <string>

namespace fdsurf::board {

/// A port bit, with the data-space addresses of its DDR and PORT registers.
struct AvrPin {
  char port;  // 'B', 'D', ...
  std::uint8_t bit;
  std::uint16_t ddr;
  std::uint16_t out;
};

/// One line of the waveform (format 1, docs/boards.md).
struct AvrSignal {
  const char* name;  // X_STEP ... SERVO
  AvrPin pin;
  bool step;  // a STEP line (a tick that raises it emitted a point)
};

/// One axis of the simulated carriage: its STEP and DIR outputs and its min
/// (and max, if the board has one) switch inputs.
struct AvrAxis {
  char name;
  AvrPin step;
  AvrPin dir;
  AvrPin min;
  bool has_max;
  AvrPin max;  // held released; unused without has_max
};

/// The timer output compare that drives the servo pin, where the waveform
/// must follow the timer rather than the pin's IRQ: simavr raises every
/// output pin of a port from its PORT register on any write to it, also a
/// pin an output compare drives, which the hardware leaves to the timer (the
/// Uno's ENABLE on PB0 shares PORTB with its servo on OC2A = PB3, so an
/// enable cut the pulse short in the recording alone). timer 0: none.
struct AvrServoTimer {
  char timer;                 // simavr's timer name: '1', '2', ...
  std::uint8_t compare;       // 0: A, 1: B
  std::uint16_t tccra;        // data-space address of TCCRnA
  std::uint8_t connect_mask;  // its COMnx bits: the pin follows the timer while any is set
};

struct AvrBoard {
  static constexpr int kSignals = 10;

  const char* name;  // --board, and the waveform's "# board"
  const char* mcu;   // simavr's part name
  // The step timer's compare A and the USART's receive vectors.
  std::uint8_t tick_vector;
  std::uint8_t rx_vector;
  // Data-space addresses: the step timer's TCCRnB and OCRnA (16 bits, low
  // byte first), the USART's UCSRnA and UBRRn (low byte first), GPIOR0 (the
  // firmware's first instructions copy MCUSR there).
  std::uint16_t tick_tccrb;
  std::uint16_t tick_ocra;
  std::uint16_t ucsra;
  std::uint16_t ubrr;
  std::uint16_t gpior0;
  // Where the firmware counts the received bytes its ring had no room for
  // (saturating at 255; the Uno: GPIOR1), or 0: it does not say.
  std::uint16_t rx_overruns;
  // The internal RAM, first and last byte (data space).
  std::uint16_t ram_start;
  std::uint16_t ram_end;
  // The image's default servo widths (the waveform header's "# pen servo").
  std::uint16_t servo_up_us;
  std::uint16_t servo_down_us;
  AvrSignal signals[kSignals];
  AvrAxis axes[3];
  /// The SERVO signal's timer (signals[] names its pin).
  AvrServoTimer servo_timer;

  [[nodiscard]] std::uint32_t RamBytes() const {
    return static_cast<std::uint32_t>(ram_end - ram_start + 1u);
  }
};

/// The board named `name` (mega2560-ramps, uno-cnc-shield), or nullptr.
const AvrBoard* FindAvrBoard(const std::string& name);
/// The names FindAvrBoard knows, "a, b".
std::string AvrBoardNames();

}  // namespace fdsurf::board
