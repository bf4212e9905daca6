# SPDX-License-Identifier: MIT
# Shared part of the Cortex-M toolchain files: Debian's arm-none-eabi-g++
# (gcc-arm-none-eabi, libnewlib-arm-none-eabi). Include after setting
# FDSURF_TARGET, FDSURF_CPU_FLAGS and FDSURF_TARGET_MEMORY.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(FDSURF_TARGET_ARCH arm)
set(FDSURF_TARGET_SETUP ON)
set(CMAKE_CXX_FLAGS_INIT
    "${FDSURF_CPU_FLAGS} -ffunction-sections -fdata-sections -fno-unwind-tables -fno-asynchronous-unwind-tables")
# Set, not _INIT: CMake would append its own -O3 to an _INIT value.
set(CMAKE_CXX_FLAGS_RELEASE "-O2" CACHE STRING "Release flags of the target" FORCE)
# No C runtime start files: targets/port/arm.cc has the vector table and reset
# handler. newlib-nano provides memcpy/memset, libgcc the compiler helpers.
set(CMAKE_EXE_LINKER_FLAGS_INIT "${FDSURF_CPU_FLAGS} -nostdlib -Wl,--gc-sections")
set(FDSURF_TARGET_LIBS -Wl,--start-group c_nano gcc -Wl,--end-group)
set(FDSURF_SIZE_TOOL arm-none-eabi-size)
set(FDSURF_NM_TOOL arm-none-eabi-nm)
