# SPDX-License-Identifier: MIT
# ATmega328P (Arduino Uno class): 32 KB flash, 2 KB RAM. Too small for the set-up, so its image steps host-prepared tables (targets/README.md).
# avr-g++ 5.4 (gcc-avr, avr-libc): C++14 at most, 16-bit int.
# cmake -S . -B build/targets/atmega328p -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/atmega328p.cmake
set(FDSURF_TARGET atmega328p)
set(FDSURF_TARGET_MCU atmega328p)
set(FDSURF_TARGET_SETUP OFF)
include(${CMAKE_CURRENT_LIST_DIR}/avr.cmake)
