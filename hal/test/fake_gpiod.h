// SPDX-License-Identifier: MIT
// A fake libgpiod 1.6 for tests linked with -Wl,--wrap=<each gpiod function
// the backend calls>: the backend's calls land in __wrap_* functions that
// emulate chips with N lines, lines used by other consumers, missing chips
// and errno values, and log every call that changes a line.
#pragma once

#include <stdint.h>

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace fdsurf::hal::testing {

struct FakeGpioLine {
  unsigned offset = 0;
  std::string consumer;    // non-empty: used by another consumer
  bool used = false;       // what gpiod_line_is_used reports
  int request_errno = 0;   // non-zero: gpiod_line_request_output fails with it
  int set_errno = 0;       // non-zero: gpiod_line_set_value fails with it
  int set_fails_for = -1;  // with set_errno: only setting this value fails (-1: any)
  bool requested = false;
  /// Which request holds the line (lines requested together share one,
  /// as they share one file descriptor in libgpiod); 0 when not requested.
  int request = 0;
  bool input = false;  // requested as an input (gpiod_line_request_input)
  int value = -1;      // an output's last value, or the level an input reads
  int get_errno = 0;   // non-zero: gpiod_line_get_value fails with it
};

struct FakeGpioChip {
  std::vector<FakeGpioLine> lines;
  bool open = false;
};

struct FakeGpio {
  /// Chips by the descriptor gpiod_chip_open_lookup is given.
  std::map<std::string, FakeGpioChip> chips;
  /// errno of a lookup of a descriptor not in `chips`.
  int missing_errno = 2;  // ENOENT
  /// "lookup gpiochip0", "request 17 fdsurf 0", "input 5 fdsurf", "set 17=1",
  /// "release 17", "close"; lines requested or set in one bulk call:
  /// "request 17,22 fdsurf 0,0", "set 17=1,22=0" (reads of inputs are not logged).
  std::vector<std::string> log;
  /// When each "set" entry happened (CLOCK_MONOTONIC µs), parallel to the sets in `log`.
  std::vector<uint64_t> set_times_us;
  /// The number the next request gets.
  int next_request = 1;
  /// Called after every output value a set stores (line offset, the level
  /// written), e.g. to move a simulated carriage; none by default.
  std::function<void(unsigned, int)> on_set;

  /// A chip with `count` unused lines, opened by `descriptor`.
  FakeGpioChip& AddChip(const std::string& descriptor, unsigned count);
};

/// The fake the __wrap_ functions use; tests install one per test.
extern FakeGpio* g_fake_gpio;

}  // namespace fdsurf::hal::testing
