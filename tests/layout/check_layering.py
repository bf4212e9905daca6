#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""No dependency runs the wrong way (docs/architecture.md).

Every quoted #include of a source file in the tree is resolved to the box
that defines the header (by the include/ folders of the boxes), and each box
may include only the boxes below it in ALLOWED. Tests are left out: a test
may reach across boxes. Exits 1 naming the file, the line and both boxes.

  check_layering.py ROOT            check the tree
  check_layering.py ROOT --self-test  the check must fail on a planted include
"""
import os
import re
import sys

# Box -> the folders whose sources belong to it (relative to the root).
BOXES = {
    # The compiler configuration every freestanding box shares (the
    # nodiscard macro): in the HAL's include folder because fdsurf::hal is
    # the lowest target, which the core links.
    "config": ["hal/include/fdsurf/config"],
    "engine": ["firmware/engine"],
    "protocol": ["firmware/protocol"],
    "motion": ["firmware/motion"],
    "device": ["firmware/device"],
    "hal": ["hal/include", "hal/src"],
    "hal-sim": ["hal/sim"],
    "hal-linux": ["hal/linux"],
    "hal-libusb": ["hal/libusb"],
    "hal-libgpiod": ["hal/libgpiod"],
    "host-core": ["host/core"],
    "host-reference": ["host/reference"],
    "host-formats": ["host/formats"],
    "host-constructions": ["host/constructions"],
    "host-toolpath": ["host/toolpath"],
    "host-stream": ["host/stream"],
    "host-link": ["host/link"],
    "hal-libserialport": ["hal/libserialport"],
    "sim": ["sim"],
    "boards": ["boards"],
    "tools": ["tools"],
}

# What each box may include besides itself. The freestanding core and the
# HAL interfaces are the ground; the host library does not know the
# simulator, the HAL backends or the tool; the simulator does not know the
# host library except its end of the link.
CORE = {"engine", "protocol", "motion", "device", "hal"}
ALLOWED = {
    "config": set(),
    "engine": set(),
    "protocol": {"engine"},
    "motion": {"engine", "protocol", "hal"},
    "device": {"engine", "protocol", "motion", "hal"},
    "hal": set(),
    "hal-sim": {"hal"},
    "hal-linux": {"hal"},
    "hal-libusb": {"hal"},
    "hal-libgpiod": {"hal", "hal-linux"},
    "host-core": {"engine"},
    "host-reference": {"engine", "host-core"},
    "host-constructions": {"engine", "host-core", "host-reference"},
    "host-formats": {"engine", "host-core", "host-reference", "host-constructions"},
    "host-toolpath": {"engine", "host-core", "host-reference", "host-constructions"},
    # host-stream asks the device's own validation (motion::ValidateCommand)
    # about every command before a job is sent.
    "host-stream": {"engine", "protocol", "motion", "host-core", "host-reference",
                    "host-constructions", "host-toolpath"},
    "host-link": {"engine", "protocol"},
    "hal-libserialport": {"hal"},
    "sim": CORE | {"hal-sim", "host-link"},
    # A board port is firmware: the freestanding core and the HAL interfaces.
    "boards": CORE,
    "tools": set(BOXES),
}
for allowed in ALLOWED.values():
    allowed.add("config")

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def box_of(path):
    for box, folders in BOXES.items():
        for folder in folders:
            if path == folder or path.startswith(folder + "/"):
                return box
    return None


def headers(root):
    """'fdsurf/x.h' -> box, from every box's include/ folders."""
    found = {}
    for box, folders in BOXES.items():
        for folder in folders:
            for dirpath, _, files in os.walk(os.path.join(root, folder)):
                rel = os.path.relpath(dirpath, root)
                if "/test" in "/" + rel or "/include" not in "/" + rel:
                    continue
                base = rel[: rel.index("include") + len("include")]
                for f in files:
                    name = os.path.relpath(os.path.join(rel, f), base)
                    found[name] = box_of(os.path.join(rel, f))
    return found


def check(root, planted=None):
    """The wrong-way includes; `planted` maps a relative path to extra text."""
    known = headers(root)
    problems = []
    for rel, text in (planted or {}).items():
        problems += check_lines(rel, box_of(rel), text.splitlines(), known)
    for box, folders in BOXES.items():
        for folder in folders:
            for dirpath, _, files in os.walk(os.path.join(root, folder)):
                rel_dir = os.path.relpath(dirpath, root)
                if "/test" in "/" + rel_dir:
                    continue
                for f in sorted(files):
                    if not f.endswith((".h", ".cc", ".c")):
                        continue
                    rel = os.path.join(rel_dir, f)
                    with open(os.path.join(root, rel), encoding="utf-8") as text:
                        problems += check_lines(rel, box, text, known)
    return problems


def check_lines(rel, box, lines, known):
    problems = []
    for number, line in enumerate(lines, 1):
        m = INCLUDE.match(line)
        if not m or m.group(1) not in known:
            continue
        target = known[m.group(1)]
        if target != box and target not in ALLOWED[box]:
            problems.append(f"{rel}:{number}: {box} includes {m.group(1)} of {target}, "
                            "which it may not")
    return problems


def main():
    root = sys.argv[1]
    if "--self-test" in sys.argv:
        # Plant the wrong-way include the layout forbids most: the simulator
        # reaching into the host library.
        problems = check(root, {"sim/src/planted_wrong_way.cc": '#include "fdsurf/host/toolpath.h"'})
        if not any("planted_wrong_way.cc:1: sim includes fdsurf/host/toolpath.h" in p
                   for p in problems):
            print("self-test: the planted include was not found", file=sys.stderr)
            return 1
        print("self-test: the planted wrong-way include was found")
        return 0
    problems = check(root)
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        return 1
    print(f"layering: {len(BOXES)} boxes, no include runs the wrong way")
    return 0


if __name__ == "__main__":
    sys.exit(main())
