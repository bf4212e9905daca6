#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Sets everything up (Debian packages, build) and runs every check: the test
# suite, the same suite under AddressSanitizer + UndefinedBehaviorSanitizer,
# the libFuzzer targets, clang-format and clang-tidy. Exits non-zero on the
# first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
# Each section says when it starts (seconds since the start), so a slow CI
# run shows where its time went.
section() { echo "== [${SECONDS} s] $*"; }

section "build (Release) and test, with every microcontroller image under its emulator"
bash scripts/setup.sh
# Includes the Target.* tests: each builds a cross target in build/targets/<target>
# and runs its image under QEMU or simavr against the host reference, and the
# label `kernel` (tests/kernel/): Debian's kernel under QEMU, its USB stack with
# the firmware as a gadget (the kernel package is fetched once by apt-get
# download into build/tests/kernel/kernel-cache). Not in the sanitizer build.
ctest --test-dir build --output-on-failure --parallel "$jobs"

section "Debian package of the tool: cpack, install, run, remove"
# CI runs as root (README). The -dev package is built beside it and tested
# through the install tests (Package.*).
(cd build && cpack -G DEB >/dev/null)
version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' build/CMakeCache.txt)
deb=$(ls build/fdsurf_"$version"_*.deb)
dpkg -i "$deb" >/dev/null
installed=$(/usr/bin/fdsurf --version)
dpkg -r fdsurf >/dev/null
if [ "$installed" != "fdsurf $version" ]; then
  echo "installed /usr/bin/fdsurf --version printed '$installed', expected 'fdsurf $version'" >&2
  exit 1
fi
echo "$deb: /usr/bin/fdsurf --version: $installed"

section "build with -fsanitize=address,undefined and test"
FDSURF_BUILD_DIR=build-sanitize FDSURF_BUILD_TYPE=Debug \
  FDSURF_CMAKE_ARGS="-DFDSURF_SANITIZE=ON -DFDSURF_BUILD_BENCH=OFF" bash scripts/setup.sh
# Left out here: the seven whole-teapot runs through the tool (100-194 s each
# under ASan in Debug, 5-18 s in Release, about 500 s of this section's wall
# time on 2 cores). The Release pass above runs them; their code runs here in
# the same suites on smaller drawings (docs/testing.md, "The sanitizer build").
teapot_runs='^(StreamHidden\.TheTeapotDrawsWhatPlotDrawsWithinTheBound'
teapot_runs+='|MachineCli\.StreamWithTheSimProfileDrawsWhatTheSameFlagsDraw'
teapot_runs+='|HiddenLines\.TheTeapotAgreesWithAMeshReferenceInTheIsoAndFrontViews'
teapot_runs+='|Cli\.StreamChargesTheDevicesComputeTimeOnRequest'
teapot_runs+='|DryRunTest\.TeapotMachineTimeIsTheSimulatedRunsFigure'
teapot_runs+='|Toolpath\.EveryPointAndChordOfTheTeapotIsWithinTolerance'
teapot_runs+='|Units\.StreamOptionsAgreeInBothUnits)$'
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-sanitize --output-on-failure --parallel "$jobs" -E "$teapot_runs"

section "fuzz targets under ASan+UBSan: regressions and corpora, then 45 s of fuzzing each"
# fuzz/README.md; a long run by hand: bash scripts/fuzz.sh 3600
bash scripts/fuzz.sh 45

section "clang-format"
git ls-files '*.cc' '*.h' | xargs clang-format --dry-run -Werror

section "clang-tidy (firmware/, hal/, host/, sim/, tools/, the boards' emulator harnesses, the test image's host build)"
# clang-tidy counts the (filtered-out) warnings of system headers on stderr;
# show its output only when it fails.
if ! tidy=$(git ls-files 'firmware/*.cc' 'host/*.cc' 'hal/*.cc' 'sim/*.cc' 'tools/*.cc' 'targets/image/*.cc' 'boards/*/host/*.cc' \
  'targets/port/host.cc' |
  grep -v '/test/' | xargs -P "$jobs" -n 2 clang-tidy -p build --quiet 2>&1); then
  echo "$tidy" | grep -v 'warnings generated'
  exit 1
fi
echo "all checks passed in ${SECONDS} s"
