#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Runs fdsurf_bench and prints the table of docs/performance.md.

Every ratio is against the fixed engine's stepping measured in the same run,
so the table compares like with like on whatever machine runs it.

usage: bench/report.py [path/to/fdsurf_bench] [--repetitions N]
"""
import json
import subprocess
import sys


def main():
    args = sys.argv[1:]
    binary = args[0] if args and not args[0].startswith("--") else "build/bench/fdsurf_bench"
    repetitions = "5"
    if "--repetitions" in args:
        repetitions = args[args.index("--repetitions") + 1]
    raw = subprocess.run(
        [binary, "--benchmark_format=json", "--benchmark_repetitions=" + repetitions,
         "--benchmark_report_aggregates_only=true"],
        check=True, capture_output=True, text=True).stdout
    results = {}
    for b in json.loads(raw)["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        name = b["run_name"]
        results[name] = b
    print("| benchmark | grid per patch | rate (median of %s) | fixed stepping is … faster |" % repetitions)
    print("|---|---|---|---|")
    for name, b in results.items():
        kind, grid = name.split("/")
        rate = b["items_per_second"]
        base = results.get("BM_FixedStepping/" + grid)
        unit = "patches/s" if kind == "BM_FixedSetupOnly" else "points/s"
        ratio = "" if base is None or unit != "points/s" else "%.2f×" % (base["items_per_second"] / rate)
        print("| %s | %s×%s | %s %s | %s |" % (kind[3:], grid, grid, format_rate(rate), unit, ratio))


def format_rate(rate):
    for scale, suffix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if rate >= scale:
            return "%.1f %s" % (rate / scale, suffix)
    return "%.1f" % rate


if __name__ == "__main__":
    main()
