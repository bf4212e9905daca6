#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""One reference board end to end under its emulator (docs/boards.md).

  run_e2e.py --board mega2560-ramps --fdsurf build/fdsurf \\
      --checker build/tests/boards/fdsurf_waveform_check \\
      --relay tests/boards/serial_relay.py --job examples/bezier-bump.json \\
      [--scenario plain|stop|hangup|corrupt] [--job-args "--fit 20x15 --speed 20"] \\
      --harness build/boards/mega2560-ramps/host/fdsurf_simavr_board --elf FILE.elf

1. the simulated plotter runs the job at the board's tick rate and writes the
   reference waveform (`fdsurf stream JOB --device sim --waveform ref.wave`);
2. the harness starts the board (--elf, --uart-socket, --waveform rec.wave)
   and the relay puts its UART on a kernel pty behind a symlink;
3. the real host tool streams the same job with the same options to
   `--device serial:LINK:BAUD`;
4. the harness is stopped (SIGTERM: it writes the waveform) and the checker
   compares rec.wave with ref.wave.

Scenarios: plain; stop (SIGINT to fdsurf mid-job: it sends STOP, waits for
rest, exits 130; the recording must be a prefix of the reference, pen up, at
rest); hangup (the pty disappears mid-job and comes back: every command
once, the same waveform); corrupt (a burst of flipped bytes on the line:
the same waveform). Every process runs under a timeout; on failure the tails
of the logs are printed. Exit 0 pass, 1 fail, 2 bad usage.
"""
import argparse
import os
import select
import shlex
import signal
import subprocess
import sys
import tempfile
import time

# Per board: the tick rate its HELLO reports (the reference runs at it), the
# baud of its UART, the step timing its drivers need (RAMPS: DRV8825, 1.9 µs
# pulse and 650 ns DIR set-up; A4988 elsewhere: 1 µs, 200 ns) and the short
# CI job's options (the speed at most one step per tick; about 6 s of
# machine time).
BOARDS = {
    "mega2560-ramps": {"tick_hz": 2000, "baud": 115200, "min_pulse_ns": 1900,
                       "min_dir_setup_ns": 650,
                       "job_args": "--fit 20x15 --lines 2 --speed 20"},
    "microbit-v1": {"tick_hz": 20000, "baud": 115200, "min_pulse_ns": 1000,
                    "min_dir_setup_ns": 200, "job_args": "--fit 40x30 --lines 2"},
    "standin": {"tick_hz": 10000, "baud": 115200, "min_pulse_ns": 1900,
                "min_dir_setup_ns": 650, "job_args": "--fit 40x30 --lines 2"},
}


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
                                   start_new_session=True)
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
                                  timeout=timeout_s).returncode
        except subprocess.TimeoutExpired:
            raise Failure("%s did not finish within %d s" % (name, timeout_s))


def reference(args, processes, board, ref):
    command = [args.fdsurf, "stream", args.job, "--device", "sim", "--waveform", ref,
               "--tick-hz", str(board["tick_hz"]), "-q"] + args.job_args
    code = run_logged(processes, "reference", command, 120)
    if code != 0:
        raise Failure("the reference run (fdsurf stream --device sim) exited with %d" % code)
    return reference_duration_s(ref)


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


def stream(args, processes, board, link, duration_s):
    """The real host tool over the serial line; STOP mid-job for `stop`."""
    command = [args.fdsurf, "stream", args.job, "--device",
               "serial:%s:%d" % (link, board["baud"]), "-q"] + args.job_args
    timeout_s = int(duration_s * 4 + 90)
    if args.scenario != "stop":
        code = run_logged(processes, "fdsurf", command, timeout_s)
        if code != 0:
            raise Failure("fdsurf stream over serial exited with %d" % code)
        return
    with open(processes.log_path("fdsurf"), "w") as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
        time.sleep(args.stop_after_s if args.stop_after_s else 2 + duration_s * 0.4)
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


def run(args, processes):
    board = dict(BOARDS[args.board])
    if args.tick_hz:
        board["tick_hz"] = args.tick_hz
    work = processes.workdir
    ref = os.path.join(work, "ref.wave")
    rec = os.path.join(work, "rec.wave")
    sock = os.path.join(work, "uart.sock")
    link = os.path.join(work, "ttyBOARD")
    duration_s = reference(args, processes, board, ref)
    harness = args.harness + ["--elf", args.elf, "--uart-socket", sock, "--waveform", rec,
                              "--time-limit-s", str(int(duration_s * 4 + 120))]
    processes.start("harness", harness, 60)
    processes.start("relay", [sys.executable, args.relay, "--socket", sock, "--link", link]
                    + relay_options(args), 30)
    time.sleep(args.settle_s)
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
    if args.scenario == "stop":
        check.append("--prefix")
    code = run_logged(processes, "check", check, 300)
    with open(os.path.join(work, "check.log")) as f:
        sys.stdout.write(f.read())
    if code != 0:
        raise Failure("the recorded waveform differs from the reference (checker exit %d)" % code)


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
                        choices=["plain", "stop", "hangup", "corrupt"])
    parser.add_argument("--tick-hz", type=int, help="override the board's tick rate")
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


def main():
    args = parse()
    workdir = args.workdir or tempfile.mkdtemp(prefix="fdsurf-e2e-%s-%s-" % (args.board,
                                                                             args.scenario))
    os.makedirs(workdir, exist_ok=True)
    processes = Processes(workdir)
    try:
        run(args, processes)
        print("run_e2e: %s %s: PASS (files in %s)" % (args.board, args.scenario, workdir))
        return 0
    except Failure as failure:
        processes.stop_all()
        processes.print_tails()
        print("run_e2e: %s %s: FAIL: %s (files in %s)" % (args.board, args.scenario, failure,
                                                           workdir))
        return 1
    finally:
        processes.stop_all()


if __name__ == "__main__":
    sys.exit(main())
