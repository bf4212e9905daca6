#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# One third-party check as a CTest test:
#   run_check.sh FDSURF INPUT gcode|g5|render [fdsurf plot options...]
# Draws INPUT with `fdsurf plot` (the strokes as JSON, and the G-code, or the
# SVG and HPGL, with the same options) and has check_gcode.py, check_g5.py or
# check_render.py read the files back with other programs.
set -euo pipefail
fdsurf=$1 input=$2 kind=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

if [ ! -d "$here/node_modules/gcode-toolpath" ] && [ "$kind" = gcode ]; then
  echo "run_check: $here/node_modules is missing; run: npm ci --prefix tests/thirdparty" >&2
  exit 1
fi
case "$kind" in
  gcode)
    "$fdsurf" plot "$input" -q --format json -o "$work/strokes.json" "$@"
    "$fdsurf" plot "$input" -q --format gcode -o "$work/out.gcode" "$@"
    timeout 300 python3 "$here/check_gcode.py" "$work/strokes.json" "$work/out.gcode"
    ;;
  g5)
    # G5 cubics (--flavor marlin or linuxcnc among the options) against the
    # input's exact curves, by a reader written from the G5 documentation.
    "$fdsurf" plot "$input" -q --format gcode -o "$work/out.gcode" "$@"
    timeout 300 python3 "$here/check_g5.py" "$input" "$work/out.gcode" "$@"
    ;;
  render)
    "$fdsurf" plot "$input" -q --format json -o "$work/strokes.json" "$@"
    "$fdsurf" plot "$input" -q --format json --quantum 0.025 -o "$work/strokes-hpgl.json" "$@"
    "$fdsurf" plot "$input" -q --format svg -o "$work/out.svg" "$@"
    "$fdsurf" plot "$input" -q --format hpgl -o "$work/out.hpgl" "$@"
    python3 "$here/check_render.py" "$work/strokes.json" --svg "$work/out.svg"
    python3 "$here/check_render.py" "$work/strokes-hpgl.json" --hpgl "$work/out.hpgl"
    ;;
  *)
    echo "run_check: unknown check '$kind'" >&2
    exit 2
    ;;
esac
