#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Cross-compiles tests/package/cortex-m4-consumer with its own (vendor-style)
# toolchain file, embedding the core by add_subdirectory of <fdsurf>/firmware
# and of the whole checkout, and checks that a Cortex-M4F ELF came out. Also
# configures fdsurf itself with that toolchain: it must build and install the
# core (not stop for a toolchain that is not one of cmake/toolchains/).
# Usage: cortex_m4_consumer.sh SOURCE_DIR WORK_DIR
set -euo pipefail
src=$(cd "$1" && pwd)
work=$2
here=$src/tests/package/cortex-m4-consumer
toolchain=$here/vendor-toolchain.cmake
rm -rf "$work"
mkdir -p "$work"

run() { # LOG COMMAND...
  local log=$1
  shift
  "$@" >"$log" 2>&1 || {
    cat "$log"
    exit 1
  }
}

for add in firmware root; do
  dir=$work/$add
  run "$dir.configure.log" cmake -S "$here" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=MinSizeRel \
    -DCMAKE_TOOLCHAIN_FILE="$toolchain" -DFDSURF_SOURCE_DIR="$src" -DFDSURF_ADD="$add"
  run "$dir.build.log" cmake --build "$dir" --parallel 2
  elf=$dir/m4_consumer.elf
  readelf -h "$elf" | grep -q 'Machine:.*ARM' || { echo "$elf: not an ARM ELF" >&2; exit 1; }
  readelf -A "$elf" | grep -q 'Tag_ABI_VFP_args: VFP registers' ||
    { echo "$elf: not hard-float" >&2; exit 1; }
  # Captured first: with pipefail, `nm | grep -q` fails when grep stops
  # reading early and nm, still writing, dies of SIGPIPE.
  symbols=$(arm-none-eabi-nm -C "$elf")
  grep -q 'PrepareCurve<2>' <<<"$symbols" ||
    { echo "$elf: the core's PrepareCurve is not linked" >&2; exit 1; }
  echo "add_subdirectory($add): $(arm-none-eabi-size "$elf" | tail -1 | awk '{print "text " $1 ", data " $2 ", bss " $3}')"
done

# fdsurf as the top-level project with the same toolchain, installed.
run "$work/direct.configure.log" cmake -S "$src" -B "$work/direct" -G Ninja \
  -DCMAKE_BUILD_TYPE=MinSizeRel -DCMAKE_TOOLCHAIN_FILE="$toolchain"
run "$work/direct.build.log" cmake --build "$work/direct" --parallel 2
run "$work/direct.install.log" cmake --install "$work/direct" --prefix "$work/prefix"
for f in lib/libfdsurf_core.a lib/libfdsurf_hal.a lib/cmake/fdsurf/fdsurfConfig.cmake \
  include/fdsurf/forward_difference.h; do
  [ -e "$work/prefix/$f" ] || { echo "cross install lacks $f" >&2; exit 1; }
done
if [ -e "$work/prefix/bin/fdsurf" ]; then
  echo "cross install has the host tool" >&2
  exit 1
fi
echo "cross build with a vendor toolchain: core built and installed"
