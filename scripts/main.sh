#!/usr/bin/env bash
# Sets everything up and runs fdsurf's main job on its default input: draws
# the Utah teapot (examples/teapot.bpt) as a wireframe of isolines, with
# adaptive forward differences within 0.05 mm, as an SVG for a pen plotter
# and a PNG to look at, both in build/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
./build/fdsurf plot examples/teapot.bpt --fit 200x150 -o build/teapot.svg --png build/teapot.png
echo "open build/teapot.svg or build/teapot.png to see the drawing"
