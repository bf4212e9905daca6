// SPDX-License-Identifier: MIT
// Entries of the motion loop's lookahead buffer: one byte each, a unit move
// (every axis −1, 0 or +1 step) or an event (pen up, pen down, end of a
// command).
#pragma once

#include <stdint.h>

namespace fdsurf {
namespace motion {

/// Kinds of buffer entries (the top two bits of an entry).
enum class EntryKind : uint8_t {
  kMove = 0,
  kPenUp = 1,
  kPenDown = 2,
  /// A command finished expanding here; counted when the loop reaches it.
  kCommandDone = 3,
};

/// One buffer entry in a byte: bits 6..7 the kind; for moves, bit 2a says
/// axis a steps and bit 2a+1 that it steps towards negative.
inline uint8_t MakeEntry(EntryKind kind) {
  return static_cast<uint8_t>(static_cast<uint8_t>(kind) << 6);
}
inline EntryKind KindOf(uint8_t entry) { return static_cast<EntryKind>(entry >> 6); }

/// A unit move from per-axis deltas in {-1, 0, 1}; axes beyond `axes` are 0.
inline uint8_t MakeMove(const int32_t* delta, int axes) {
  uint8_t entry = 0;
  for (int a = 0; a < axes; ++a) {
    if (delta[a] != 0) entry = static_cast<uint8_t>(entry | (1u << (2 * a)));
    if (delta[a] < 0) entry = static_cast<uint8_t>(entry | (2u << (2 * a)));
  }
  return entry;
}

/// Length units of the profile: 2^-24 steps of path length.
constexpr int kLengthFracBits = 24;
/// The length of a unit move entry, 2^-24 steps: √k·2^24 rounded up for a
/// move that steps k axes, so that a diagonal move is never taken as
/// shorter than it is. (Chosen by comparisons rather than read from a
/// table: avr-gcc would keep a table in RAM.)
inline uint32_t LengthOfMove(uint8_t move) {
  // Constant shifts: on an AVR a shift by a variable count is a loop, and
  // this runs for every unit move.
  const uint8_t axes = static_cast<uint8_t>((move & 1) + ((move >> 2) & 1) + ((move >> 4) & 1));
  if (axes == 1) return 16777216u;   // 2^24
  if (axes == 2) return 23726567u;   // ⌈√2·2^24⌉
  return axes == 3 ? 29058991u : 0;  // ⌈√3·2^24⌉
}

/// *sum += addend, for the path coordinates and distances the loop keeps
/// in 64 bits and grows by a move's or a run's length at a time. On an AVR
/// one add-with-carry chain over the sum's bytes: avr-gcc would call
/// __adddi3 with both operands moved through 16 registers, four times for
/// every unit move.
inline void AddLength(uint64_t* sum, uint32_t addend) {
#if defined(__AVR__)
  uint8_t* bytes = reinterpret_cast<uint8_t*>(sum);
  asm volatile(
      "ld __tmp_reg__, %a[bytes]\n\t"
      "add __tmp_reg__, %A[addend]\n\t"
      "st %a[bytes]+, __tmp_reg__\n\t"
      "ld __tmp_reg__, %a[bytes]\n\t"
      "adc __tmp_reg__, %B[addend]\n\t"
      "st %a[bytes]+, __tmp_reg__\n\t"
      "ld __tmp_reg__, %a[bytes]\n\t"
      "adc __tmp_reg__, %C[addend]\n\t"
      "st %a[bytes]+, __tmp_reg__\n\t"
      "ld __tmp_reg__, %a[bytes]\n\t"
      "adc __tmp_reg__, %D[addend]\n\t"
      "st %a[bytes]+, __tmp_reg__\n\t"
      ".rept 4\n\t"
      "ld __tmp_reg__, %a[bytes]\n\t"
      "adc __tmp_reg__, __zero_reg__\n\t"
      "st %a[bytes]+, __tmp_reg__\n\t"
      ".endr"
      : [bytes] "+e"(bytes)
      : [addend] "r"(addend)
      : "memory");
#else
  *sum += addend;
#endif
}

}  // namespace motion
}  // namespace fdsurf
