// SPDX-License-Identifier: MIT
// CRC-32 as in IEEE 802.3 (the CRC of zlib, PNG and Ethernet): reflected
// polynomial 0xEDB88320, initial value and final XOR 0xFFFFFFFF. The check
// value of the ASCII string "123456789" is 0xCBF43926 (the "CRC-32" entry of
// Greg Cook's catalogue of parametrised CRC algorithms, reveng.sourceforge.io).
//
// A 16-entry (nibble) table keeps it small for 8-bit targets: 64 bytes of
// table, two lookups per byte.
#pragma once

#include <stddef.h>
#include <stdint.h>
#include "fdsurf/config/nodiscard.h"

namespace fdsurf {
namespace protocol {

/// Incremental CRC-32: Update() any number of times, then Value().
class Crc32 {
 public:
  constexpr Crc32() = default;

  /// Feeds one byte.
  void Update(uint8_t byte);
  /// Feeds `size` bytes; `data` may be null when `size` is 0.
  void Update(const uint8_t* data, size_t size);
  /// The CRC of every byte fed so far (does not change the state).
  FDSURF_NODISCARD constexpr uint32_t Value() const { return state_ ^ 0xFFFFFFFFu; }

 private:
  uint32_t state_ = 0xFFFFFFFFu;
};

/// The CRC-32 of a whole buffer.
uint32_t ComputeCrc32(const uint8_t* data, size_t size);

}  // namespace protocol
}  // namespace fdsurf
