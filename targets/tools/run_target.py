#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Runs a target's test image under its emulator and checks it against the host.

1. The host reference (fdsurf_image_host, --small for the ATmega328P) prints
   the expected report.
2. The image runs under QEMU (with the instruction-counting plugin) or simavr
   (exact cycles), always under `timeout`: a hard fault is a silent hang.
3. The report must equal the host's bit for bit (lines starting with '#'
   describe the target and are left out of the comparison).
4. Each "bench" line is paired with its two marks; the cost per point and the
   sizes (text/data/bss of each size image minus the baseline) go to
   DIR/results/bench.tsv and DIR/results/sizes.tsv for targets/tools/target_report.py.

Usage: run_target.py --target T --dir BUILD_DIR --host REF --plugin SO --simavr EXE
"""
import argparse
import difflib
import os
import subprocess
import sys

QEMU = {
    "cortex-m0": ("qemu-system-arm", ["-M", "microbit"]),
    "cortex-m3": ("qemu-system-arm", ["-M", "mps2-an385"]),
    "cortex-m4f": ("qemu-system-arm", ["-M", "mps2-an386"]),
    "cortex-m7": ("qemu-system-arm", ["-M", "mps2-an500"]),
    "rv32imac": ("qemu-system-riscv32", ["-M", "virt", "-bios", "none"]),
}
AVR = {"atmega328p", "atmega2560"}
TOOLS = {"arm": "arm-none-eabi-", "riscv": "riscv64-unknown-elf-", "avr": "avr-"}
TIMEOUT_SECONDS = 300


def tool_prefix(target):
    if target in AVR:
        return TOOLS["avr"]
    return TOOLS["riscv"] if target.startswith("rv") else TOOLS["arm"]


def symbol_address(target, elf, name):
    out = subprocess.run([tool_prefix(target) + "nm", elf], check=True, capture_output=True,
                         text=True).stdout
    for line in out.splitlines():
        fields = line.split()
        if len(fields) == 3 and fields[2] == name:
            return int(fields[0], 16)
    sys.exit(f"{elf}: no symbol {name}")


def run_image(args, elf, results):
    report = os.path.join(results, "report.txt")
    marks = os.path.join(results, "marks.txt")
    for path in (report, marks):
        if os.path.exists(path):
            os.remove(path)
    if args.target in AVR:
        command = ["timeout", str(TIMEOUT_SECONDS), args.simavr, "-m", args.target, "-f",
                   "16000000", "-o", marks, elf]
        with open(report, "wb") as out:
            proc = subprocess.run(command, stdout=out, stderr=subprocess.PIPE)
    else:
        qemu, machine = QEMU[args.target]
        mark = symbol_address(args.target, elf, "fdsurf_image_mark")
        command = (["timeout", str(TIMEOUT_SECONDS), qemu] + machine +
                   ["-display", "none", "-monitor", "none", "-serial", "none",
                    "-chardev", f"file,id=semihosting,path={report}",
                    "-semihosting-config", "enable=on,target=native,chardev=semihosting",
                    "-plugin", f"{args.plugin},mark={mark:#x},out={marks}",
                    "-kernel", elf])
        proc = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    print(" ".join(command))
    sys.stderr.write(proc.stderr.decode(errors="replace"))
    if proc.returncode != 0:
        sys.exit(f"{args.target}: the image exited with {proc.returncode}"
                 f"{' (timeout: a hang or a fault)' if proc.returncode == 124 else ''}")
    with open(report) as f:
        text = f.read()
    with open(marks) as f:
        counts = [int(line) for line in f if line.strip() and not line.startswith("total")]
    return text, counts


def sizes(args, build):
    size_tool = tool_prefix(args.target) + "size"
    with open(os.path.join(build, "size_groups.txt")) as f:
        groups = f.read().split()

    def measure(name):
        out = subprocess.run([size_tool, "-A", os.path.join(build, f"fdsurf_{name}.elf")],
                             check=True, capture_output=True, text=True).stdout
        text = data = bss = 0
        for line in out.splitlines():
            fields = line.split()
            if len(fields) < 2 or not fields[1].isdigit():
                continue
            section, size = fields[0], int(fields[1])
            if section in (".text", ".rodata", ".init_array", ".ARM.exidx", ".vectors"):
                text += size
            elif section in (".data", ".sdata"):
                data += size
            elif section in (".bss", ".sbss", ".noinit"):
                bss += size
        return text, data, bss

    rows = []
    base = measure("size_baseline")
    for group in groups:
        t, d, b = measure(f"size_{group}")
        rows.append((group, t - base[0], d - base[1], b - base[2]))
    t, d, b = measure("image")
    rows.append(("test-image", t, d, b))
    rows.append(("baseline", *base))  # the port alone: a group's image is it plus the group
    return rows


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--target", required=True)
    p.add_argument("--dir", required=True)
    p.add_argument("--host", required=True)
    p.add_argument("--plugin", required=True)
    p.add_argument("--simavr", required=True)
    p.add_argument("--self-test", action="store_true",
                   help="change one digit of the host's report and pass only if the comparison "
                        "then fails (the check of the check)")
    args = p.parse_args()

    build = os.path.join(args.dir, "targets")
    elf = os.path.join(build, "fdsurf_image.elf")
    results = os.path.join(args.dir, "results-self-test" if args.self_test else "results")
    os.makedirs(results, exist_ok=True)

    host_args = [args.host] + (["--small"] if args.target == "atmega328p" else [])
    expected = subprocess.run(host_args, check=True, capture_output=True, text=True).stdout
    if args.self_test:
        # The last digit of the first CRC.
        at = expected.index(" crc ") + len(" crc ") + 7
        flipped = "0" if expected[at] != "0" else "1"
        expected = expected[:at] + flipped + expected[at + 1:]
    actual, counts = run_image(args, elf, results)

    def compared(text):
        return [line for line in text.splitlines() if not line.startswith("#")]

    if compared(actual) != compared(expected):
        diff = difflib.unified_diff(compared(expected), compared(actual), "host", args.target,
                                    lineterm="", n=1)
        print("\n".join(list(diff)[:60]))
        if args.self_test:
            print(f"{args.target}: one changed digit in the reference is caught, as it must be")
            return
        sys.exit(f"{args.target}: the report differs from the host reference")
    if args.self_test:
        sys.exit(f"{args.target}: a changed reference went unnoticed")
    lines = compared(actual)
    items = sum(1 for line in lines if line.split()[0] in
                ("patch2", "patch3", "curve2", "curve3", "adaptive2", "adaptive3", "coefficients"))
    print(f"{args.target}: {items} items, {len(lines)} lines, bit-identical to the host")

    bench = [line.split() for line in lines if line.startswith("bench ")]
    if len(counts) != 2 * len(bench):
        sys.exit(f"{args.target}: {len(counts)} marks for {len(bench)} bench lines")
    unit = "cycles" if args.target in AVR else "instructions"
    stack = [line.split()[2] for line in actual.splitlines() if line.startswith("# stack ")]
    with open(os.path.join(results, "bench.tsv"), "w") as out:
        out.write(f"# target\tname\tdims\tpoints\tacc\t{unit}\tper point\n")
        for i, fields in enumerate(bench):
            # bench NAME 2d points N acc W
            name, dims, points, acc = fields[1], fields[2], int(fields[4]), fields[6]
            count = counts[2 * i + 1] - counts[2 * i]
            out.write(f"{args.target}\t{name}\t{dims}\t{points}\t{acc}\t{count}\t"
                      f"{count / points:.1f}\n")
            print(f"  {name:20} {dims} {points:6} points  acc {acc:3}  {count:10} {unit}"
                  f"  {count / points:9.1f} per point")
    with open(os.path.join(results, "sizes.tsv"), "w") as out:
        out.write("# target\tgroup\ttext\tdata\tbss\tstack\n")
        for group, t, d, b in sizes(args, build):
            out.write(f"{args.target}\t{group}\t{t}\t{d}\t{b}\t"
                      f"{stack[0] if stack and group == 'test-image' else ''}\n")
            print(f"  size {group:12} text {t:7}  data {d:5}  bss {b:6}")
    if stack:
        print(f"  test image stack high-water mark: {stack[0]} bytes")


main()
