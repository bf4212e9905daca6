#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The check of the checker: fdsurf_waveform_check passes the simulated
plotter's waveform against itself and catches each perturbation a broken board
would show (a dropped step, a flipped direction, a too-short pulse, a step
while disabled, motion too fast, a STOP that did not decelerate), and passes a
recording cut at a rest with --prefix.

  check_selftest.py FDSURF CHECKER JOB
"""
import os
import shutil
import subprocess
import sys
import tempfile

JOB_ARGS = ["--fit", "40x30", "--lines", "2", "--tick-hz", "10000"]


def read(path):
    header, data = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                header.append(line)
            else:
                t, signal, level = line.split()
                data.append([int(t), signal, int(level)])
    return header, data


def write(path, header, data):
    with open(path, "w") as f:
        f.writelines(header)
        for t, signal, level in sorted(data, key=lambda d: d[0]):
            f.write("%d %s %d\n" % (t, signal, level))


def edges(data, signal, level=1):
    return [i for i, d in enumerate(data) if d[1] == signal and d[2] == level]


def drop_step(data):
    rise = edges(data, "X_STEP")[len(edges(data, "X_STEP")) // 2]
    del data[rise:rise + 1]
    fall = next(i for i in range(rise, len(data)) if data[i][1] == "X_STEP")
    del data[fall]


def flip_direction(data):
    rise = edges(data, "Y_STEP")[len(edges(data, "Y_STEP")) // 2]
    level = [d[2] for d in data[:rise] if d[1] == "Y_DIR"][-1]
    t = data[rise][0]
    data.append([t - 700, "Y_DIR", 1 - level])
    data.append([t + 2500, "Y_DIR", level])


def short_pulse(data):
    rise = edges(data, "X_STEP")[100]
    fall = next(i for i in range(rise + 1, len(data)) if data[i][1] == "X_STEP")
    data[fall][0] = data[rise][0] + 300


def step_while_disabled(data):
    enable = next(d[0] for d in data if d[1] == "X_EN" and d[0] > 0)
    data.append([enable - 50000, "X_STEP", 1])
    data.append([enable - 48000, "X_STEP", 0])


def too_fast(data):
    for d in data:
        d[0] = d[0] * 4 // 5


def cut(data, at_ns, lift=True):
    """The recording ends at `at_ns` (a STOP that stopped dead), pen lifted."""
    kept = [d for d in data if d[0] < at_ns]
    last = {d[1]: d[2] for d in kept}
    for signal in ("X_STEP", "Y_STEP"):
        if last.get(signal) == 1:
            kept.append([at_ns, signal, 0])
    if lift and last.get("PEN") == 1:
        kept.append([at_ns + 1000, "PEN", 0])
    data[:] = kept


def stopped_mid_stroke(data):
    steps = edges(data, "X_STEP")
    cut(data, data[steps[len(steps) // 2]][0] + 5000)


def cut_at_a_rest(data):
    # Just after a pen-up half way through: the motion was at rest there.
    ups = edges(data, "PEN", 0)
    cut(data, data[ups[len(ups) // 2]][0] + 1000)


CASES = [
    # name, perturbation, --prefix, expected exit, text the output must contain
    ("identical", None, False, 0, "OK"),
    ("dropped step", drop_step, False, 1, "FAIL: move"),
    ("flipped direction", flip_direction, False, 1, "FAIL: move"),
    ("short pulse", short_pulse, False, 1, "high for only 300 ns"),
    ("step while disabled", step_while_disabled, False, 1, "while the motors are disabled"),
    ("too fast", too_fast, False, 1, "motion limits"),
    ("stopped dead mid-stroke", stopped_mid_stroke, True, 1, "before a stop at rest"),
    ("cut at a rest", cut_at_a_rest, True, 0, "a prefix: cut by the STOP"),
    ("truncated without --prefix", cut_at_a_rest, False, 1, "got none"),
]


def main():
    fdsurf, checker, job = sys.argv[1:4]
    work = tempfile.mkdtemp(prefix="fdsurf-check-selftest-")
    ref = os.path.join(work, "ref.wave")
    subprocess.run([fdsurf, "stream", job, "--device", "sim", "--waveform", ref, "-q"] + JOB_ARGS,
                   check=True, timeout=120)
    header, data = read(ref)
    failed = 0
    for name, perturb, prefix, expected, text in CASES:
        rec = os.path.join(work, name.replace(" ", "_") + ".wave")
        copy = [list(d) for d in data]
        if perturb:
            perturb(copy)
        write(rec, header, copy)
        command = [checker, "--reference", ref, "--recorded", rec] + (["--prefix"] if prefix else [])
        result = subprocess.run(command, capture_output=True, text=True, timeout=120)
        output = result.stdout + result.stderr
        ok = result.returncode == expected and text in output
        print("%s: %s (exit %d)" % ("ok  " if ok else "FAIL", name, result.returncode))
        if not ok:
            failed += 1
            print("  expected exit %d and '%s' in:\n%s" % (expected, text, output))
    bad = os.path.join(work, "bad.wave")
    with open(bad, "w") as f:
        f.write("not a waveform\n")
    result = subprocess.run([checker, "--reference", ref, "--recorded", bad], capture_output=True,
                            text=True, timeout=60)
    ok = result.returncode == 2 and bad + ":1: not a waveform" in result.stderr
    print("%s: a file that is not a waveform (exit %d)" % ("ok  " if ok else "FAIL",
                                                          result.returncode))
    failed += 0 if ok else 1
    if failed:
        print("files in %s" % work)
        return 1
    shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
