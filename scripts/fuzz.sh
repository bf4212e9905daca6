#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets (fuzz/README.md) with clang, ASan and UBSan in
# build-fuzz/, runs every file of fuzz/regressions/<target>/ and
# fuzz/corpus/<target>/ through its target (the regression test), then fuzzes
# each target for SECONDS (default 60). New corpus entries go to a temporary
# directory, never into the repository. Exits non-zero on any finding; the
# input that found it is kept and its path printed.
#
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET]
#
# Environment: FDSURF_FUZZ_TARGETS (default: all five), FDSURF_FUZZ_JOBS
# (parallel libFuzzer jobs per target, default 1), FDSURF_FUZZ_KEEP (a
# directory to keep the grown corpora and artifacts in instead of a
# temporary one), FDSURF_FUZZ_KNOWN_DEFECTS (device_harness.h: report the
# known defects of issue 12 too).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
targets=${FDSURF_FUZZ_TARGETS:-fuzz_bpt fuzz_json fuzz_mesh fuzz_gcode fuzz_svg fuzz_device_bytes fuzz_device_frames}
jobs=${FDSURF_FUZZ_JOBS:-1}
build=build-fuzz

# The largest input per target: text files of a few patches or a few dozen
# triangles, a few frames' worth of link bytes, a few dozen host actions.
max_len() {
  case $1 in
    fuzz_bpt | fuzz_json | fuzz_mesh | fuzz_gcode | fuzz_svg) echo 4096 ;;
    fuzz_device_bytes) echo 2048 ;;
    fuzz_device_frames) echo 1024 ;;
  esac
}

echo "== fuzz: configure and build ($build, clang, -fsanitize=fuzzer,address,undefined)"
CC=${CC_FUZZ:-clang} CXX=${CXX_FUZZ:-clang++} cmake -S . -B "$build" -G Ninja \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFDSURF_FUZZ=ON -DFDSURF_BUILD_TESTS=OFF \
  -DFDSURF_BUILD_BENCH=OFF -DFDSURF_INSTALL=OFF >/dev/null
cmake --build "$build" --target fdsurf_fuzz --parallel "$(nproc)"

if [ -n "${FDSURF_FUZZ_KEEP:-}" ]; then
  work=$FDSURF_FUZZ_KEEP
  mkdir -p "$work"
else
  work=$(mktemp -d -t fdsurf-fuzz.XXXXXX)
  trap 'rm -rf "$work"' EXIT
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

# A finding leaves a crash-, leak-, timeout-, oom- or slow-unit- file in the
# artifact directory; libFuzzer's exit status says so too.
failed=0
report() {
  echo "fuzz: FINDING in $1 ($2); the input is kept:" >&2
  ls "$work/artifacts/$1"/* >&2 2>/dev/null || true
  if [ -z "${FDSURF_FUZZ_KEEP:-}" ]; then
    mkdir -p "$build/fuzz-findings/$1"
    cp "$work/artifacts/$1"/* "$build/fuzz-findings/$1/" 2>/dev/null || true
    echo "fuzz: copied to $build/fuzz-findings/$1/ (add it to fuzz/regressions/$1/)" >&2
  fi
  failed=1
}

for t in $targets; do
  bin=$build/fuzz/$t
  mkdir -p "$work/artifacts/$t" "$work/corpus/$t"
  inputs=()
  for dir in fuzz/regressions/$t fuzz/corpus/$t; do
    [ -d "$dir" ] && inputs+=($(find "$dir" -type f ! -name '.*' | sort))
  done
  echo "== fuzz: $t: ${#inputs[@]} regression and corpus inputs"
  # One process per input, so that every failing one is named (libFuzzer
  # stops at the first, and writes no artifact for an input given as a file).
  for input in "${inputs[@]}"; do
    if ! "$bin" -timeout=60 "$input" >"$work/$t.regression.log" 2>&1; then
      grep -E 'FINDING|SUMMARY|runtime error' "$work/$t.regression.log" | head -n 5 >&2 || true
      echo "fuzz: FINDING in $t (regression run) on $input" >&2
      failed=1
    fi
  done
done
if [ "$failed" != 0 ]; then exit 1; fi

for t in $targets; do
  bin=$build/fuzz/$t
  extra=()
  if [ -f "fuzz/$t.dict" ]; then extra+=(-dict="fuzz/$t.dict"); fi
  # -jobs forks workers that log to fuzz-N.log in the current directory.
  if [ "$jobs" -gt 1 ]; then extra+=(-jobs="$jobs" -workers="$jobs"); fi
  seeds=()
  if [ -d "fuzz/corpus/$t" ]; then seeds=("fuzz/corpus/$t"); fi
  echo "== fuzz: $t for ${seconds} s"
  status=0
  "$bin" -max_total_time="$seconds" -max_len="$(max_len "$t")" -timeout=25 -rss_limit_mb=2048 \
    -print_final_stats=1 "${extra[@]}" \
    -artifact_prefix="$work/artifacts/$t/" "$work/corpus/$t" "${seeds[@]}" \
    >"$work/$t.log" 2>&1 || status=$?
  # The last progress line: executions, coverage, corpus.
  grep -E '^#[0-9]+' "$work/$t.log" | tail -n 1 || true
  grep -E 'stat::(number_of_executed_units|average_exec_per_sec|new_units_added)' "$work/$t.log" |
    tr '\n' ' ' || true
  echo
  if [ "$status" != 0 ] || [ -n "$(ls -A "$work/artifacts/$t")" ]; then
    grep -E 'FINDING|ERROR|SUMMARY|runtime error' "$work/$t.log" | head -n 20 >&2 || true
    report "$t" "libFuzzer exit status $status"
  fi
done
if [ "$failed" != 0 ]; then exit 1; fi
echo "fuzz: no findings"
