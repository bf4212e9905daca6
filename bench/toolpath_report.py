#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Adaptive vs fixed-step forward differencing on the teapot, for the same tolerance.

Runs `fdsurf plot` in each mode and prints a markdown table of the points it
emits (docs/toolpaths.md). Usage: python3 bench/toolpath_report.py [--fdsurf build/fdsurf]
"""
import argparse
import re
import subprocess
import sys

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--fdsurf", default="build/fdsurf")
parser.add_argument("--file", default="examples/teapot.bpt")
parser.add_argument("--args", default="--view iso --fit 200x150 --lines 8",
                    help="plot options shared by every run")
args = parser.parse_args()

SUMMARY = re.compile(r"(\d+) patches, (\d+) curves, (\d+) points, longest curve (\d+)")


def points(mode, tolerance):
    command = [args.fdsurf, "plot", args.file, "--format", "json", "-o", "/dev/null",
               "--mode", mode, "--tolerance", str(tolerance)] + args.args.split()
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)} failed: {result.stderr}")
    match = SUMMARY.search(result.stderr)
    if not match:
        sys.exit(f"no summary in: {result.stderr}")
    return int(match.group(2)), int(match.group(3)), int(match.group(4))


print(f"`{args.fdsurf} plot {args.file} --mode MODE --tolerance T {args.args}`\n")
print("| tolerance (mm) | curves | adaptive | fixed, N per curve | ratio | fixed, one N for all | ratio |")
print("|---|---|---|---|---|---|---|")
for tolerance in (0.5, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005):
    curves, adaptive, _ = points("adaptive", tolerance)
    _, fixed, longest = points("fixed", tolerance)
    uniform = curves * longest  # every curve stepped with the worst curve's N
    print(f"| {tolerance} | {curves} | {adaptive} | {fixed} | {fixed / adaptive:.2f}× "
          f"| {uniform} | {uniform / adaptive:.2f}× |")
