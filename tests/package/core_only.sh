#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# -DFDSURF_CORE_ONLY=ON needs nothing but a compiler: configured with every
# package fdsurf's full build finds disabled, it builds the core, and its
# install is a package with fdsurf::core and fdsurf::hal only.
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
