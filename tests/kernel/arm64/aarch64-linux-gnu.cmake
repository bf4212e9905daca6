# SPDX-License-Identifier: MIT
# Debian's aarch64-linux-gnu cross toolchain (g++-aarch64-linux-gnu) with the
# multiarch arm64 libraries (dpkg --add-architecture arm64; libgpiod-dev:arm64)
# for the GPIO test under QEMU (tests/kernel/arm64/cross/, docs/testing.md).
# Unlike cmake/toolchains/ (microcontrollers), it sets no FDSURF_TARGET.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# Headers and libraries of the target come from the multiarch directories of
# this system (/usr/include, /usr/lib/aarch64-linux-gnu); programs run here.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
