#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Prints the microcontroller tables of docs/performance.md from the results
of the emulator runs (ctest --test-dir build -L targets writes them to
build/targets/<target>/results/).

Usage: python3 targets/tools/target_report.py [BUILD_DIR]
"""
import os
import sys

TARGETS = ["atmega328p", "atmega2560", "cortex-m0", "cortex-m3", "cortex-m4f", "cortex-m7",
           "rv32imac"]
CLOCK_AVR = 16_000_000
ALTERNATIVES = ["float-de-casteljau", "float-horner", "fixed-horner"]


def read_tsv(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append(line.rstrip("\n").split("\t"))
    return rows


def load(build):
    bench, sizes = {}, {}
    for target in TARGETS:
        results = os.path.join(build, "targets", target, "results")
        if not os.path.exists(os.path.join(results, "bench.tsv")):
            continue
        for t, name, dims, points, acc, count, _ in read_tsv(os.path.join(results, "bench.tsv")):
            bench[(t, name, dims)] = (int(points), int(acc), int(count))
        for t, group, text, data, bss, stack in read_tsv(os.path.join(results, "sizes.tsv")):
            sizes[(t, group)] = (int(text), int(data), int(bss), stack)
    return bench, sizes


def per_point(bench, target, name, dims):
    value = bench.get((target, name, dims))
    return None if value is None else value[2] / value[0]


def fmt(x, digits=0):
    return "–" if x is None else f"{x:,.{digits}f}"


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    bench, sizes = load(build)
    present = [t for t in TARGETS if any(k[0] == t for k in bench)]

    print("### AVR at 16 MHz: exact cycles per point (simavr)\n")
    print("| chip | output | engine | float de Casteljau | float Horner | fixed Horner "
          "| engine points/s | vs de Casteljau | vs float Horner | vs fixed Horner |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for t in [t for t in present if t.startswith("atmega")]:
        for dims in ("2d", "3d"):
            e = per_point(bench, t, "engine-curve", dims)
            if e is None:  # the ATmega328P image has no 3-D curve bench (no room)
                continue
            alts = [per_point(bench, t, a, dims) for a in ALTERNATIVES]
            print(f"| {t} | {dims} curve | {fmt(e)} | " + " | ".join(fmt(a) for a in alts)
                  + f" | {fmt(CLOCK_AVR / e)} | "
                  + " | ".join(f"{fmt(a / e, 2)}×" for a in alts) + " |")
    print()
    print("| chip | engine row | points | accumulator | cycles/point | points/s |")
    print("|---|---|---|---|---|---|")
    for t in [t for t in present if t.startswith("atmega")]:
        for (tt, name, dims), (points, acc, count) in sorted(bench.items()):
            if tt != t or not (name.startswith("engine") or name.startswith("setup")):
                continue
            cpp = count / points
            rate = "–" if name.startswith("setup") else fmt(CLOCK_AVR / cpp)
            unit = "per item" if name.startswith("setup") else ""
            print(f"| {t} | {name} {dims} {unit} | {points} | {acc}-bit | {fmt(cpp)} | {rate} |")
    print()

    print("### Cortex-M and RV32: guest instructions per point (QEMU plugin)\n")
    print("| target | output | engine | float de Casteljau | float Horner | fixed Horner "
          "| vs de Casteljau | vs float Horner | vs fixed Horner |")
    print("|---|---|---|---|---|---|---|---|---|")
    for t in [t for t in present if not t.startswith("atmega")]:
        for dims in ("2d", "3d"):
            e = per_point(bench, t, "engine-curve", dims)
            if e is None:
                continue
            alts = [per_point(bench, t, a, dims) for a in ALTERNATIVES]
            print(f"| {t} | {dims} curve | {fmt(e, 1)} | "
                  + " | ".join(fmt(a, 1) for a in alts) + " | "
                  + " | ".join(f"{fmt(a / e, 2)}×" for a in alts) + " |")
    print()
    print("| target | 2-D patch | 3-D patch | 2-D adaptive | 2-D curve, 128-bit | set-up, 3-D patch 16×16 "
          "| set-up, 2-D curve |")
    print("|---|---|---|---|---|---|---|")
    for t in present:
        row = [per_point(bench, t, "engine-patch", "2d"), per_point(bench, t, "engine-patch", "3d"),
               per_point(bench, t, "engine-adaptive", "2d"),
               per_point(bench, t, "engine-curve-wide", "2d"),
               per_point(bench, t, "setup-patch", "3d"), per_point(bench, t, "setup-curve", "2d")]
        unit = "cycles" if t.startswith("atmega") else "instructions"
        print(f"| {t} ({unit}) | " + " | ".join(fmt(x, 0 if t.startswith('atmega') else 1)
                                               for x in row) + " |")
    print()

    print("### Flash and RAM (bytes)\n")
    print("| target | engine: set-up + stepping (flash / static RAM) | stepping only (flash) "
          "| test image flash | test image RAM: data + bss | test image stack high-water |")
    print("|---|---|---|---|---|---|")
    for t in present:
        eng = sizes.get((t, "engine"))
        step = sizes.get((t, "stepping"))
        img = sizes.get((t, "test-image"))
        eng_text = "does not fit" if eng is None else f"{eng[0] + eng[1]:,} / {eng[1]}"
        print(f"| {t} | {eng_text} | {step[0] + step[1]:,} | {img[0] + img[1]:,} | "
              f"{img[1] + img[2]:,} | {img[3]} |")
    print()

    # The whole device firmware (size/device.cc), and the same in the small
    # chip's configuration (size/device_prepared.cc: PREPARED_CURVE only,
    # 64-bit tables, no turn caps).
    print("### The device firmware, whole and in the small chip's configuration (bytes)\n")
    print("| target | device: flash / static RAM | no planner, 64-bit tables, no turn caps: "
          "flash / static RAM | the flash they take |")
    print("|---|---|---|---|")
    for t in present:
        full = sizes.get((t, "device"))
        lean = sizes.get((t, "device_prepared"))
        cells = ["does not fit" if x is None else f"{x[0] + x[1]:,} / {x[1] + x[2]:,}"
                 for x in (full, lean)]
        saved = "–" if full is None or lean is None else f"{full[0] + full[1] - lean[0] - lean[1]:,}"
        print(f"| {t} | {cells[0]} | {cells[1]} | {saved} |")
    print()

    # The same without the planner, sized as the Arduino Uno would hold it
    # (size/device_uno.cc: 2 queued commands, a 64-entry lookahead), as whole
    # images (the group plus the port alone) against the ATmega328P: 32,256
    # bytes of flash under a 512-byte boot loader (Optiboot), 2,048 of RAM.
    print("### The device firmware in the Arduino Uno's configuration (bytes)\n")
    print("| target | flash (text + data) | static RAM (data + bss) | ATmega328P: flash left "
          "| RAM left for the stack |")
    print("|---|---|---|---|---|")
    for t in present:
        uno = sizes.get((t, "device_uno"))
        base = sizes.get((t, "baseline"))
        if uno is None or base is None:
            continue
        flash = uno[0] + uno[1] + base[0] + base[1]
        ram = uno[1] + uno[2] + base[1] + base[2]
        if t == "atmega328p":
            print(f"| {t} | {flash:,} | {ram:,} | {32256 - flash:,} | {2048 - ram:,} |")
        else:
            print(f"| {t} | {flash:,} | {ram:,} | – | – |")


main()
