#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Sums an AVR image's cycle profile (fdsurf_simavr_board --profile) per function.

    profile_report.py --elf IMAGE.elf --profile PROFILE.tsv [--top N] [--by function|line]

Each address is attributed with avr-addr2line -f -i -C to the innermost
function (or source line) it was inlined from, so the work GCC inlines into
main() and the interrupt vectors still shows under its own name, and the
cycles asleep apart. Prints the
cycles and their share of the whole run (sleep and interrupts included) for
the N largest, then the total. Needs the image's debug information (the
board images are built with -g).
"""
import argparse
import collections
import subprocess
import sys


def read_profile(path):
    """The cycles per address, and the cycles asleep."""
    cycles = {}
    asleep = 0
    with open(path, encoding="utf-8") as file:
        header = file.readline().split()
        if header != ["address", "cycles"]:
            sys.exit(f"profile_report: {path}: not a --profile TSV (header {header})")
        for number, line in enumerate(file, start=2):
            fields = line.split()
            if len(fields) != 2:
                sys.exit(f"profile_report: {path}:{number}: expected 'address<TAB>cycles'")
            if fields[0] == "asleep":
                asleep = int(fields[1])
            else:
                cycles[int(fields[0], 16)] = int(fields[1])
    return cycles, asleep


def innermost(elf, addresses, by):
    """Maps each address to its innermost inlined function (or file:line)."""
    query = "".join(f"{address:x}\n" for address in addresses)
    # With -i each address prints its inline chain, innermost first, and
    # "-a" prefixes every chain with the address, which separates them.
    out = subprocess.run(["avr-addr2line", "-a", "-f", "-i", "-C", "-e", elf],
                         input=query, capture_output=True, text=True, check=True).stdout
    names = {}
    lines = out.splitlines()
    for index, line in enumerate(lines):
        if not line.startswith("0x") or index + 2 >= len(lines):
            continue
        # The first function and location after an address are the innermost.
        function = lines[index + 1]
        location = lines[index + 2].split(" (discriminator")[0]
        if function == "??":
            names[int(line, 16)] = "?? (no debug information)"
        else:
            names[int(line, 16)] = function if by == "function" else f"{function} @ {location}"
    return names


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elf", required=True)
    parser.add_argument("--profile", required=True)
    parser.add_argument("--top", type=int, default=25)
    parser.add_argument("--by", choices=["function", "line"], default="function")
    args = parser.parse_args()
    cycles, asleep = read_profile(args.profile)
    names = innermost(args.elf, sorted(cycles), args.by)
    totals = collections.Counter()
    for address, count in cycles.items():
        totals[names.get(address, f"0x{address:x}")] += count
    totals["(asleep)"] += asleep
    whole = sum(cycles.values()) + asleep
    if whole == 0:
        sys.exit(f"profile_report: {args.profile}: no cycles recorded")
    print(f"{'cycles':>14}  {'share':>6}  where")
    for name, count in totals.most_common(args.top):
        print(f"{count:>14,}  {100.0 * count / whole:5.1f}%  {name}")
    print(f"{whole:>14,}  100.0%  the whole run")


if __name__ == "__main__":
    main()
