// SPDX-License-Identifier: MIT
#include "fdsurf/protocol/crc32.h"

#if defined(__AVR__)
// avr-gcc copies a const table into RAM at start-up unless it is placed in
// flash and read with lpm: 64 bytes of an Arduino Uno's 2,048, where the
// validation's stack needs every byte (boards/uno-cnc-shield/README.md).
#include <avr/pgmspace.h>
#define FDSURF_CRC_TABLE_IN_FLASH PROGMEM
#else
#define FDSURF_CRC_TABLE_IN_FLASH
#endif

namespace fdsurf {
namespace protocol {
namespace {

// kTable[i] is the reflected CRC register after shifting the 4-bit value i
// through the polynomial 0xEDB88320 (bit by bit); the tests recompute it.
const uint32_t kTable[16] FDSURF_CRC_TABLE_IN_FLASH = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
    0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
    0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
};

uint32_t TableAt(uint32_t index) {
#if defined(__AVR__)
  return pgm_read_dword(&kTable[index]);
#else
  return kTable[index];
#endif
}

}  // namespace

void Crc32::Update(uint8_t byte) {
  uint32_t crc = state_ ^ byte;
  crc = (crc >> 4) ^ TableAt(crc & 0x0Fu);
  crc = (crc >> 4) ^ TableAt(crc & 0x0Fu);
  state_ = crc;
}

void Crc32::Update(const uint8_t* data, size_t size) {
  for (size_t i = 0; i < size; ++i) {
    Update(data[i]);
  }
}

uint32_t ComputeCrc32(const uint8_t* data, size_t size) {
  Crc32 crc;
  crc.Update(data, size);
  return crc.Value();
}

}  // namespace protocol
}  // namespace fdsurf
