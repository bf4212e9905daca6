// SPDX-License-Identifier: MIT
// What fdsurf_simavr_board records from an emulated AVR board (avr_boards.h:
// the Mega 2560 + RAMPS, the Uno + CNC Shield): its step/dir/enable and
// servo pins as a waveform (format 1, docs/boards.md), and the measures of
// the firmware's timing and memory (../README.md):
//
//   - the step interrupt (the step timer's compare A) from its vector to its RETI, in
//     cycles: min, mean, max, over all ticks and over the ticks that step;
//   - late ticks: an interrupt that starts a period or more after its
//     compare match, and compare matches lost while the flag was still set;
//   - the receive interrupt's cycles;
//   - from the first step to the last: the main loop's cycles (those neither
//     asleep nor in an interrupt) per emitted point (a tick that steps), and
//     the bytes received per second;
//   - the stack's high-water mark from the painted RAM (the firmware paints
//     from __heap_start to its stack with 0xA5 at start), flash, static RAM.
#pragma once

#include <sim_avr.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "avr_boards.h"

namespace fdsurf::board {

/// Sizes from the ELF image, bytes.
struct ImageFacts {
  std::uint32_t flash;  // .text + .data, as programmed
  std::uint32_t data;
  std::uint32_t bss;
};

/// Running sums of a measured interval.
struct CycleStats {
  std::uint64_t count = 0;
  std::uint64_t sum = 0;
  std::uint64_t min = UINT64_MAX;
  std::uint64_t max = 0;
  std::uint64_t max_at = 0;  // the cycle at which the longest one started
  void Add(std::uint64_t cycles, std::uint64_t started_at = 0);
  [[nodiscard]] double Mean() const {
    return count == 0 ? 0.0 : static_cast<double>(sum) / static_cast<double>(count);
  }
};

/// The counters that the drawing window takes differences of.
struct Accumulated {
  std::uint64_t cycle = 0;
  std::uint64_t sleep = 0;
  std::uint64_t isr = 0;  // both interrupts
  std::uint64_t points = 0;
  std::uint64_t bytes_in = 0;
};

class Recorder {
 public:
  explicit Recorder(const AvrBoard& board) : board_(board) {}
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;
  ~Recorder();

  /// Creates the waveform file and writes its header. False with *error
  /// naming the file.
  bool Open(const std::string& path, std::string* error);
  /// Listens to the pins, the two interrupts, the UART and the core's
  /// sleep. One Recorder per process (simavr's sleep hook has no argument).
  void Attach(avr_t* avr);
  /// Flushes and closes the waveform.
  void Finish(avr_t* avr);
  /// Writes the measures as TSV (measure, value, unit).
  bool WriteMeasures(const std::string& path, avr_t* avr, const ImageFacts& facts,
                     std::uint64_t bridge_in, std::uint64_t bridge_out, std::string* error) const;

  /// One recorded pin.
  struct Signal {
    AvrSignal line;
    Recorder* recorder;
    bool started;  // set up as an output: its changes are recorded
    int level;
    // The servo pin of a board with a servo timer: while the timer drives
    // it, its level is the timer's output, not the pin's IRQ.
    bool timer_driven;
  };
  static constexpr int kSignals = AvrBoard::kSignals;

 private:
  static void OnPin(avr_irq_t* irq, std::uint32_t value, void* param);
  static void OnServoTimer(avr_irq_t* irq, std::uint32_t value, void* param);
  void Record(Signal* signal, int level);
  [[nodiscard]] bool ServoTimerConnected() const;
  static void OnDirection(avr_irq_t* irq, std::uint32_t value, void* param);
  static void OnTickPending(avr_irq_t* irq, std::uint32_t value, void* param);
  static void OnTickRunning(avr_irq_t* irq, std::uint32_t value, void* param);
  static void OnRxRunning(avr_irq_t* irq, std::uint32_t value, void* param);
  static void OnUartIn(avr_irq_t* irq, std::uint32_t value, void* param);
  static void OnSleep(avr_t* avr, avr_cycle_count_t cycles);
  static void OnBoot(avr_t* avr, avr_io_addr_t addr, std::uint8_t value, void* param);
  void Write(const Signal& signal);
  [[nodiscard]] std::uint64_t TickPeriod() const;
  [[nodiscard]] std::uint32_t StackHighWater(avr_t* avr, const ImageFacts& facts) const;

  const AvrBoard& board_;
  avr_t* avr_ = nullptr;
  std::FILE* file_ = nullptr;
  std::string path_;
  Signal signals_[kSignals];
  // The step interrupt.
  std::uint64_t pending_at_ = 0;
  std::uint64_t last_pending_ = 0;
  std::uint64_t running_at_ = 0;
  bool in_tick_ = false;
  bool stepped_ = false;
  CycleStats tick_;
  CycleStats stepping_tick_;
  CycleStats latency_;
  std::uint64_t late_ticks_ = 0;
  std::uint64_t lost_ticks_ = 0;
  // The receive interrupt.
  std::uint64_t rx_at_ = 0;
  CycleStats rx_;
  Accumulated now_;
  Accumulated first_step_;
  Accumulated last_step_;
  bool drawing_ = false;
  // Starts of the firmware (it copies MCUSR to GPIOR0 first thing).
  std::uint64_t boots_ = 0;
  std::uint64_t watchdog_resets_ = 0;
};

}  // namespace fdsurf::board
