// SPDX-License-Identifier: MIT
#include "avr_boards.h"

namespace fdsurf::board {
namespace {

// Ports (data-space DDR and PORT addresses; the same on both chips where
// both have the port).
constexpr AvrPin B(std::uint8_t bit) { return AvrPin{'B', bit, 0x24, 0x25}; }
constexpr AvrPin D(std::uint8_t bit) { return AvrPin{'D', bit, 0x2A, 0x2B}; }
constexpr AvrPin E(std::uint8_t bit) { return AvrPin{'E', bit, 0x2D, 0x2E}; }
constexpr AvrPin F(std::uint8_t bit) { return AvrPin{'F', bit, 0x30, 0x31}; }
constexpr AvrPin J(std::uint8_t bit) { return AvrPin{'J', bit, 0x104, 0x105}; }
constexpr AvrPin K(std::uint8_t bit) { return AvrPin{'K', bit, 0x107, 0x108}; }
constexpr AvrPin L(std::uint8_t bit) { return AvrPin{'L', bit, 0x10A, 0x10B}; }

// Arduino Mega 2560 + RAMPS 1.4 (boards/mega2560-ramps/src/ramps_outputs.h,
// ramps_inputs.h): the step tick on Timer3, the servo on OC1A.
constexpr AvrBoard kMega{
    "mega2560-ramps",
    "atmega2560",
    32,  // TIMER3_COMPA
    25,  // USART0_RX
    0x91,
    0x98,  // TCCR3B, OCR3A
    0xC0,
    0xC4,  // UCSR0A, UBRR0
    0x3E,  // GPIOR0
    0,     // no count of lost received bytes
    0x200,
    0x21FF,  // 8 KB
    1000,
    2000,
    {
        {"X_STEP", F(0), true},
        {"X_DIR", F(1), false},
        {"X_EN", D(7), false},
        {"Y_STEP", F(6), true},
        {"Y_DIR", F(7), false},
        {"Y_EN", F(2), false},
        {"Z_STEP", L(3), true},
        {"Z_DIR", L(1), false},
        {"Z_EN", K(0), false},
        {"SERVO", B(5), false},
    },
    {
        {'X', F(0), F(1), E(5), true, E(4)},
        {'Y', F(6), F(7), J(1), true, J(0)},
        {'Z', L(3), L(1), D(3), true, D(2)},
    },
    // No other output shares PORTB with the servo: its pin is recorded.
    {0, 0, 0, 0},
};

// Arduino Uno + CNC Shield v3 (boards/uno-cnc-shield/src/shield_outputs.h,
// shield_inputs.h, servo_pwm.h): the step tick on Timer1, the servo on
// OC2A. The shield has one enable line (D8) for its three drivers: it is
// recorded under each axis's name. The shield joins each axis's "+" and "-"
// headers on one pin, so there is no max switch.
constexpr AvrBoard kUno{
    "uno-cnc-shield",
    "atmega328p",
    11,  // TIMER1_COMPA
    18,  // USART_RX
    0x81,
    0x88,  // TCCR1B, OCR1A
    0xC0,
    0xC4,  // UCSR0A, UBRR0
    0x3E,  // GPIOR0
    0x4A,  // GPIOR1: received bytes lost to a full ring
    0x100,
    0x8FF,  // 2 KB
    1000,
    2000,
    {
        {"X_STEP", D(2), true},
        {"X_DIR", D(5), false},
        {"X_EN", B(0), false},
        {"Y_STEP", D(3), true},
        {"Y_DIR", D(6), false},
        {"Y_EN", B(0), false},
        {"Z_STEP", D(4), true},
        {"Z_DIR", D(7), false},
        {"Z_EN", B(0), false},
        {"SERVO", B(3), false},
    },
    {
        {'X', D(2), D(5), B(1), false, B(1)},
        {'Y', D(3), D(6), B(2), false, B(2)},
        {'Z', D(4), D(7), B(4), false, B(4)},
    },
    {'2', 0, 0xB0, 0xC0},  // OC2A; TCCR2A's COM2A1:0
};

const AvrBoard* const kBoards[] = {&kMega, &kUno};

}  // namespace

const AvrBoard* FindAvrBoard(const std::string& name) {
  for (const AvrBoard* board : kBoards) {
    if (name == board->name) return board;
  }
  return nullptr;
}

std::string AvrBoardNames() {
  std::string names;
  for (const AvrBoard* board : kBoards)
    names += (names.empty() ? "" : ", ") + std::string(board->name);
  return names;
}

}  // namespace fdsurf::board
