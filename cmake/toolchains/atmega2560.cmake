# SPDX-License-Identifier: MIT
# ATmega2560 (Arduino Mega class): 256 KB flash, 8 KB RAM. Runs the full image, set-up included.
# avr-g++ 5.4 (gcc-avr, avr-libc): C++14 at most, 16-bit int.
# cmake -S . -B build/targets/atmega2560 -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/atmega2560.cmake
set(FDSURF_TARGET atmega2560)
set(FDSURF_TARGET_MCU atmega2560)
set(FDSURF_TARGET_SETUP ON)
include(${CMAKE_CURRENT_LIST_DIR}/avr.cmake)
