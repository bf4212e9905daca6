// SPDX-License-Identifier: MIT
// What the firmware measures about itself, in RAM at the symbol
// `fdsurf_board_stats`, for the QEMU harness (host/run_qemu.py reads it from
// a RAM dump at the end of a run) or a debugger on a real board.
//
// Times are TIMER0 counts at 16 MHz: CPU cycles on the board (the M0 runs
// from the same 16 MHz clock); under QEMU -icount, emulated time / 62.5 ns.
// The layout is part of the harness's interface: all fields are 32-bit
// little-endian words in this order (host/run_qemu.py, STATS_FIELDS).
#pragma once

#include <stdint.h>

namespace fdsurf {
namespace board {

constexpr uint32_t kBoardStatsMagic = 0x5354424Du;  // "MBTS"
constexpr uint32_t kStackPaint = 0xC0DEFACEu;

struct BoardStats {
  uint32_t magic;
  uint32_t tick_hz;
  /// Timer interrupts served; those that began more than half a period
  /// after their compare event (late), and those a whole period or more
  /// after it (a tick slot lost; the timer is re-armed).
  uint32_t ticks;
  uint32_t late_ticks;
  uint32_t missed_ticks;
  /// Late ticks while the machine was moving (speed > 0), the ones that
  /// shift a step edge; the others fall in a pen change's rest.
  uint32_t late_moving_ticks;
  /// Worst delay from the compare event to the first instruction of the
  /// handler's body (exception entry and any masked section included).
  uint32_t max_lateness;
  /// Cycles inside the handler body (Device::Tick and the bookkeeping):
  /// the worst, the sum (low, high word), and the worst of a tick that
  /// stepped.
  uint32_t max_tick_cycles;
  uint32_t tick_cycles_low;
  uint32_t tick_cycles_high;
  uint32_t stepping_ticks;
  uint32_t max_stepping_tick_cycles;
  /// Main-loop iterations that did work (bytes arrived or lookahead entries
  /// were produced): their cycles minus the timer interrupts inside them
  /// (low, high word), and the entries they produced (unit moves and pen
  /// events): cycles per emitted point = work / points.
  uint32_t work_cycles_low;
  uint32_t work_cycles_high;
  uint32_t points;
  /// The worst single such iteration (a patch's validation, typically).
  uint32_t max_work_cycles;
  /// UART: bytes received, bytes the ring had to drop, line errors seen.
  uint32_t rx_bytes;
  uint32_t rx_overruns;
  uint32_t uart_errors;
  /// Non-zero once a fault handler ran (its exception number).
  uint32_t fault;
  /// The pen servo (servo builds; 0 otherwise): periods started, and the
  /// worst delay from a period's compare to its handler, µs (TIMER1 counts).
  uint32_t servo_periods;
  uint32_t servo_max_lateness_us;
};

}  // namespace board
}  // namespace fdsurf
