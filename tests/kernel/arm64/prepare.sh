#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Kernel.Arm64 fixture: the guest's Debian parts (fetch_guest.sh), the
# arm64 fdsurf-gpio-stream (cross/, statically linked; `file` must say
# aarch64) and the job with the simulated plotter's waveform of it.
#   prepare.sh SOURCE_DIR WORK_DIR JOB_TOOL TICK_HZ
set -euo pipefail
source_dir=$1 work=$2 job_tool=$3 tick_hz=$4
here=$source_dir/tests/kernel/arm64
for tool in qemu-system-aarch64 aarch64-linux-gnu-g++; do
  command -v "$tool" >/dev/null || {
    echo "prepare.sh: $tool is missing: run scripts/setup.sh (qemu-system-arm, g++-aarch64-linux-gnu)" >&2
    exit 1
  }
done
bash "$here/fetch_guest.sh" "$work"
cmake -S "$here/cross" -B "$work/cross" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE="$here/aarch64-linux-gnu.cmake" >/dev/null
cmake --build "$work/cross" --parallel 2 >"$work/cross-build.log" 2>&1 || {
  tail -n 40 "$work/cross-build.log" >&2
  exit 1
}
what=$(file -b "$work/cross/fdsurf-gpio-stream")
case $what in
  *"ARM aarch64"*statically\ linked*) echo "fdsurf-gpio-stream: $what" ;;
  *) echo "prepare.sh: fdsurf-gpio-stream is not a static aarch64 executable: $what" >&2; exit 1 ;;
esac
"$job_tool" --input "$here/job.json" --job "$work/job" --reference "$work/reference.wave" \
  --tick-hz "$tick_hz"
