# SPDX-License-Identifier: MIT
# RV32IMAC, ilp32 (QEMU -M virt), with Debian's riscv64-unknown-elf-gcc
# (gcc-riscv64-unknown-elf). Freestanding: the toolchain has no C library, so
# targets/port/riscv.cc provides start-up, semihosting and memcpy/memset.
# cmake -S . -B build/targets/rv32imac -G Ninja -DCMAKE_BUILD_TYPE=Release \
#   -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/rv32imac.cmake
set(FDSURF_TARGET rv32imac)
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR riscv32)
set(CMAKE_C_COMPILER riscv64-unknown-elf-gcc)
set(CMAKE_CXX_COMPILER riscv64-unknown-elf-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(FDSURF_TARGET_ARCH riscv)
set(FDSURF_TARGET_SETUP ON)
set(FDSURF_CPU_FLAGS "-march=rv32imac -mabi=ilp32 -mcmodel=medany")
set(CMAKE_CXX_FLAGS_INIT "${FDSURF_CPU_FLAGS} -ffunction-sections -fdata-sections")
# Set, not _INIT: CMake would append its own -O3 to an _INIT value.
set(CMAKE_CXX_FLAGS_RELEASE "-O2" CACHE STRING "Release flags of the target" FORCE)
# One RAM region holds code and data (QEMU loads the ELF into RAM): no RWX warning.
set(CMAKE_EXE_LINKER_FLAGS_INIT
    "${FDSURF_CPU_FLAGS} -nostdlib -nostartfiles -Wl,--gc-sections -Wl,--no-warn-rwx-segments")
set(FDSURF_TARGET_LIBS gcc)
set(FDSURF_SIZE_TOOL riscv64-unknown-elf-size)
set(FDSURF_NM_TOOL riscv64-unknown-elf-nm)
