// SPDX-License-Identifier: MIT
// libFuzzer target: the G-code reader (host::ReadGcode, docs/formats.md
// "G-code") on arbitrary text; what it accepts must step within 0.51 quanta
// of the reference (patch_check.h), and it may only fail with InputError.
#include <cstddef>
#include <cstdint>

#include "fdsurf/host/gcode_io.h"
#include "patch_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fdsurf::fuzz::CheckReader(data, size, [](const std::string& text) {
    return fdsurf::host::ReadGcode(text, "fuzz.gcode");
  });
}
