#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Homing a board against its emulator's endstops, end to end (docs/boards.md).

  run_homing_e2e.py --fdsurf build/fdsurf --relay tests/boards/serial_relay.py \\
      --job examples/bezier-bump.json \\
      --harness build/boards/mega2560-ramps/host/fdsurf_simavr_board --elf FILE.elf

The harness runs the image with a simulated carriage START_X, START_Y steps
above its min switches (--endstop-start) and the relay puts its UART on a
pty LINK. Then, each one a separate `fdsurf` process that opens the link
anew (the board must keep its state between them: it is not reset):

1. `fdsurf stream JOB --require-homing` (and --stream-args) on the unhomed
   board: refused, exit 3, a message naming "not homed";
2. `fdsurf machine home --travel ...`: exit 0;
3. `fdsurf machine where`: position 0, 0 steps, homed xy;
4. the harness is stopped and its recording is read: on each axis the
   STEP pulses went START steps towards the switch (DIR high; with
   --switch-late-steps N up to N more, for a harness whose switch closes
   late), then exactly the back-off away from it, and nothing else; the
   harness's carriage says it ended at the back-off (less the steps past the
   switch); the board started once (measures: boots 1, where counted).

Scenario `hardlimit` instead starts the carriage 40 steps past its X min
switch (the board counts 0 there, unhomed, as after a carriage pushed by
hand), then `fdsurf machine goto 10 5` (away from the switch: allowed) and
`fdsurf machine goto 0 0`: X reaches its switch at counted step 40 and the
board stops there (kEndstopHit): exit 3 with "X min endstop hit during
motion at step 40"; the recording shows X 200 steps out and exactly 160
back, no step past the switch; `fdsurf machine where` then reports X at
step 40, homed none.

