#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# What the freestanding core takes from the C library and the compiler's
# runtime on each microcontroller target (docs/embedding.md): builds the core
# alone (FDSURF_CORE_ONLY) with cmake/toolchains/TARGET.cmake and lists the
# symbols libfdsurf_core.a and libfdsurf_hal.a use but do not define.
# Usage: core_libc_symbols.sh [WORK_DIR] [TARGET...]
#   default targets: cortex-m0 cortex-m4f rv32imac atmega2560
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-$src/build/core-symbols}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(cortex-m0 cortex-m4f rv32imac atmega2560)
for target in "${targets[@]}"; do
  dir=$work/$target
  mkdir -p "$work"
  cmake -S "$src" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFDSURF_CORE_ONLY=ON \
    -DCMAKE_TOOLCHAIN_FILE="$src/cmake/toolchains/$target.cmake" >"$dir.configure.log" 2>&1 || {
    cat "$dir.configure.log"
    exit 1
  }
  cmake --build "$dir" --parallel 2 >"$dir.build.log" 2>&1 || {
    cat "$dir.build.log"
    exit 1
  }
  nm=$(sed -n 's/^CMAKE_NM:[^=]*=//p' "$dir/CMakeCache.txt")
  libs=("$dir/firmware/libfdsurf_core.a" "$dir/firmware/hal/libfdsurf_hal.a")
  [ -e "${libs[1]}" ] || libs[1]=$dir/hal/libfdsurf_hal.a
  defined=$("$nm" --defined-only "${libs[@]}" 2>/dev/null | awk 'NF == 3 {print $3}' | sort -u)
  undefined=$("$nm" --undefined-only "${libs[@]}" 2>/dev/null | awk 'NF == 2 {print $2}' | sort -u)
  needed=$(comm -23 <(echo "$undefined") <(echo "$defined") | tr '\n' ' ')
  echo "$target: $needed"
done
