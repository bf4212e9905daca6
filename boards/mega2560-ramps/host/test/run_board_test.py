#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Runs the Mega 2560 + RAMPS 1.4 image under fdsurf_simavr_board, streams a
short job into its UART socket with fdsurf_board_stream_client, and checks
the recorded waveform:

- the format (header, known signals, levels 0/1, times never decreasing);
- after reset every ENABLE line comes up high (motors released);
- steps happen on X and Y, each with ENABLE low, a high time of at least
  1.9 us (DRV8825) and its DIR line unchanged for at least 650 ns before it;
- the steps, counted with their DIR level, end where the device's final
  STATUS says it is;
- the servo's pulses are the profile's up and down widths, 20 ms apart;
- the measures (--measures) show no late or lost tick and a stack that fits.

Every subprocess runs under a timeout. Exit 0 when all checks pass.
"""
import argparse
import os
import select
import signal
import subprocess
import sys

SIGNALS = ["X_STEP", "X_DIR", "X_EN", "Y_STEP", "Y_DIR", "Y_EN", "Z_STEP", "Z_DIR", "Z_EN",
           "SERVO"]
MIN_STEP_HIGH_NS = 1900
MIN_DIR_SETUP_NS = 650
SERVO_US = (1000, 2000)


class CheckError(Exception):
    pass


def read_waveform(path):
    """Returns (header lines, [(time_ns, signal, level)])."""
    header, events = [], []
    last = 0
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if line.startswith("#"):
                header.append(line)
                continue
            parts = line.split()
            if len(parts) != 3 or parts[1] not in SIGNALS or parts[2] not in ("0", "1"):
                raise CheckError(f"{path}:{number}: not '<time_ns> <SIGNAL> <0|1>': {line!r}")
            time = int(parts[0])
            if time < last:
                raise CheckError(f"{path}:{number}: time goes back ({time} < {last})")
            last = time
            events.append((time, parts[1], int(parts[2])))
    if not header or header[0] != "# fdsurf-waveform 1":
        raise CheckError(f"{path}: no '# fdsurf-waveform 1' header")
    return header, events


def check_steps(events):
    """Checks each step pulse; returns the net steps per axis."""
    level = {}
    changed = {}
    rise = {}
    net = {"X": 0, "Y": 0, "Z": 0}
    for time, name, value in events:
        axis = name[0]
        if name.endswith("_STEP") and value == 1 and level.get(name) == 0:
            if level.get(axis + "_EN") != 0:
                raise CheckError(f"{name} at {time} ns with {axis}_EN not active (low)")
            setup = time - changed.get(axis + "_DIR", -10**12)
            if setup < MIN_DIR_SETUP_NS:
                raise CheckError(f"{name} at {time} ns only {setup} ns after {axis}_DIR changed")
            rise[name] = time
            net[axis] += -1 if level.get(axis + "_DIR") == 1 else 1
        elif name.endswith("_STEP") and value == 0 and name in rise:
            high = time - rise.pop(name)
            if high < MIN_STEP_HIGH_NS:
                raise CheckError(f"{name} high for {high} ns at {time} ns (< {MIN_STEP_HIGH_NS})")
        if name in level and level[name] == value:
            raise CheckError(f"{name} 'changes' to the level it has at {time} ns")
        if name not in level and name.endswith("_EN") and value != 1:
            raise CheckError(f"{name} starts at {value}: the motors are enabled before set-up")
        level[name] = value
        changed[name] = time
    return net


def check_servo(events):
    """Returns the pulse widths seen, in us, after checking each one."""
    widths = set()
    rise = None
    last_rise = None
    for time, name, value in events:
        if name != "SERVO":
            continue
        if value == 1:
            # Servos take 40-60 Hz; under simavr a width written at the
            # period's start can shift that start by the interrupt latency.
            if last_rise is not None and abs(time - last_rise - 20_000_000) > 1_000_000:
                raise CheckError(f"servo pulses {time - last_rise} ns apart at {time} ns")
            rise = last_rise = time
        elif rise is not None:
            width = round((time - rise) / 1000)
            if not any(abs(width - w) <= 2 for w in SERVO_US):
                raise CheckError(f"servo pulse of {width} us at {time} ns, not up/down {SERVO_US}")
            widths.add(min(SERVO_US, key=lambda w: abs(w - width)))
            rise = None
    return widths


def read_measures(path):
    with open(path) as f:
        rows = [line.rstrip("\n").split("\t") for line in f][1:]
    return {name: float(value) for name, value, _ in rows}


def wait_ready(harness, seconds):
    ready, _, _ = select.select([harness.stdout], [], [], seconds)
    line = harness.stdout.readline() if ready else ""
    if line.strip() != "ready":
        raise CheckError(f"the harness did not print 'ready' within {seconds} s (got {line!r})")


def run(args):
    if not os.path.exists(args.elf):
        raise CheckError(f"{args.elf}: no image (Target.atmega2560.Build makes it)")
    os.makedirs(args.out, exist_ok=True)
    sock = os.path.join(args.out, "uart.sock")
    waveform = os.path.join(args.out, "waveform.txt")
    measures = os.path.join(args.out, "measures.tsv")
    harness = subprocess.Popen(
        [args.harness, "--elf", args.elf, "--uart-socket", sock, "--waveform", waveform,
         "--time-limit-s", str(args.time_limit_s), "--measures", measures],
        stdout=subprocess.PIPE, text=True)
    try:
        wait_ready(harness, 10)
        client = subprocess.run(
            [args.client, "--socket", sock, "--file", args.file, "--patches", str(args.patches),
             "--lines", str(args.lines), "--timeout-s", str(args.client_timeout_s)],
            capture_output=True, text=True, timeout=args.client_timeout_s + 30)
        sys.stdout.write(client.stdout)
        sys.stderr.write(client.stderr)
        if client.returncode != 0:
            raise CheckError(f"the client exited with {client.returncode}")
    finally:
        harness.send_signal(signal.SIGTERM)
        try:
            code = harness.wait(timeout=30)
        except subprocess.TimeoutExpired:
            harness.kill()
            raise CheckError("the harness did not exit within 30 s of SIGTERM")
    if code != 0:
        raise CheckError(f"the harness exited with {code}")
    done = [line for line in client.stdout.splitlines() if line.startswith("done ")]
    final = dict(item.split("=") for item in done[0].split()[1:])
    return waveform, measures, final


def check(waveform, measures, final):
    _, events = read_waveform(waveform)
    net = check_steps(events)
    steps = sum(1 for _, name, value in events if name.endswith("_STEP") and value == 1)
    if steps == 0 or net["X"] == 0 and net["Y"] == 0:
        raise CheckError("no steps recorded")
    if (net["X"], net["Y"]) != (int(final["x"]), int(final["y"])):
        raise CheckError(f"the waveform's steps end at X {net['X']} Y {net['Y']}, the device "
                         f"reports X {final['x']} Y {final['y']}")
    widths = check_servo(events)
    if widths != set(SERVO_US):
        raise CheckError(f"servo pulses seen: {sorted(widths)} us, expected both {SERVO_US}")
    m = read_measures(measures)
    if m["late_ticks"] != 0 or m["lost_ticks"] != 0:
        raise CheckError(f"{m['late_ticks']:.0f} late and {m['lost_ticks']:.0f} lost ticks")
    if m["ram_never_used"] <= 0:
        raise CheckError(f"the stack ({m['stack_high_water']:.0f} bytes) reached the static RAM")
    print(f"ok: {steps} step pulses, end X {net['X']} Y {net['Y']}, servo {sorted(widths)} us, "
          f"tick ISR max {m['tick_isr_cycles_max']:.0f} of {m['tick_period']:.0f} cycles, "
          f"stack {m['stack_high_water']:.0f} bytes")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--harness", required=True)
    parser.add_argument("--client", required=True)
    parser.add_argument("--elf", required=True)
    parser.add_argument("--file", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--patches", type=int, default=2)
    parser.add_argument("--lines", type=int, default=2)
    parser.add_argument("--time-limit-s", type=float, default=600)
    parser.add_argument("--client-timeout-s", type=float, default=180)
    args = parser.parse_args()
    try:
        check(*run(args))
    except (CheckError, subprocess.TimeoutExpired) as e:
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
