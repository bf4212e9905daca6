#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Sets everything up and runs fdsurf's main job on its default target, the
# simulated plotter: streams the Utah teapot (examples/teapot.bpt) as 32
# Bézier patches to the firmware running over the in-memory HAL, which draws
# their isolines by step-exact forward differences; then shows what it drew
# (build/teapot.svg, build/teapot.png) and how it compares with the exact
# surface and the machine's limits. No hardware needed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
./build/fdsurf stream examples/teapot.bpt --svg build/teapot.svg --png build/teapot.png
echo "open build/teapot.svg or build/teapot.png to see what the simulated plotter drew"
