# SPDX-License-Identifier: MIT
# Cortex-M7 (QEMU -M mps2-an500): double-precision FPU, hard-float ABI.
# cmake -S . -B build/targets/cortex-m7 -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/cortex-m7.cmake
set(FDSURF_TARGET cortex-m7)
set(FDSURF_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfloat-abi=hard -mfpu=fpv5-d16")
set(FDSURF_TARGET_MEMORY mps2)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
