#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""End to end on the emulated micro:bit v1: starts host/run_qemu.py, streams a
small job over its socket with the host's link (fdsurf_board_socket_stream),
stops the harness, and checks what the pins did:

- the waveform's header and format (version 1, times non-decreasing);
- every STEP pulse is high for >= 1.9 us, its DIR was set >= 650 ns before,
  and the drivers were enabled (ENABLE low);
- the steps, decoded with the header's DIR polarity, end exactly at the
  position the device's STATUS reports, and there are as many step ticks as
  the device's unit moves; the pen went down and up;
- the measures: no fault, no received byte dropped, no late tick while
  moving, a stack high-water inside the stack space, HELLO's tick rate.
The check of the check: decoded with the opposite DIR polarity, the same
waveform must miss the reported position (else the position check proves
nothing and the test fails).

Usage: qemu_board_test.py --elf ELF --client EXE --plugin SO --job FILE --out DIR
"""
import argparse
import os
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
HARNESS = os.path.join(os.path.dirname(HERE), "host", "run_qemu.py")
HEADER = ["# fdsurf-waveform 1", "# board microbit-v1", "# dir_negative_level 1",
          "# enable_active_level 0", "# pen line 1"]
SIGNALS = {"X_STEP", "X_DIR", "X_EN", "Y_STEP", "Y_DIR", "Y_EN", "PEN"}
MIN_PULSE_NS = 1900
MIN_DIR_SETUP_NS = 650


def read_waveform(path):
    with open(path, encoding="ascii") as f:
        lines = f.read().splitlines()
    if lines[:len(HEADER)] != HEADER:
        raise AssertionError(f"{path}: header {lines[:len(HEADER)]}, expected {HEADER}")
    events, last = [], 0
    for number, line in enumerate(lines[len(HEADER):], len(HEADER) + 1):
        time_ns, name, level = line.split()
        time_ns, level = int(time_ns), int(level)
        if name not in SIGNALS or level not in (0, 1) or time_ns < last:
            raise AssertionError(f"{path}:{number}: bad line '{line}'")
        last = time_ns
        events.append((time_ns, name, level))
    return events


def decode(events, dir_negative_level):
    """Positions, step ticks, pulse and set-up problems, pen changes."""
    level = {}
    dir_changed = {"X": -10**18, "Y": -10**18}
    rise = {}
    position = {"X": 0, "Y": 0}
    step_times, problems, pen_changes = set(), [], 0
    for time_ns, name, value in events:
        axis = name[0]
        if name.endswith("_STEP") and value == 1 and level.get(name) == 0:
            if level.get(f"{axis}_EN") != 0:
                problems.append(f"{time_ns} ns: {name} while the driver is disabled")
            if time_ns - dir_changed[axis] < MIN_DIR_SETUP_NS:
                problems.append(f"{time_ns} ns: {axis}_DIR set {time_ns - dir_changed[axis]} ns "
                                f"before the step")
            rise[axis] = time_ns
            step_times.add(time_ns)
            negative = level.get(f"{axis}_DIR") == dir_negative_level
            position[axis] += -1 if negative else 1
        elif name.endswith("_STEP") and value == 0 and axis in rise:
            if time_ns - rise[axis] < MIN_PULSE_NS:
                problems.append(f"{time_ns} ns: {name} high for {time_ns - rise[axis]} ns")
            del rise[axis]
        elif name.endswith("_DIR") and level.get(name) is not None and level[name] != value:
            dir_changed[axis] = time_ns
        elif name == "PEN" and name in level and level[name] != value:
            pen_changes += 1
        level[name] = value
    return position, len(step_times), problems, pen_changes


def read_pairs(text):
    pairs = {}
    for line in text.splitlines():
        if line.strip():
            key, value = line.split(None, 1)
            pairs[key] = value.strip()
    return pairs


def read_measures(path):
    with open(path, encoding="ascii") as f:
        rows = [line.split("\t") for line in f.read().splitlines()[1:]]
    return {row[0]: float(row[1]) for row in rows}


def run_board(args, waveform, measures, socket_path):
    harness = subprocess.Popen(
        ["timeout", "--signal=KILL", "240", sys.executable, HARNESS, "--elf", args.elf,
         "--uart-socket", socket_path, "--waveform", waveform, "--measures", measures,
         "--plugin", args.plugin, "--time-limit-s", "200"],
        stdout=subprocess.PIPE, text=True)
    try:
        if harness.stdout.readline().strip() != "ready":
            raise AssertionError("the harness did not say ready")
        client = subprocess.run([args.client, "--socket", socket_path, "--lines", "3", "--fit",
                                 "6", "--timeout-s", "120", args.job],
                                capture_output=True, text=True, timeout=150)
        sys.stdout.write(client.stdout)
        if client.returncode != 0:
            raise AssertionError(f"the client failed ({client.returncode}): {client.stderr}")
        return read_pairs(client.stdout)
    finally:
        harness.send_signal(signal.SIGTERM)
        harness.wait(timeout=60)
        if harness.returncode != 0:
            raise AssertionError(f"the harness exited {harness.returncode}")


def check(status, events, measures):
    position, ticks, problems, pen_changes = decode(events, dir_negative_level=1)
    expected = {"X": int(status["position_x"]), "Y": int(status["position_y"])}
    failures = problems[:5]
    if position != expected:
        failures.append(f"steps decoded to {position}, the device reports {expected}")
    if ticks != int(status["moves"]) or ticks == 0:
        failures.append(f"{ticks} step ticks on the pins, the device reports {status['moves']}")
    if pen_changes < 2:
        failures.append(f"the pen changed {pen_changes} times")
    wrong_polarity, _, _, _ = decode(events, dir_negative_level=0)
    if wrong_polarity == expected:
        failures.append("the check of the check: the opposite DIR polarity also matches")
    for name, bound in (("fault", 0), ("rx_overruns", 0), ("late_moving_ticks", 0)):
        if measures[name] > bound:
            failures.append(f"measure {name} = {measures[name]:g}")
    if not 0 < measures["stack_high_water_bytes"] < measures["stack_space_bytes"]:
        failures.append(f"stack high-water {measures['stack_high_water_bytes']:g} B")
    if int(status["tick_hz"]) != measures["tick_hz"]:
        failures.append(f"HELLO's tick rate {status['tick_hz']} != the board's")
    return failures, position, ticks


def main():
    p = argparse.ArgumentParser()
    for name in ("--elf", "--client", "--plugin", "--job", "--out"):
        p.add_argument(name, required=True)
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    waveform = os.path.join(args.out, "waveform.txt")
    measures = os.path.join(args.out, "measures.tsv")
    socket_path = os.path.join(args.out, f"uart-{os.getpid()}.sock")
    start = time.monotonic()
    status = run_board(args, waveform, measures, socket_path)
    failures, position, ticks = check(status, read_waveform(waveform), read_measures(measures))
    print(f"waveform: {ticks} step ticks, end position {position}; "
          f"{time.monotonic() - start:.1f} s; measures in {measures}")
    for failure in failures:
        print(f"FAIL: {failure}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
