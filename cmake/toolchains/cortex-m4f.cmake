# SPDX-License-Identifier: MIT
# Cortex-M4F (QEMU -M mps2-an386): single-precision FPU, hard-float ABI.
# cmake -S . -B build/targets/cortex-m4f -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/cortex-m4f.cmake
set(FDSURF_TARGET cortex-m4f)
set(FDSURF_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
set(FDSURF_TARGET_MEMORY mps2)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
