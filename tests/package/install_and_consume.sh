#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs a build of fdsurf into a scratch prefix and uses it as another
# project would: find_package(fdsurf) from tests/package/consumer (CMake,
# Ninja), then pkg-config fdsurf / fdsurf-host with the compiler alone.
# Usage: install_and_consume.sh BUILD_DIR WORK_DIR EXAMPLES_DIR [core-only]
set -euo pipefail
build=$1
work=$2
examples=$3
mode=${4:-full}
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)
examples=$(cd "$examples" && pwd)
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" >"$work/install.log"
expected_curve="curve: 0,0 150,225 300,0"

check() { # NAME EXPECTED ACTUAL
  if [ "$2" != "$3" ]; then
    printf '%s: expected\n%s\ngot\n%s\n' "$1" "$2" "$3" >&2
    exit 1
  fi
  echo "$1: ok"
}

# CMake: find_package(fdsurf 0.2 REQUIRED ...) and nothing of the source tree.
consumer_args=()
if [ "$mode" = core-only ]; then
  consumer_args+=(-DFDSURF_CONSUMER_CORE_ONLY=ON)
fi
cmake -S "$here/consumer" -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF "${consumer_args[@]}" \
  >"$work/consumer.configure.log" 2>&1 || {
  cat "$work/consumer.configure.log"
  exit 1
}
cmake --build "$work/consumer" --parallel 2 >"$work/consumer.build.log" 2>&1 || {
  cat "$work/consumer.build.log"
  exit 1
}
check "cmake core_consumer" "$expected_curve" "$("$work/consumer/core_consumer")"
if [ "$mode" != core-only ]; then
  check "cmake consumer" "patches: 32
$expected_curve" "$("$work/consumer/consumer" "$examples/teapot.bpt")"
fi

# pkg-config: the core with its Cflags/Libs, C++14 as an MCU project would.
export PKG_CONFIG_PATH=$(dirname "$(find "$prefix" -name fdsurf.pc)")
c++ -std=c++14 -o "$work/pc_core" "$here/consumer/core_main.cc" $(pkg-config --cflags --libs fdsurf)
check "pkg-config fdsurf" "$expected_curve" "$("$work/pc_core")"
if [ "$mode" != core-only ]; then
  # The libraries are static: --static brings in cairo (Requires.private).
  c++ -std=c++20 -o "$work/pc_host" "$here/consumer/host_consumer.cc" \
    $(pkg-config --static --cflags --libs fdsurf-host)
  check "pkg-config fdsurf-host" "patches: 32
$expected_curve" "$("$work/pc_host" "$examples/teapot.bpt")"
else
  if [ -e "$PKG_CONFIG_PATH/fdsurf-host.pc" ] || [ -e "$prefix/bin/fdsurf" ]; then
    echo "core-only install has host parts" >&2
    exit 1
  fi
fi
echo "installed package consumed"