The expected step counts come from this driver's own parameters, not from
the firmware. Every process runs under a timeout. Exit 0 pass, 1 fail.
"""
import argparse
import os
import re
import shlex
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run_e2e  # noqa: E402  (the processes, the relay's start, the waveform reader)
from run_e2e import Failure  # noqa: E402

BAUD = 115200
STEP_MM = 0.05  # 20 steps per mm
TRAVEL = "40x30"  # 800 x 600 steps: the search budget is 901 x 676 steps
RATE_MM_S = 10  # 200 steps/s, 1/10 of the board's tick rate
BACKOFF_MM = 1  # 20 steps
AXES = ("X", "Y")


def machine(args, processes, name, action, extra, timeout_s):
    """`fdsurf machine ACTION` on the link with the test's machine settings;
    returns (exit code, its output)."""
    command = [args.fdsurf, "machine", action, "--device", "serial:%s:%d" % (args.link, BAUD),
               "--step", str(STEP_MM), "--travel", TRAVEL] + extra
    code = run_e2e.run_logged(processes, name, command, timeout_s)
    with open(os.path.join(processes.workdir, name + ".log")) as f:
        return code, f.read()


def refused_unhomed(args, processes):
    command = [args.fdsurf, "stream", args.job, "--device", "serial:%s:%d" % (args.link, BAUD),
               "--step", str(STEP_MM), "--travel", TRAVEL, "--fit", "20x15", "--lines", "2",
               "--require-homing", "-q"] + shlex.split(args.stream_args)
    code = run_e2e.run_logged(processes, "unhomed", command, 120)
    with open(os.path.join(processes.workdir, "unhomed.log")) as f:
        output = f.read()
    if code != 3 or "not homed" not in output:
        raise Failure("a --require-homing job on the unhomed board: exit %d, expected 3 with "
                      "'not homed' in: %s" % (code, output.strip()[-300:]))
    print("run_homing_e2e: ok: an unhomed board refuses a --require-homing job (exit 3)")


def steps_by_direction(transitions, axis):
    """The runs of STEP rising edges on `axis`: [(negative, count), ...]."""
    runs, dir_level, step_level = [], 0, 0
    for _, name, level in transitions:
        if name == axis + "_DIR":
            dir_level = level
        elif name == axis + "_STEP":
            if level == 1 and step_level == 0:
                negative = dir_level == 1
                if runs and runs[-1][0] == negative:
                    runs[-1] = (negative, runs[-1][1] + 1)
                else:
                    runs.append((negative, 1))
            step_level = level
    return runs


def check_recording(rec, starts, backoff_steps, late_steps):
    """Each axis stepped its start (plus at most `late_steps` past the switch,
    for a harness whose switch closes late) towards the switch, then exactly
    the back-off away: the steps past it, per axis."""
    header, transitions = run_e2e.read_transitions(rec)
    if run_e2e.header_value(header, "dir_negative_level") != ["1"]:
        raise Failure("%s: expected '# dir_negative_level 1'" % rec)
    past = []
    for axis, start in zip(AXES, starts):
        runs = steps_by_direction(transitions, axis)
        towards = runs[0][1] - start if len(runs) == 2 and runs[0][0] else -1
        expected = [(True, start + max(towards, 0)), (False, backoff_steps)]
        if runs != expected or not 0 <= towards <= late_steps:
            raise Failure("%s's steps were %s (negative?, count), expected %d towards the "
                          "switch (up to %d more, the harness's switch latency) and %d back off"
                          % (axis, runs, start, late_steps, backoff_steps))
        past.append(towards)
        print("run_homing_e2e: ok: %s stepped %d towards its switch (%d past it), stopped, backed "
              "off %d" % (axis, start + towards, towards, backoff_steps))
    return past


def hard_limit(args, processes, rec):
    """Scenario hardlimit (the carriage started at --start -40,10): the board
    stops where it reads the switch, at counted step 40 (less the steps the
    harness's switch may close late, --switch-late-steps)."""
    code, output = machine(args, processes, "out", "goto", ["10", "5"], 60)
    if code != 0:
        raise Failure("goto 10 5 (away from the triggered switch) exited with %d: %s" %
                      (code, output.strip()[-300:]))
    code, output = machine(args, processes, "back", "goto", ["0", "0"], 60)
    found = re.search(r"X min endstop hit during motion at step (\d+): the position is lost; "
                      r"home the machine \(fdsurf machine home\)", output)
    at = int(found.group(1)) if found else None
    if code != 3 or at is None or not 40 - args.switch_late_steps <= at <= 40:
        raise Failure("goto 0 0 into the X switch: exit %d, expected 3 and 'X min endstop hit "
                      "during motion at step 40' (down to %d with a late switch) in: %s" %
                      (code, 40 - args.switch_late_steps, output.strip()[-400:]))
    print("run_homing_e2e: ok: the board stopped at the X switch: %s" % output.strip()[-160:])
    code, output = machine(args, processes, "where", "where", [], 60)
    if code != 0 or "(steps %d," % at not in output or "homed none" not in output:
        raise Failure("fdsurf machine where after the hit said %r (exit %d): expected X at "
                      "step %d, homed none" % (output.strip(), code, at))
    time.sleep(0.3)
    processes.stop("relay")
    if processes.stop("harness") != 0:
        raise Failure("the harness did not exit cleanly after SIGTERM")
    _, transitions = run_e2e.read_transitions(rec)
    runs = steps_by_direction(transitions, "X")
    if runs != [(False, 200), (True, 200 - at)]:
        raise Failure("X's steps were %s (negative?, count), expected 200 out and %d back "
                      "to where the board read its switch, none past it" % (runs, 200 - at))
    print("run_homing_e2e: ok: X went 200 steps out and %d back, none past where the board "
          "read its switch" % (200 - at))


def run(args, processes):
    work = processes.workdir
    rec = os.path.join(work, "rec.wave")
    measures = os.path.join(work, "measures.tsv")
    sock = os.path.join(work, "uart.sock")
    args.link = os.path.join(work, "ttyBOARD")
    starts = [int(v) for v in args.start.split(",")]
    backoff_steps = round(BACKOFF_MM / STEP_MM)
    processes.start("harness", args.harness + [
        "--elf", args.elf, "--uart-socket", sock, "--waveform", rec, "--measures", measures,
        "--time-limit-s", str(args.time_limit_s), "--endstop-start", args.start], 60)
    processes.start("relay", [sys.executable, args.relay, "--socket", sock, "--link",
                              args.link], 30)
    time.sleep(0.2)
    if args.scenario == "hardlimit":
        return hard_limit(args, processes, rec)
    refused_unhomed(args, processes)
    code, output = machine(args, processes, "home", "home",
                           ["--rate", str(RATE_MM_S), "--backoff", str(BACKOFF_MM)], 120)
    if code != 0:
        raise Failure("fdsurf machine home exited with %d: %s" % (code, output.strip()[-300:]))
    code, output = machine(args, processes, "where", "where", [], 60)
    expected = "(steps 0, 0)"  # homing sets the position at the back-off's end to 0
    if code != 0 or expected not in output or "homed xy" not in output:
        raise Failure("fdsurf machine where (a new connection) exited with %d and said %r: "
                      "expected %s and 'homed xy'" % (code, output.strip(), expected))
    print("run_homing_e2e: ok: a second connection finds the board homed at 0, 0")
    time.sleep(0.3)
    processes.stop("relay")
    if processes.stop("harness") != 0:
        raise Failure("the harness did not exit cleanly after SIGTERM")
    past = check_recording(rec, starts, backoff_steps, args.switch_late_steps)
    with open(os.path.join(work, "harness.log")) as f:
        carriage = re.findall(r"carriage X (-?\d+) Y (-?\d+)", f.read())
    expected = [(str(backoff_steps - past[0]), str(backoff_steps - past[1]))]
    if carriage != expected:
        raise Failure("the harness's carriage ended at %s, expected X %s Y %s" %
                      (carriage, expected[0][0], expected[0][1]))
    boots = run_e2e.read_measures(measures).get("boots")
    if boots is not None and boots != 1:  # a harness that counts boots (simavr's)
        raise Failure("the board started %s times: reset between the connections?" % boots)
    print("run_homing_e2e: ok: the carriage rests %s, %s steps off the switches%s" %
          (expected[0][0], expected[0][1], "; one boot" if boots is not None else ""))


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fdsurf", required=True)
    parser.add_argument("--relay", required=True)
    parser.add_argument("--job", required=True, help="a patch file (refused unhomed)")
    parser.add_argument("--elf", required=True)
    parser.add_argument("--stream-args", default="",
                        help="more fdsurf stream options for the unhomed job, one string "
                             "(--prepare-on-host for a board without a planner, the Uno)")
    parser.add_argument("--scenario", choices=("home", "hardlimit"), default="home")
    parser.add_argument("--start",
                        help="steps from each min switch at start, X,Y (default 300,200; "
                             "hardlimit: -40,10)")
    parser.add_argument("--time-limit-s", type=int, default=200)
    parser.add_argument("--switch-late-steps", type=int, default=0,
                        help="steps a carriage may make past a switch before the harness "
                             "closes it (0: exact, simavr's; QEMU's harness drives it from "
                             "outside the emulator, a few ms late)")
    parser.add_argument("--workdir", help="keep the files here (default: a temporary folder)")
    parser.add_argument("--harness", nargs=argparse.REMAINDER, required=True)
    args = parser.parse_args()
    if args.start is None:
        args.start = "-40,10" if args.scenario == "hardlimit" else "300,200"
    return run_e2e.run_in_workdir(run, args, args.workdir, "fdsurf-homing-e2e-",
                                  "run_homing_e2e")

if __name__ == "__main__":
    sys.exit(main())
