#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# -DFDSURF_CORE_ONLY=ON needs nothing but a compiler: configured with every
# package fdsurf's full build finds disabled, it builds the core, and its
# install is a package with fdsurf::core and fdsurf::hal only. Also a host
# project that adds <fdsurf>/firmware alone, again with no package lookups.
# Usage: core_only.sh SOURCE_DIR WORK_DIR
set -euo pipefail
src=$(cd "$1" && pwd)
work=$2
rm -rf "$work"
mkdir -p "$work"
disabled=()
for p in GTest CLI11 PkgConfig nlohmann_json benchmark Threads Python3; do
  disabled+=("-DCMAKE_DISABLE_FIND_PACKAGE_$p=ON")
done
cmake -S "$src" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFDSURF_CORE_ONLY=ON \
  "${disabled[@]}" >"$work/configure.log" 2>&1 || {
  cat "$work/configure.log"
  exit 1
}
cmake --build "$work/build" --parallel 2 >"$work/build.log" 2>&1 || {
  cat "$work/build.log"
  exit 1
}
"$src/tests/package/install_and_consume.sh" "$work/build" "$work/consume" "$src/examples" core-only

# add_subdirectory(<fdsurf>/firmware) from a host project.
mkdir -p "$work/subdir"
cat >"$work/subdir/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.16)
project(fdsurf_subdir_consumer CXX)
set(CMAKE_CXX_STANDARD 17)
add_subdirectory("$src/firmware" fdsurf)
add_executable(core_consumer "$src/tests/package/consumer/core_main.cc")
target_link_libraries(core_consumer PRIVATE fdsurf::core)
CMAKE
cmake -S "$work/subdir" -B "$work/subdir/build" -G Ninja "${disabled[@]}" \
  >"$work/subdir.configure.log" 2>&1 || {
  cat "$work/subdir.configure.log"
  exit 1
}
cmake --build "$work/subdir/build" --parallel 2 >"$work/subdir.build.log" 2>&1 || {
  cat "$work/subdir.build.log"
  exit 1
}
out=$("$work/subdir/build/core_consumer")
if [ "$out" != "curve: 0,0 150,225 300,0" ]; then
  echo "add_subdirectory(firmware) consumer printed: $out" >&2
  exit 1
fi
echo "add_subdirectory(firmware) from a host project: ok"
