// SPDX-License-Identifier: MIT
// What the ARM and RISC-V ports share: output and exit through semihosting
// (the same operations on both; only the trap instruction differs), and a
// painted stack for the high-water mark. Each port defines Semihost() and
// paints the stack in its start code; targets/port/semihosting.cc does the rest.
#pragma once

#include <stddef.h>
#include <stdint.h>

extern "C" {
// Linker script symbols (targets/link/).
extern uint32_t __stack_limit[];
extern uint32_t __stack_top[];

// The instruction-counting plugin (targets/sim/qemu_insn_count.c) records its
// counter each time this function's first instruction executes.
__attribute__((noinline, used)) void fdsurf_image_mark();
}

namespace fdsurf {
namespace image {
namespace semihosting {

/// Start code fills the unused stack with this, for PortStackUsed().
constexpr uint32_t kStackPaint = 0xA5A5A5A5u;

/// SYS_WRITE0, SYS_EXIT and the exit reasons of the semihosting specification.
constexpr uint32_t kSysWrite0 = 0x04;
constexpr uint32_t kSysExit = 0x18;
constexpr uint32_t kApplicationExit = 0x20026;
constexpr uint32_t kRunTimeErrorUnknown = 0x20023;

/// The semihosting trap with its operation and argument; defined per port.
uint32_t Semihost(uint32_t operation, const void* argument);

}  // namespace semihosting
}  // namespace image
}  // namespace fdsurf
