#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs everything fdsurf needs on Debian 12 (run as root), then configures
# and builds the project in build/. Safe to run again: apt-get skips what is
# already installed and CMake rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config git
  libgtest-dev libgmock-dev libbenchmark-dev
  # Optional library baselines of the host benchmark (bench/CMakeLists.txt,
  # docs/performance.md): OpenCASCADE (LGPL-2.1) and SISL (AGPL-3). Linked
  # into bench/fdsurf_bench only, never into anything fdsurf installs; the
  # build works without them.
  libocct-modeling-data-dev libocct-foundation-dev libsisl-dev
  libcli11-dev nlohmann-json3-dev
  # Machine profiles (docs/machines.md).
  libtomlplusplus-dev
  # The SVG reader.
  libpugixml-dev
  clang-format clang-tidy
  # The libFuzzer targets (scripts/fuzz.sh): clang and its runtimes
  # (libclang_rt.fuzzer and the sanitizers are in libclang-rt-14-dev).
  clang libclang-rt-14-dev
  libcairo2-dev
  libusb-1.0-0-dev libgpiod-dev gpiod libserialport-dev
  python3 hp2xx librsvg2-bin
  # The SVG reader's third-party check (tests/thirdparty/check_svg.py): inkscape --query-all.
  inkscape
  # Microcontroller images under emulation (targets/README.md): the cross
  # compilers, QEMU (Cortex-M, RV32) and simavr with its library (AVR).
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  gcc-riscv64-unknown-elf
  gcc-avr avr-libc binutils-avr
  qemu-system-arm qemu-system-misc
  simavr libsimavr-dev libelf-dev
  # The USB stack of a real Debian kernel under QEMU (tests/kernel/README.md):
  # the guest's shell and the emulator; umockdev for the libusb error paths.
  qemu-system-x86 busybox-static umockdev libumockdev-dev
  # GPIO on arm64 under QEMU (tests/kernel/arm64/): the cross compiler and
  # libgpiod for arm64 (multiarch, below); qemu-system-aarch64 is in
  # qemu-system-arm. The guest's kernel and busybox are extracted from their
  # .deb files into the build tree (tests/kernel/arm64/fetch_guest.sh).
  g++-aarch64-linux-gnu libgpiod-dev:arm64
)
# The arm64 packages above need dpkg to know the architecture (and apt its
# package lists, which the update below fetches when something is missing).
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  dpkg --add-architecture arm64
fi
# The G-code read-back check uses the npm packages gcode-toolpath/gcode-parser.
# Debian's nodejs + npm provide node; a machine that already has a node with
# npm bundled (e.g. from NodeSource) keeps it.
if ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -d tests/thirdparty/node_modules/gcode-toolpath ]; then
  echo "setup: installing the npm packages of tests/thirdparty" >&2
  npm ci --prefix tests/thirdparty --no-audit --no-fund --loglevel=error >/dev/null
fi

build_dir=${FDSURF_BUILD_DIR:-build}
build_type=${FDSURF_BUILD_TYPE:-Release}
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" ${FDSURF_CMAKE_ARGS:-} >/dev/null
cmake --build "$build_dir" --parallel "$(nproc)"
# The guest of the GPIO test under QEMU arm64 (CTest label kernel), where
# its fixture (tests/kernel/arm64/CMakeLists.txt) looks for it; sanitizer
# builds do not run it.
if ! grep -q '^FDSURF_SANITIZE:BOOL=ON' "$build_dir/CMakeCache.txt"; then
  bash tests/kernel/arm64/fetch_guest.sh "$build_dir/tests/kernel/arm64/guest"
fi
