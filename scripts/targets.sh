#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds every microcontroller target, runs each image under its emulator
# against the host reference, and prints the tables of docs/performance.md
# ("Microcontrollers") from those runs. Needs scripts/setup.sh first.
set -euo pipefail
cd "$(dirname "$0")/.."
ctest --test-dir build -L targets --output-on-failure --parallel "$(nproc)"
python3 targets/tools/target_report.py build
