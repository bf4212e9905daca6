# SPDX-License-Identifier: MIT
# Cortex-M3 (QEMU -M mps2-an385): no FPU.
# cmake -S . -B build/targets/cortex-m3 -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/cortex-m3.cmake
set(FDSURF_TARGET cortex-m3)
set(FDSURF_CPU_FLAGS "-mcpu=cortex-m3 -mthumb -mfloat-abi=soft")
set(FDSURF_TARGET_MEMORY mps2)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
