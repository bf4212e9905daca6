#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Configures and builds one microcontroller target (cmake/toolchains/TARGET.cmake)
# in DIR: the test image, the size images and the hot-path check.
# Usage: build_target.sh TARGET DIR HOST_REFERENCE
#   HOST_REFERENCE: the host build's targets/fdsurf_image_host, which prepares
#   the tables of images without set-up (ATmega328P).
set -euo pipefail
target=$1
dir=$2
host=$3
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
cmake -S "$source_dir" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE="$source_dir/cmake/toolchains/$target.cmake" \
  -DFDSURF_IMAGE_HOST="$host" >"$dir.configure.log" 2>&1 || {
  cat "$dir.configure.log"
  exit 1
}
# One job: CTest already runs two target builds side by side on 2 cores.
cmake --build "$dir" --parallel "${FDSURF_TARGET_JOBS:-1}"
