# SPDX-License-Identifier: MIT
# Cortex-M0 (BBC micro:bit under QEMU -M microbit): no FPU, no divide instruction.
# cmake -S . -B build/targets/cortex-m0 -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/cortex-m0.cmake
set(FDSURF_TARGET cortex-m0)
set(FDSURF_CPU_FLAGS "-mcpu=cortex-m0 -mthumb -mfloat-abi=soft")
set(FDSURF_TARGET_MEMORY microbit)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
