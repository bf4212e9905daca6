#!/usr/bin/env bash
# Sets everything up and runs fdsurf's main job on its default input, the Utah
# teapot: checks the fixed-point engine against the double reference on a
# 64x64 grid per patch and writes every grid point to build/teapot-64.csv.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
./build/fdsurf check examples/teapot.bpt --grid 64
./build/fdsurf sample examples/teapot.bpt --grid 64 > build/teapot-64.csv
echo "wrote build/teapot-64.csv ($(($(wc -l < build/teapot-64.csv) - 1)) points)"
