// SPDX-License-Identifier: MIT
// libFuzzer target: the SVG reader (host::ReadSvg) on arbitrary text; what it
// accepts must step within 0.51 quanta of the reference (patch_check.h).
#include <cstddef>
#include <cstdint>

#include "fdsurf/host/svg_io.h"
#include "patch_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fdsurf::fuzz::CheckReader(
      data, size, [](const std::string& text) { return fdsurf::host::ReadSvg(text, "fuzz.svg"); });
}
