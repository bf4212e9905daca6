#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks fdsurf's G-code by reading it back with a third-party interpreter.

usage: check_gcode.py STROKES.json FILE.gcode

The npm package gcode-toolpath (through gcode_segments.js) turns the G-code into
motion segments. A stroke is rebuilt as a maximal run of consecutive G1
segments, each starting where the previous one ended, without its leading
Z-only moves (the pen-down plunge). The strokes must match the ones fdsurf
reports in STROKES.json (`fdsurf plot --format json` with the same options)
point for point: same count, same order, each coordinate within half a quantum.
"""
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def fail(message):
    print(f"check_gcode: {message}", file=sys.stderr)
    sys.exit(1)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    strokes_file, gcode_file = sys.argv[1:]
    with open(strokes_file, encoding="utf-8") as f:
        expected = json.load(f)
    result = subprocess.run(["node", os.path.join(HERE, "gcode_segments.js"), gcode_file],
                            capture_output=True, text=True, check=False, timeout=300)
    if result.returncode != 0:
        fail(f"gcode-toolpath could not read {gcode_file}: {result.stderr.strip()}")
    segments = json.loads(result.stdout)

    # gcode-toolpath reports millimetres; bring the expectation to the same unit.
    to_mm = 25.4 if expected["units"] == "in" else 1.0
    dims = expected["dims"]
    tolerance = expected["quantum"] * to_mm / 2 + 1e-9

    strokes = []
    current = None
    for seg in segments:
        if seg["motion"] != "G1":
            current = None
            continue
        v1, v2 = seg["v1"], seg["v2"]
        if current is not None and current[-1] == v2[:3] and v1 == v2:
            continue  # a zero-length G1 changes nothing
        if current is None or current[-1] != v1:
            current = [v1]
            strokes.append(current)
        current.append(v2)
    rebuilt = []
    for stroke in strokes:
        # Leading Z-only moves are the plunge, not part of the drawing.
        while len(stroke) > 1 and stroke[0][:2] == stroke[1][:2] and (dims == 2 or stroke[0][2] != stroke[1][2]):
            stroke = stroke[1:]
        rebuilt.append([p[:dims] for p in stroke])

    want = expected["strokes"]
    if len(rebuilt) != len(want):
        fail(f"{gcode_file}: gcode-toolpath sees {len(rebuilt)} strokes, fdsurf drew {len(want)}")
    worst = 0.0
    points = 0
    for i, (got, ref) in enumerate(zip(rebuilt, want)):
        if len(got) != len(ref):
            fail(f"{gcode_file}: stroke {i}: gcode-toolpath sees {len(got)} points, fdsurf drew {len(ref)}")
        for k, (g, r) in enumerate(zip(got, ref)):
            for c in range(dims):
                d = abs(g[c] - r[c] * to_mm)
                worst = max(worst, d)
                if d > tolerance:
                    fail(f"{gcode_file}: stroke {i} point {k}: gcode-toolpath reads {g[:dims]} mm, "
                         f"fdsurf drew {[v * to_mm for v in r]} mm")
            points += 1
    print(f"check_gcode: {gcode_file}: {len(rebuilt)} strokes, {points} points match "
          f"(largest difference {worst:.3g} mm, limit {tolerance:.3g} mm)")


if __name__ == "__main__":
    main()
