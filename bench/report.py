#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Turns one fdsurf_bench run into the host tables of docs/performance.md.

Runs build/bench/fdsurf_bench with --benchmark_format=json (or reads a saved
run with --json), takes the medians of its repetitions, and prints: stepping
in ns per point, set-up in µs per patch, and both together per point (the
set-up spread over the (N+1)² points of a patch), each with the ratio of every
method's time to the fixed engine's in the same run (above 1: the engine is
faster), then the strongest baseline at each N.

usage: bench/report.py [path/to/fdsurf_bench] [--json RUN.json] [--save RUN.json]
"""
import json
import subprocess
import sys

ENGINE = "FixedEngine"

# Method -> what it emits, in the order of the tables.
METHODS = {
    "FixedEngine": "quanta",
    "DoubleFdQuanta": "quanta",
    "HornerRowsFmaQuanta": "quanta",
    "HornerFmaQuanta": "quanta",
    "HornerFma": "doubles",
    "OcctIsoCache": "doubles",
    "OcctD0": "doubles",
    "SislS1506": "doubles",
}


def option(args, name):
    if name in args:
        return args[args.index(name) + 1]
    return None


def load(args):
    saved = option(args, "--json")
    if saved:
        with open(saved) as f:
            return json.load(f)
    binary = args[0] if args and not args[0].startswith("--") else "build/bench/fdsurf_bench"
    raw = subprocess.run([binary, "--benchmark_format=json"], check=True,
                         capture_output=True, text=True).stdout
    save = option(args, "--save")
    if save:
        with open(save, "w") as f:
            f.write(raw)
    return json.loads(raw)


def medians(run):
    """{(kind, method, n): (seconds per item, repetitions)} from the median aggregates."""
    result = {}
    for b in run["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        # "BM_Stepping<FixedEngine>/64/repeats:5"
        head, n = b["run_name"].split("/")[:2]
        kind, method = head[len("BM_"):].rstrip(">").split("<")
        per = b.get("per_point", b.get("per_patch"))
        result[(kind, method, int(n))] = (per, b.get("repetitions", 0))
    return result


def main():
    run = load(sys.argv[1:])
    m = medians(run)
    grids = sorted({n for (_, _, n) in m})
    methods = [x for x in METHODS if any(k[1] == x for k in m)]
    repetitions = max(r for (_, r) in m.values())

    def stepping(method, n):
        return m[("Stepping", method, n)][0] * 1e9

    def setup(method, n):
        return m[("Setup", method, n)][0] * 1e6

    def whole(method, n):
        return stepping(method, n) + setup(method, n) * 1e3 / (n + 1) ** 2

    context = run["context"]
    print("Run: %s, %d CPUs at %s MHz, load average %s; Horner FMA: %s; OCCT: %s; SISL: %s; "
          "medians of %d repetitions." % (
              context.get("date", "?"), context.get("num_cpus", 0), context.get("mhz_per_cpu", "?"),
              ", ".join("%.2f" % x for x in context.get("load_avg", [])),
              context.get("horner_fma", "?"), context.get("occt", "?"), context.get("sisl", "?"),
              repetitions))
    header = "| method | output | " + " | ".join("N = %d" % n for n in grids) + " |"
    rule = "|---|---|" + "---|" * len(grids)

    def table(title, value, unit, ratios):
        print()
        print(title)
        print()
        print(header)
        print(rule)
        for method in methods:
            cells = []
            for n in grids:
                v = value(method, n)
                cell = ("%.3f" if v < 1 else "%.2f" if v < 100 else "%.0f") % v
                if ratios:
                    cell += " (%.2f×)" % (v / value(ENGINE, n))
                cells.append(cell)
            print("| %s | %s | %s |" % (method, METHODS[method], " | ".join(cells)))
        if ratios:
            print()
            for n in grids:
                best = min((x for x in methods if x != ENGINE), key=lambda x: value(x, n))
                r = value(best, n) / value(ENGINE, n)
                verdict = ("the engine is %.2f× faster" % r if r >= 1 else
                           "the engine is %.2f× slower" % (1 / r))
                print("- N = %d: strongest baseline %s, %.2f %s against the engine's %.2f: %s." %
                      (n, best, value(best, n), unit, value(ENGINE, n), verdict))

    table("Stepping, ns per point (in brackets: time ÷ the engine's; above 1 the engine is "
          "faster):", stepping, "ns", True)
    table("Set-up, µs per patch:", setup, "µs", False)
    table("Set-up and stepping, ns per point (the set-up spread over the patch's (N+1)² "
          "points):", whole, "ns", True)


if __name__ == "__main__":
    main()
