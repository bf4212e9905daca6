#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""One reference board end to end under its emulator (docs/boards.md).

  run_e2e.py --board mega2560-ramps --fdsurf build/fdsurf \\
      --checker build/tests/boards/fdsurf_waveform_check \\
      --relay tests/boards/serial_relay.py --job examples/bezier-bump.json \\
      [--scenario plain|stop|hangup|corrupt] [--job-args "--fit 20x15 --speed 20"] \\
      --harness build/boards/mega2560-ramps/host/fdsurf_simavr_board --elf FILE.elf

1. the harness starts the board (--elf, --uart-socket, --waveform rec.wave,
   --measures measures.tsv) and the relay puts its UART on a kernel pty
   behind a symlink LINK;
2. `fdsurf ports --probe LINK` sends HELLO through the relay: the board's
   tick rate;
3. the simulated plotter runs the job at that tick rate and writes the
   reference waveform (`fdsurf stream JOB --device sim --waveform ref.wave`);
4. the real host tool streams the same job with the same options to
   `--device serial:LINK:BAUD`;
5. the harness is stopped (SIGTERM: it writes the waveform and the
   measures), the checker compares rec.wave with ref.wave, and the board's
   own promises are checked: its measures (BOARDS' limits: no late tick, no
   fault, the stack fits with margin ...; the measured tick rate is HELLO's),
   every ENABLE released at reset, and a servo pen's pulses exactly the
   profile's widths, one period apart.

Scenarios: plain; stop (SIGINT to fdsurf mid-job: it sends STOP, waits for
rest, exits 130; the recording must be a prefix of the reference, pen up, at
rest); hangup (the pty disappears mid-job and comes back: every command
once, the same waveform); corrupt (a burst of flipped bytes on the line:
the same waveform). Every process runs under a timeout; on failure the tails
of the logs are printed. Exit 0 pass, 1 fail, 2 bad usage.
"""
import argparse
import ctypes
import os
import re
import select
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

SCENARIOS = ("plain", "stop", "hangup", "corrupt")


class Limit:
    """One promise about a harness's measures (its --measures TSV): the value
    `of(measures)` compared with `bound` by `op` ("==", "<=" or ">="), in the
    scenarios listed (default all of them), with why it must hold."""

    def __init__(self, label, op, bound, why, scenarios=SCENARIOS, of=None):
        self.label = label
        self.op = op
        self.bound = bound
        self.why = why
        self.scenarios = scenarios
        self.of = of or (lambda measures: measures[label])

    def holds(self, value):
        return {"==": value == self.bound, "<=": value <= self.bound,
                ">=": value >= self.bound}[self.op]


def stack_margin(high_water, space):
    """The bytes of stack space the painted high-water mark left untouched."""
    return lambda measures: measures[space] - measures[high_water]


# Mega 2560 (fdsurf_simavr_board --measures, boards/mega2560-ramps/README.md).
# The hang-up and the corrupt burst change what arrives, not what the board
# must keep: the relay holds the socket, so the board keeps running (no DTR
# reset under the emulator; a reset would make the resume fail anyway), and
# flipped bytes are refused by the frame check, never executed. So every
# limit holds in every scenario; STOP decelerates within the job's limits.
# What does differ is the step interrupt's worst latency (about 400 cycles
# plain, up to 3 300 of the 8 000-cycle period after a hang-up or a burst, as
# the resent frames arrive together), so the limit is on late ticks, not on it.
MEGA_LIMITS = [
    Limit("late_ticks", "==", 0, "no step interrupt began a period after its compare match"),
    Limit("lost_ticks", "==", 0, "no compare match lost (2000 Hz is the rate it holds)"),
    Limit("watchdog_resets", "==", 0, "the main loop never stalled for the watchdog"),
    Limit("boots", "==", 1, "one start: no reset mid-job (a resume after one is refused)"),
    Limit("stack_high_water", ">=", 512, "the paint was read: the job used the stack"),
    Limit("ram_never_used", ">=", 256, "the stack stays 256 B clear of the static RAM"),
]

# micro:bit v1 (run_qemu.py --measures, boards/microbit-v1/README.md). Late
# or missed ticks at rest (a pen change's wait, a PATCH validation) shift no
# step edge, so only the late ticks while moving count (every scenario shows
# one missed tick at rest, the board does not promise otherwise). The
# receive ring must never overflow while the host streams normally (plain,
# stop); after a hang-up the host resends what was unacknowledged, after a
# corrupt burst what the board refused, in one go, and the 2 KB ring holds
# that too, so the limit is the same there. The relay flips bytes, not the
# line's framing, so no scenario may show a UART error.
MICROBIT_LIMITS = [
    Limit("fault", "==", 0, "no fault handler ran"),
    Limit("late_moving_ticks", "==", 0, "no tick late while moving (a step edge moved)"),
    Limit("rx_overruns", "==", 0, "no received byte dropped by a full ring"),
    Limit("uart_errors", "==", 0, "no framing or overrun error in the UART"),
    Limit("stack_high_water_bytes", ">=", 512, "the paint was read: the job used the stack"),
    Limit("stack margin", ">=", 1024, "1 KB of the stack space never touched",
          of=stack_margin("stack_high_water_bytes", "stack_space_bytes")),
    # The servo's TIMER1 counts µs: its handler reaches the capture 1-2 µs
    # after the compare; more means an edge waited for a masked section,
    # which moves that pulse's width by as much.
    # A period every 20 ms all the time the board ran, however long the
    # scenario (a STOP a tenth of the way in leaves about 1.3 s of them).
    Limit("servo_periods", ">=", 25, "the pen servo's 20 ms periods ran (0.5 s of them)"),
    Limit("servo periods missing", "<=", 2,
          "one period every 20 ms of the emulated time, from reset",
          of=lambda measures: int(measures["emulated_s"] * 50) - measures["servo_periods"]),
    Limit("servo_max_lateness_us", "<=", 3,
          "no servo edge delayed beyond its handler's entry (its width moved)"),
]

# Arduino Uno + CNC Shield v3 (fdsurf_simavr_board --board uno-cnc-shield
# --measures, boards/uno-cnc-shield/README.md): the Mega's promises, on 2 KB
# of RAM, and no received byte lost to a full ring (the firmware counts them
# in GPIOR1). The stack's deepest path (a PREPARED_CURVE's check with the
# step interrupt on top: 522 + 144 bytes by the call graph) leaves about 60
# of the 736 bytes the static RAM leaves it; the runs measured 72 to 114
# bytes never used. 48 catches a change that deepens it by a few dozen.
UNO_LIMITS = [
    Limit("late_ticks", "==", 0, "no step interrupt began a period after its compare match"),
    Limit("lost_ticks", "==", 0, "no compare match lost (2000 Hz is the rate it holds)"),
    Limit("watchdog_resets", "==", 0, "the main loop never stalled for the watchdog"),
    Limit("boots", "==", 1, "one start: no reset mid-job (a resume after one is refused)"),
    Limit("rx_overruns", "==", 0, "no received byte lost to a full ring"),
    Limit("stack_high_water", ">=", 256, "the paint was read: the job used the stack"),
    Limit("ram_never_used", ">=", 160, "the stack stays 160 B clear of the static RAM"),
]

# Per board: the baud of its UART, the step timing its drivers need (RAMPS:
# DRV8825, 1.9 us pulse and 650 ns DIR set-up; A4988 elsewhere: 1 us, 200 ns),
# the pen servo's widths built into the image (us, up and down; None: a pen
# line) and the widths the job's CONFIG gives it (--servo-pulse-up/-down in
# the job's options; None: the image's), the
# limits on its measures (None: its harness writes none), and the short CI
# job's options (about 6 s of machine time, the speed at most one step per
# tick of the board; the tick rate itself comes from the board's HELLO).
BOARDS = {
    "mega2560-ramps": {"baud": 115200, "min_pulse_ns": 1900, "min_dir_setup_ns": 650,
                       "servo_us": (1000, 2000), "job_servo_us": (1200, 1800),
                       "limits": MEGA_LIMITS,
                       "job_args": "--fit 20x15 --lines 2 --speed 20 "
                                   "--servo-pulse-up 1200 --servo-pulse-down 1800"},
    # The Uno has no planner: the host prepares every line (--prepare-on-host)
    # and sends the ones its 64-bit tables cannot hold in pieces; the
    # reference is given the same pieces (--sim-64bit-tables), whose joins
    # make moves of their own. Its job is a short teapot (the teapot's 32
    # patches, 2 t-lines each, on a 20 x 15 mm page, pen delay 50 ms: 9.7 s
    # of machine time for the simulated plotter; the Uno, without turn caps,
    # runs at 607 steps/s at most and takes about 32 s). A new width goes
    # out at the next gating, 512 us before its pulse: within one pulse
    # period and those 512 us, 20.99 ms ("servo_wait_ns"; the checker times
    # the change at that pulse and allows the wait; 24.08 ms before
    # 2026-12-08, when the gating ran at the pulse's compare), so the job's
    # pen delay is longer than that: at 20 ms a first step could come before
    # the pen had moved, on a real machine too. Its servo (Timer2,
    # servo_pwm.h) pulses every 20.48 ms in steps of 16 us: 1800 us is made
    # as 1808, so a width within 10 us (half a step, and the 2 us every
    # board is allowed) of the profile's is exact.
    "uno-cnc-shield": {"baud": 115200, "min_pulse_ns": 1900, "min_dir_setup_ns": 650,
                       "servo_us": (1000, 2000), "job_servo_us": (1200, 1800),
                       "servo_period_ns": 20_480_000, "servo_width_slack_us": 10,
                       "servo_wait_ns": 20_992_000,
                       "reference_args": ["--sim-64bit-tables"],
                       "limits": UNO_LIMITS,
                       "job_args": "--prepare-on-host --fit 20x15 --lines 0x2 --speed 20 "
                                   "--pen-delay 50 --servo-pulse-up 1200 --servo-pulse-down 1800"},
    "microbit-v1": {"baud": 115200, "min_pulse_ns": 1000, "min_dir_setup_ns": 200,
                    "servo_us": (1000, 2000), "job_servo_us": (1200, 1800),
                    "limits": MICROBIT_LIMITS,
                    # QEMU runs the M0 two to three times faster than real
                    # time once it has booted: the STOP a tenth of the way in
                    # by the machine time (at a quarter it came with 2.9 of the
                    # job's 3.0 s drawn).
                    "stop_fraction": 0.1,
                    "job_args": "--fit 40x30 --lines 2 "
                                "--servo-pulse-up 1200 --servo-pulse-down 1800"},
    # 3 lines each way: 5.3 s, so that the STOP (1 s + a quarter of the job
    # after the start) falls well inside it (2 lines took 3.0 s once the
    # device stepped chords, and the STOP, then at 2 s + 40 %, came after the
    # end).
    "standin": {"baud": 115200, "min_pulse_ns": 1900, "min_dir_setup_ns": 650,
                "servo_us": None, "limits": None, "job_args": "--fit 40x30 --lines 3"},
}
# A servo pulse starts every 20 ms (50 Hz; a board's "servo_period_ns" says
# otherwise); under simavr a width written at a
# period's start can shift that start by the interrupt latency, and servos
# take 40-60 Hz anyway. A width within 2 us of the profile's is exact (the
# waveform's 62.5 ns cycle and the rounding to us), or within a board's
# "servo_width_slack_us" where its PWM cannot make the width exactly.
SERVO_PERIOD_NS = 20_000_000
SERVO_PERIOD_SLACK_NS = 1_000_000
SERVO_WIDTH_SLACK_US = 2


PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def die_with_parent():
    """In each child before exec: SIGKILL when this driver ends, however it
    ends (CTest's timeout kills the driver alone), so no emulator, relay or
    fdsurf outlives a run."""
    if ctypes.CDLL(None).prctl(PR_SET_PDEATHSIG, signal.SIGKILL) != 0 or os.getppid() == 1:
        os._exit(127)


class Failure(Exception):
    pass


class Processes:
    """The background processes of a run, their logs, and their clean-up."""

    def __init__(self, workdir):
        self.workdir = workdir
        self.running = []  # (name, Popen)
        self.logs = []

    def log_path(self, name):
        path = os.path.join(self.workdir, name + ".log")
        self.logs.append(path)
        return path

    def start(self, name, command, wait_ready_s):
        """Starts `command`, waits for its `ready` line on stdout."""
        err = open(self.log_path(name), "w")
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=err,
                                   start_new_session=True, preexec_fn=die_with_parent)
        self.running.append((name, process))
        deadline = time.monotonic() + wait_ready_s
        out = process.stdout.fileno()
        seen = b""
        while time.monotonic() < deadline:
            if select.select([out], [], [], 0.05)[0]:
                seen += os.read(out, 4096)
            if b"ready\n" in seen:
                return process
            if process.poll() is not None:
                raise Failure("%s exited with %d before it was ready: %s" %
                              (name, process.returncode, shlex.join(command)))
        raise Failure("%s was not ready within %.0f s: %s" % (name, wait_ready_s,
                                                             shlex.join(command)))

    def stop(self, name, timeout_s=30):
        """SIGTERM, then SIGKILL after timeout_s; returns the exit code."""
        for entry in list(self.running):
            if entry[0] != name:
                continue
            process = entry[1]
            self.running.remove(entry)
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
            try:
                return process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait(5)
                raise Failure("%s did not exit within %d s of SIGTERM" % (name, timeout_s))
        return None

    def stop_all(self):
        for name, _ in list(reversed(self.running)):
            try:
                self.stop(name, 10)
            except Failure as failure:
                print("run_e2e: %s" % failure)

    def print_tails(self, lines=25):
        for path in self.logs:
            if not os.path.exists(path):
                continue
            with open(path, errors="replace") as f:
                tail = f.readlines()[-lines:]
            print("---- %s (last %d lines)" % (path, len(tail)))
            sys.stdout.write("".join(tail))


def run_logged(processes, name, command, timeout_s):
    """Runs to completion under a timeout; returns the exit code."""
    with open(processes.log_path(name), "w") as log:
        log.write("$ %s\n" % shlex.join(command))
        log.flush()
        try:
            return subprocess.run(command, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=timeout_s, preexec_fn=die_with_parent).returncode
        except subprocess.TimeoutExpired:
            raise Failure("%s did not finish within %d s" % (name, timeout_s))


def reference(args, processes, tick_hz, ref):
    """The simulated plotter at the board's tick rate, given the job as the
    board is given it (the board's "reference_args"); returns its machine
    time."""
    command = [args.fdsurf, "stream", args.job, "--device", "sim", "--waveform", ref,
               "--tick-hz", str(tick_hz), "-q"] + args.job_args + \
        BOARDS[args.board].get("reference_args", [])
    code = run_logged(processes, "reference", command, 120)
    if code != 0:
        raise Failure("the reference run (fdsurf stream --device sim) exited with %d" % code)
    return reference_duration_s(ref)


def probe_tick_hz(args, processes, link, baud):
    """The tick rate the board's HELLO reports (`fdsurf ports --probe LINK`)."""
    command = [args.fdsurf, "ports", "--probe", "--baud", str(baud), "--timeout", "5", link]
    code = run_logged(processes, "probe", command, 60)
    with open(os.path.join(processes.workdir, "probe.log")) as f:
        lines = f.read().splitlines()[1:]
    names = {link, os.path.realpath(link)}
    for line in lines:
        answer = re.search(r"fdsurf protocol \d+, \d+ axes, (\d+) Hz ticks", line)
        if line.split()[:1] and line.split()[0] in names and answer:
            return int(answer.group(1))
    raise Failure("no HELLO reply from the board on %s (fdsurf ports --probe exited with %d)" %
                  (link, code))


def reference_duration_s(ref):
    """The reference's machine time (its last line's time)."""
    with open(ref, "rb") as f:
        f.seek(0, os.SEEK_END)
        f.seek(max(f.tell() - 200, 0))
        last = f.read().decode().strip().splitlines()[-1]
    return int(last.split()[0]) * 1e-9


def relay_options(args):
    if args.scenario == "hangup":
        return ["--hangup-after", str(args.disturb_after), "--hangup-for", "1.5"]
    if args.scenario == "corrupt":
        return ["--corrupt-after", str(args.disturb_after), "--corrupt-bytes", "12"]
    return []


def stream_timeout_s(duration_s, factor=4):
    """How long the serial run may take: `factor` x the machine time (4 by
    default), plus connecting."""
    return int(duration_s * factor + 90)


def stream(args, processes, board, link, duration_s):
    """The real host tool over the serial line; STOP mid-job for `stop`."""
    command = [args.fdsurf, "stream", args.job, "--device",
               "serial:%s:%d" % (link, board["baud"]), "-q"] + args.job_args
    timeout_s = stream_timeout_s(duration_s, args.stream_time_factor)
    if args.scenario != "stop":
        code = run_logged(processes, "fdsurf", command, timeout_s)
        if code != 0:
            raise Failure("fdsurf stream over serial exited with %d" % code)
        return
    with open(processes.log_path("fdsurf"), "w") as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT,
                                   preexec_fn=die_with_parent)
        # A quarter of the way in by the machine time (the host needs about a
        # second to connect; a board's "stop_fraction" says otherwise): a
        # STOP that comes before the first move still passes (the recording
        # must be a proper prefix, or nothing), one after the last fails. At
        # 2 s + 40 % the micro:bit, faster with slices, had once finished.
        fraction = board.get("stop_fraction", 0.25)
        time.sleep(args.stop_after_s if args.stop_after_s else 1 + duration_s * fraction)
        if process.poll() is not None:
            raise Failure("fdsurf finished (exit %d) before the STOP" % process.returncode)
        process.send_signal(signal.SIGINT)
        try:
            code = process.wait(60)
        except subprocess.TimeoutExpired:
            process.kill()
            raise Failure("fdsurf did not exit within 60 s of SIGINT (STOP)")
    if code != 130:
        raise Failure("fdsurf exited with %d after SIGINT, expected 130 (stopped)" % code)


def read_measures(path):
    """A harness's measures TSV (a header row, then measure, value, unit ...)."""
    measures = {}
    try:
        with open(path) as f:
            rows = f.read().splitlines()[1:]
    except OSError as error:
        raise Failure("%s: no measures from the harness (%s)" % (path, error.strerror))
    for number, row in enumerate(rows, 2):
        fields = row.split("\t")
        try:
            measures[fields[0]] = float(fields[1])
        except (IndexError, ValueError):
            raise Failure("%s:%d: not 'measure<TAB>value<TAB>...': %r" % (path, number, row))
    return measures


def check_measures(measures, limits, scenario, hello_tick_hz, path):
    """The board's limits for `scenario`, and that the tick rate it measured
    is the one its HELLO reported; returns the lines to print, raises Failure
    listing every limit that does not hold."""
    report, broken = [], []
    for limit in limits:
        if scenario not in limit.scenarios:
            continue
        try:
            value = limit.of(measures)
        except KeyError as key:
            raise Failure("%s: no measure %s (the harness's keys changed?)" % (path, key))
        line = "%s %g (%s %g: %s)" % (limit.label, value, limit.op, limit.bound, limit.why)
        (report if limit.holds(value) else broken).append(line)
    if "tick_hz" not in measures:
        raise Failure("%s: no measure tick_hz" % path)
    if abs(measures["tick_hz"] - hello_tick_hz) >= 0.5:
        broken.append("tick_hz %g, but HELLO reported %d Hz" % (measures["tick_hz"],
                                                                 hello_tick_hz))
    else:
        report.append("tick_hz %g (HELLO's)" % measures["tick_hz"])
    if broken:
        raise Failure("the board's measures (%s) break its limits: %s" % (path,
                                                                          "; ".join(broken)))
    return report


def read_transitions(path):
    """The header lines and the (time_ns, signal, level) lines of a waveform."""
    header, transitions = [], []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            if line.startswith("#"):
                header.append(line.strip())
                continue
            fields = line.split()
            if len(fields) != 3 or fields[2] not in ("0", "1"):
                raise Failure("%s:%d: not '<time_ns> <SIGNAL> <0|1>': %r" % (path, number, line))
            transitions.append((int(fields[0]), fields[1], int(fields[2])))
    return header, transitions


def header_value(header, key):
    """The words after `# KEY` in a waveform header, or None."""
    for line in header:
        words = line[1:].split()
        if words[:1] == [key]:
            return words[1:]
    return None


def check_enable_released(header, transitions):
    """Every ENABLE line starts at its inactive level: the firmware releases
    the motors first thing after a reset."""
    active = int(header_value(header, "enable_active_level")[0])
    first = {}
    for time_ns, name, level in transitions:
        if name.endswith("_EN") and name not in first:
            first[name] = (time_ns, level)
    if not first:
        raise Failure("the recording has no ENABLE line")
    for name, (time_ns, level) in sorted(first.items()):
        if level == active:
            raise Failure("%s starts active (%d at %d ns): the motors are energised before "
                          "the firmware set them up" % (name, level, time_ns))
    return "%s released at reset" % " ".join(sorted(first))


def check_servo(header, transitions, servo_us, job_us=None, pen_lowered=True,
                period_ns=SERVO_PERIOD_NS, width_slack_us=SERVO_WIDTH_SLACK_US):
    """A servo pen: the header names the image's widths `servo_us`; every
    pulse is exactly one of the job's widths (`job_us`, the CONFIG's; None:
    the image's), except the image's pen-up pulses before the first of them
    (the board starts before the CONFIG arrives); pulses start one period
    apart, and both job widths were seen (the pen went down and up), or the
    pen-up width alone when the job was stopped before its pen first went
    down (`pen_lowered` False). `period_ns` and `width_slack_us`: the
    board's period and how close to a width its PWM can come."""
    declared = header_value(header, "pen")
    if declared != ["servo"] + [str(us) for us in servo_us]:
        raise Failure("the recording's header says '# pen %s', the image's 'servo %d %d'" %
                      (" ".join(declared or []), servo_us[0], servo_us[1]))
    image_up_us = servo_us[0]
    servo_us = job_us or servo_us
    seen, rise, last_rise = set(), None, None
    for time_ns, name, level in transitions:
        if name != "SERVO":
            continue
        if level == 1:
            if last_rise is not None and abs(time_ns - last_rise - period_ns) > \
                    SERVO_PERIOD_SLACK_NS:
                raise Failure("servo pulses %d ns apart at %d ns, not %d" %
                              (time_ns - last_rise, time_ns, period_ns))
            rise = last_rise = time_ns
        elif rise is not None:
            width_us = (time_ns - rise) / 1000
            rise = None
            if not seen and abs(width_us - image_up_us) <= width_slack_us:
                continue  # before the CONFIG took effect
            nearest = min(servo_us, key=lambda us: abs(us - width_us))
            if abs(width_us - nearest) > width_slack_us:
                raise Failure("a servo pulse of %.1f us at %d ns: not up/down %s us" %
                              (width_us, last_rise, servo_us))
            seen.add(nearest)
    if seen != (set(servo_us) if pen_lowered else {servo_us[0]}):
        raise Failure("servo pulses of %s us only, expected %s" %
                      (sorted(seen), "both %s" % (servo_us,) if pen_lowered else servo_us[0]))
    if not pen_lowered:
        return "servo pulses %d us every %g ms (stopped before the pen first went down)" % \
            (servo_us[0], period_ns / 1e6)
    return "servo pulses %d/%d us (within %d us) every %g ms" % (servo_us + (width_slack_us,
                                                                           period_ns / 1e6))


def pen_lowered(args, rec):
    """False only for a stop that came before the job's first pen change, as
    the checker counted the recording's pen changes (check.log beside it): a
    slow host can make the emulated board that far behind the wall clock."""
    if args.scenario != "stop":
        return True
    with open(os.path.join(os.path.dirname(rec), "check.log")) as f:
        counted = re.search(r"^recorded .*: \d+ moves, (\d+) pen changes", f.read(), re.M)
    return counted is None or int(counted.group(1)) > 0


def check_board(args, board, rec, measures_path, hello_tick_hz):
    """What the board promises beyond the comparison with the simulator."""
    header, transitions = read_transitions(rec)
    report = [check_enable_released(header, transitions)]
    if board["servo_us"]:
        report.append(check_servo(header, transitions, board["servo_us"],
                                  board.get("job_servo_us"), pen_lowered(args, rec),
                                  board.get("servo_period_ns", SERVO_PERIOD_NS),
                                  board.get("servo_width_slack_us", SERVO_WIDTH_SLACK_US)))
    if board["limits"] is not None:
        report += check_measures(read_measures(measures_path), board["limits"], args.scenario,
                                 hello_tick_hz, measures_path)
    for line in report:
        print("run_e2e: ok: %s" % line)


def run(args, processes):
    """One scenario: board, probe, reference, stream, then the checks."""
    board = BOARDS[args.board]
    work = processes.workdir
    ref = os.path.join(work, "ref.wave")
    rec = os.path.join(work, "rec.wave")
    measures = os.path.join(work, "measures.tsv")
    sock = os.path.join(work, "uart.sock")
    link = os.path.join(work, "ttyBOARD")
    harness = args.harness + ["--elf", args.elf, "--uart-socket", sock, "--waveform", rec,
                              "--time-limit-s", str(args.time_limit_s)]
    if board["limits"] is not None:
        harness += ["--measures", measures]
    processes.start("harness", harness, 60)
    processes.start("relay", [sys.executable, args.relay, "--socket", sock, "--link", link]
                    + relay_options(args), 30)
    time.sleep(args.settle_s)
    tick_hz = probe_tick_hz(args, processes, link, board["baud"])
    duration_s = reference(args, processes, tick_hz, ref)
    needed_s = stream_timeout_s(duration_s, args.stream_time_factor) + 30
    if needed_s > args.time_limit_s:
        raise Failure("the job takes %.0f s of machine time: the harness needs --time-limit-s "
                      "%d or more, not %d" % (duration_s, needed_s, args.time_limit_s))
    stream(args, processes, board, link, duration_s)
    time.sleep(0.5)  # the last pin changes after the last acknowledgement
    processes.stop("relay")
    expected = {"hangup": "hung up after", "corrupt": "corrupted"}.get(args.scenario)
    with open(os.path.join(work, "relay.log")) as f:
        if expected and expected not in f.read():
            raise Failure("the relay's %s never happened (the job sent fewer than %d bytes?)" %
                          (args.scenario, args.disturb_after))
    code = processes.stop("harness")
    if code != 0:
        raise Failure("the harness exited with %s after SIGTERM" % code)
    check = [args.checker, "--reference", ref, "--recorded", rec,
             "--min-pulse-ns", str(board["min_pulse_ns"]),
             "--min-dir-setup-ns", str(board["min_dir_setup_ns"])]
    if "servo_wait_ns" in board:
        check += ["--servo-wait-ns", str(board["servo_wait_ns"])]
    if args.scenario == "stop":
        check.append("--prefix")
    code = run_logged(processes, "check", check, 300)
    with open(os.path.join(work, "check.log")) as f:
        sys.stdout.write(f.read())
    if code != 0:
        raise Failure("the recorded waveform differs from the reference (checker exit %d)" % code)
    check_board(args, board, rec, measures, tick_hz)


def parse():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--board", required=True, choices=sorted(BOARDS))
    parser.add_argument("--elf", default="", help="the board's image")
    parser.add_argument("--fdsurf", required=True)
    parser.add_argument("--checker", required=True, help="fdsurf_waveform_check")
    parser.add_argument("--relay", default=os.path.join(os.path.dirname(__file__),
                                                        "serial_relay.py"))
    parser.add_argument("--job", required=True, help="a patch file")
    parser.add_argument("--job-args",
                        help="fdsurf stream options of both runs, one string (default: the "
                             "board's short job)")
    parser.add_argument("--scenario", default="plain",
                        choices=SCENARIOS)
    parser.add_argument("--time-limit-s", type=int, default=240,
                        help="the harness's own time limit, should this driver die (default "
                             "240 s; a job needs --stream-time-factor x its machine time + 120 s)")
    parser.add_argument("--stream-time-factor", type=float, default=4,
                        help="the host tool may take this many times the simulated plotter's "
                             "machine time (default 4; a CPU-bound board on a whole teapot, or "
                             "several emulators on one machine, need more)")
    parser.add_argument("--disturb-after", type=int, default=600,
                        help="hangup/corrupt: bytes towards the board before it happens")
    parser.add_argument("--stop-after-s", type=float, help="stop: seconds before the SIGINT")
    parser.add_argument("--settle-s", type=float, default=0.2,
                        help="wait after the relay is ready (a board's reset)")
    parser.add_argument("--workdir", help="keep the files here (default: a temporary folder)")
    parser.add_argument("--harness", nargs=argparse.REMAINDER, required=True,
                        help="the harness command (last: everything after it is its)")
    args = parser.parse_args()
    if args.job_args is None:
        args.job_args = BOARDS[args.board]["job_args"]
    args.job_args = shlex.split(args.job_args)
    if not args.harness:
        parser.error("--harness needs a command")
    return args


def run_in_workdir(run_scenario, args, given_workdir, prefix, name):
    """Runs `run_scenario(args, processes)` in `given_workdir` or a temporary
    folder, with every process stopped on the way out: 0 and the temporary
    folder removed when it passed, 1 with the processes' log tails and the
    folder kept for its files when it failed. `name` heads the verdict."""
    workdir = given_workdir or tempfile.mkdtemp(prefix=prefix)
    os.makedirs(workdir, exist_ok=True)
    processes = Processes(workdir)
    try:
        run_scenario(args, processes)
        processes.stop_all()
        print("%s: PASS" % name)
        if not given_workdir:
            shutil.rmtree(workdir, ignore_errors=True)
        return 0
    except Failure as failure:
        processes.stop_all()
        processes.print_tails()
        print("%s: FAIL: %s (files in %s)" % (name, failure, workdir))
        return 1
    finally:
        processes.stop_all()


def main():
    args = parse()
    return run_in_workdir(run, args, args.workdir,
                          "fdsurf-e2e-%s-%s-" % (args.board, args.scenario),
                          "run_e2e: %s %s" % (args.board, args.scenario))

if __name__ == "__main__":
    sys.exit(main())
