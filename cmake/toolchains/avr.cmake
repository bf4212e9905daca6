# SPDX-License-Identifier: MIT
# Shared part of the AVR toolchain files; include after setting
# FDSURF_TARGET, FDSURF_TARGET_MCU and FDSURF_TARGET_SETUP. avr-libc's start
# files and linker script; -Os, as AVR firmware is built.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR avr)
set(CMAKE_C_COMPILER avr-gcc)
set(CMAKE_CXX_COMPILER avr-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(FDSURF_TARGET_ARCH avr)
set(FDSURF_CPU_FLAGS "-mmcu=${FDSURF_TARGET_MCU} -DF_CPU=16000000UL")
set(CMAKE_CXX_FLAGS_INIT "${FDSURF_CPU_FLAGS} -ffunction-sections -fdata-sections")
# Set, not _INIT: CMake would append its own -O3 to an _INIT value.
set(CMAKE_CXX_FLAGS_RELEASE "-Os" CACHE STRING "Release flags of the target" FORCE)
set(CMAKE_EXE_LINKER_FLAGS_INIT "-mmcu=${FDSURF_TARGET_MCU} -Wl,--gc-sections")
set(FDSURF_TARGET_LIBS "")
set(FDSURF_SIZE_TOOL avr-size)
set(FDSURF_NM_TOOL avr-nm)
