#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Boots the USB test guest once under QEMU (TCG) and runs one scenario.

  run_guest.py --kernel VMLINUZ --initrd BASE.cpio --scenario SCRIPT
               [--file HOST_PATH:GUEST_PATH]... [--timeout S]

SCRIPT becomes /scenario.sh in a second cpio archive appended to BASE (the
kernel unpacks both); --file adds files the same way. The console (ttyS0) is
read until the guest powers off. Lines "FDSURF-RESULT key value..." are the
scenario's results, "FDSURF-EXIT n" its exit code.

As a module: boot(...) returns (exit code or None, {key: value}, console).
As a program: prints the results and exits with the scenario's code; a
guest that does not finish within --timeout is killed and the console's
last 60 lines are printed, exit 124.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from initramfs import Cpio  # noqa: E402


def boot(kernel, initrd, scenario, files=(), timeout=60, memory_mb=512):
    extra = Cpio()
    extra.file("scenario.sh", Path(scenario).read_bytes())
    for host, guest in files:
        extra.file(guest, Path(host).read_bytes())
    with tempfile.NamedTemporaryFile(suffix=".cpio", delete=False) as image:
        image.write(Path(initrd).read_bytes())
        image.write(extra.bytes())
    command = [
        "qemu-system-x86_64", "-accel", "tcg", "-m", str(memory_mb), "-nographic",
        "-no-reboot", "-kernel", str(kernel), "-initrd", image.name,
        "-append", "console=ttyS0 quiet loglevel=4 panic=-1 rdinit=/init",
    ]
    console = []
    start = time.monotonic()
    process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT)
    os.set_blocking(process.stdout.fileno(), False)
    pending = b""
    timed_out = False
    while True:
        chunk = process.stdout.read()
        if chunk:
            pending += chunk
            *lines, pending = pending.split(b"\n")
            console += [line.decode(errors="replace").rstrip("\r") for line in lines]
        elif process.poll() is not None:
            break
        elif time.monotonic() - start > timeout:
            timed_out = True
            process.kill()
            process.wait()
            break
        else:
            time.sleep(0.02)
    if pending:
        console.append(pending.decode(errors="replace"))
    os.unlink(image.name)
    code = None
    results = {}
    for line in console:
        words = line.split()
        if len(words) >= 2 and words[0] == "FDSURF-EXIT" and words[1].isdigit():
            code = int(words[1])
        elif len(words) >= 2 and words[0] == "FDSURF-RESULT":
            results[words[1]] = " ".join(words[2:])
    results["_seconds"] = f"{time.monotonic() - start:.1f}"
    if timed_out:
        results["_timed_out"] = "1"
    return code, results, console


def tail(console, lines=60):
    return "\n".join(console[-lines:])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kernel", required=True)
    parser.add_argument("--initrd", required=True)
    parser.add_argument("--scenario", required=True)
    parser.add_argument("--file", action="append", default=[])
    parser.add_argument("--timeout", type=float, default=60)
    args = parser.parse_args()
    files = [tuple(f.split(":", 1)) for f in args.file]
    code, results, console = boot(args.kernel, args.initrd, args.scenario, files, args.timeout)
    if code is None:
        why = "timed out" if results.get("_timed_out") else "ended without FDSURF-EXIT"
        print(f"run_guest.py: the guest {why} after {results['_seconds']} s; console tail:\n"
              f"{tail(console)}", file=sys.stderr)
        sys.exit(124)
    for key, value in results.items():
        print(key, value)
    sys.exit(code)


if __name__ == "__main__":
    main()
