#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The firmware as a USB gadget of a real Linux kernel, the host tool on the
same kernel's host side (dummy_hcd), one QEMU boot per test.

  kernel_test.py --class acm|ffs --case stream|rebind|silent
                 --fdsurf HOST_FDSURF --kernel VMLINUZ --initrd BASE.cpio
                 --examples DIR

stream  the bump and a small teapot: what the gadget's Device drew (steps per
        axis, final position, digest of every step and pen change in order)
        equals what the simulated plotter drew for the same job (its
        waveform, from `fdsurf stream --device sim --waveform` on this host);
        every command executed once.
rebind  the teapot, with the gadget unbound from and bound again to the UDC
        (its configfs UDC file) mid-stream: the host reattaches and resumes;
        the same drawing, every command executed once.
silent  a gadget that reads and never answers: fdsurf exits 3 with an error
        naming the device, within its --connect-timeout, no hang.
machine `fdsurf machine` commands one after the other on the same gadget
        (where, pen down, pen up, goto, jog, where, motors off): each answers
        with the position the gadget's Device reports, the gadget keeps it
        between invocations, and its steps are those of the moves asked.
Exits 0 when every check holds; else prints what differed and the guest's
console tail and exits 1.
"""
import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import run_guest  # noqa: E402

VID_PID = "1209:0001"
# Small enough for TCG: the bump's 4 patches with 3 isolines, the teapot's
# 32 patches with 2 isolines each way.
JOBS = {
    "bump": ["bezier-bump.json", "--lines", "3"],
    "teapot": ["teapot.bpt", "--lines", "2"],
}
TICK_HZ = 20000
SPEEDUP = 20

GADGET_COMMON = """
bind() {  # the UDC refuses a bind while a previous unbind is still settling
  i=0
  until echo $UDC > $G/UDC 2>/dev/null; do
    i=$((i + 1)); [ $i -lt 40 ] || { echo "FDSURF-ERROR cannot bind to $UDC"; return 1; }
    sleep 0.1
  done
}
G=/sys/kernel/config/usb_gadget/fdsurf
mkdir $G
echo 0x1209 > $G/idVendor
echo 0x0001 > $G/idProduct
mkdir $G/strings/0x409
echo FDSURF-KERNEL-1 > $G/strings/0x409/serialnumber
echo fdsurf > $G/strings/0x409/manufacturer
echo "fdsurf plotter (gadget)" > $G/strings/0x409/product
mkdir $G/configs/c.1
UDC=$(ls /sys/class/udc)
wait_for() {  # wait_for FILE SECONDS
  i=0
  while [ ! -e "$1" ] && [ $i -lt $(($2 * 20)) ]; do sleep 0.05; i=$((i + 1)); done
  [ -e "$1" ] || { echo "FDSURF-ERROR $1 did not appear within $2 s"; return 1; }
}
report() {  # report PREFIX FILE
  while read -r key value; do echo "FDSURF-RESULT $1$key $value"; done < "$2"
}
"""

ACM_SETUP = """
mkdir $G/functions/acm.usb0
ln -s $G/functions/acm.usb0 $G/configs/c.1/
start_gadget() {
  fdsurf_gadget_device --acm /dev/ttyGS0 --report /tmp/report --tick-hz %(tick_hz)d \
    --speedup %(speedup)d $1 > /tmp/ready &
  GADGET=$!
  wait_for /dev/ttyGS0 5
  bind
  wait_for /sys/bus/usb/devices/1-1 10
  wait_for /dev/ttyACM0 10
}
DEVICE=serial:/dev/ttyACM0
GONE=/sys/bus/usb/devices/1-1
"""

FFS_SETUP = """
mkdir $G/functions/ffs.fdsurf
ln -s $G/functions/ffs.fdsurf $G/configs/c.1/
mkdir -p /dev/ffs
mount -t functionfs fdsurf /dev/ffs
start_gadget() {
  fdsurf_gadget_device --ffs /dev/ffs --report /tmp/report --tick-hz %(tick_hz)d \
    --speedup %(speedup)d $1 > /tmp/ready &
  GADGET=$!
  i=0
  while ! grep -q ready /tmp/ready 2>/dev/null && [ $i -lt 100 ]; do sleep 0.05; i=$((i+1)); done
  bind
  wait_for /sys/bus/usb/devices/1-1:1.0 10
  echo "FDSURF-RESULT endpoints $(cd /sys/bus/usb/devices/1-1:1.0 && echo ep_*)"
  sleep 0.3
}
DEVICE=usb:%(vid_pid)s
GONE=/sys/bus/usb/devices/1-1
"""


def stream_command(job, device, extra=""):
    args = " ".join(f"'{a}'" if not a.startswith("-") else a for a in JOBS[job][1:])
    return (f"fdsurf stream '/examples/{JOBS[job][0]}' {args} --tick-hz {TICK_HZ} "
            f"--device {device} {extra}")


def stop_gadget(prefix):
    # Unbound first, then stopped: a FunctionFS gadget whose ep0 closes while
    # bound is torn down by the kernel on its own, and the next bind could
    # meet that teardown half done.
    return f"""
echo "" > $G/UDC
i=0
while [ -e $GONE ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i+1)); done
kill $GADGET; wait $GADGET
report {prefix} /tmp/report
rm -f /tmp/report
"""


def scenario(klass, case):
    setup = (ACM_SETUP if klass == "acm" else FFS_SETUP) % {
        "tick_hz": TICK_HZ, "speedup": SPEEDUP, "vid_pid": VID_PID}
    body = [GADGET_COMMON, setup]
    if case == "stream":
        for job in JOBS:
            body.append(f"""
start_gadget
{stream_command(job, "$DEVICE")} 2> /tmp/stderr
echo "FDSURF-RESULT {job}.exit $?"
echo "FDSURF-RESULT {job}.stderr $(tail -n 1 /tmp/stderr)"
{stop_gadget(job + ".")}""")
    elif case == "rebind":
        body.append(f"""
start_gadget
{stream_command("teapot", "$DEVICE", "--reconnect-timeout 20")} 2> /tmp/stderr &
HOST=$!
i=0
while ! grep -q "^executed [1-9]" /tmp/report 2>/dev/null && [ $i -lt 200 ]; do
  kill -USR1 $GADGET 2>/dev/null; sleep 0.05; i=$((i+1))
done
sleep 1
rm -f /tmp/report; kill -USR1 $GADGET; sleep 0.2
echo "FDSURF-RESULT executed_at_unbind $(sed -n 's/^executed //p' /tmp/report)"
echo "" > $G/UDC
echo "FDSURF-RESULT unbound 1"
i=0
while [ -e $GONE ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i+1)); done
sleep 0.5
bind
wait $HOST
echo "FDSURF-RESULT teapot.exit $?"
echo "FDSURF-RESULT teapot.stderr $(tr '\\r' '\\n' < /tmp/stderr | grep -v '^fdsurf: \\[' | tr '\\n' '|')"
{stop_gadget("teapot.")}""")
    elif case == "machine":
        body.append("start_gadget")
        for index, command in enumerate(MACHINE_COMMANDS):
            body.append(
                f"fdsurf machine {command} --device $DEVICE --travel 100x80 > /tmp/out 2> /tmp/stderr\n"
                f'echo "FDSURF-RESULT machine{index}.exit $?"\n'
                f"echo \"FDSURF-RESULT machine{index}.out $(tr '\\n' '|' < /tmp/out)\"\n"
                f"echo \"FDSURF-RESULT machine{index}.stderr $(tr '\\n' '|' < /tmp/stderr)\"")
        body.append(stop_gadget("machine."))
    else:
        body.append(f"""
start_gadget --never-answer
{stream_command("bump", "$DEVICE", "--connect-timeout 2")} 2> /tmp/stderr
echo "FDSURF-RESULT bump.exit $?"
echo "FDSURF-RESULT bump.stderr $(tr '\\n' '|' < /tmp/stderr)"
{stop_gadget("bump.")}""")
    return "\n".join(body)


# The machine case's commands and what each must print (a part of its
# output; 80 steps per mm, the tool's default step of 0.0125 mm).
MACHINE_COMMANDS = ["where", "pen down", "pen up", "goto 10 5", "jog 2 -1", "where", "motors off"]
MACHINE_OUTPUTS = [
    "position x 0, y 0 mm (steps 0, 0); pen up; motors off",
    "(steps 0, 0); pen down; motors off",
    "(steps 0, 0); pen up; motors off",
    "position x 10, y 5 mm (steps 800, 400); pen up; motors on",
    "position x 12, y 4 mm (steps 960, 320); pen up; motors on",
    "position x 12, y 4 mm (steps 960, 320); pen up; motors on",
    "(steps 960, 320); pen up; motors off",
]


def reference(fdsurf, examples, job, workdir):
    """The simulated plotter's drawing of job: steps, position, digest."""
    wave = workdir / f"{job}.wave"
    command = [fdsurf, "stream", str(examples / JOBS[job][0]), *JOBS[job][1:],
               "--tick-hz", str(TICK_HZ), "--device", "sim", "--waveform", str(wave)]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed: {done.stderr}")
    return fold_waveform(wave)


def fold_waveform(path):
    """Steps, position and digest of a waveform, folded as gadget_device does."""
    fnv = 14695981039346656037
    level = {}
    negative_level = 1
    pen_down_level = 1
    steps = [0, 0]
    position = [0, 0]
    commands = None
    events = []  # (time, kind, axis or pen level)
    for line in path.read_text().splitlines():
        words = line.split()
        if line.startswith("#"):
            if words[1:2] == ["dir_negative_level"]:
                negative_level = int(words[2])
            elif words[1:3] == ["pen", "line"]:
                pen_down_level = int(words[3])
            elif words[1:2] == ["commands"]:
                commands = int(words[2])
            continue
        time, signal, value = int(words[0]), words[1], int(words[2])
        first = signal not in level
        previous = level.get(signal, 0 if signal.endswith("_STEP") else None)
        level[signal] = value
        if signal.endswith("_STEP") and value == 1 and previous == 0:
            axis = "XYZ".index(signal[0])
            negative = level.get(signal[0] + "_DIR") == negative_level
            events.append((time, "step", axis, negative))
        elif signal == "PEN" and not first and value != previous:
            events.append((time, "pen", value == pen_down_level, False))
    digest = fnv
    index = 0
    while index < len(events):
        time, kind, what, negative = events[index]
        if kind == "pen":
            byte = 0x81 if what else 0x80
            index += 1
        else:
            mask = negative_mask = 0
            while index < len(events) and events[index][0] == time and events[index][1] == "step":
                _, _, axis, negative = events[index]
                mask |= 1 << axis
                negative_mask |= (1 << axis) if negative else 0
                steps[axis] += 1
                position[axis] += -1 if negative else 1
                index += 1
            byte = mask | negative_mask << 4
        digest = ((digest ^ byte) * 1099511628211) % (1 << 64)
    return {"steps_x": str(steps[0]), "steps_y": str(steps[1]),
            "position": f"{position[0]},{position[1]}", "digest": f"{digest:016x}",
            "commands": str(commands)}


def check(klass, case, results, references):
    """What differed, as lines; empty when every check holds."""
    problems = []

    def expect(key, wanted):
        got = results.get(key)
        if got != wanted:
            problems.append(f"{key}: {got!r}, expected {wanted!r}")

    if case == "machine":
        for index, wanted in enumerate(MACHINE_OUTPUTS):
            expect(f"machine{index}.exit", "0")
            out = results.get(f"machine{index}.out", "")
            if wanted not in out:
                problems.append(f"machine {MACHINE_COMMANDS[index]}: {out!r} lacks {wanted!r} "
                                f"(stderr {results.get(f'machine{index}.stderr', '')!r})")
        # The moves' steps: 800 + 160 in X, 400 + 80 in Y, and where they end.
        expect("machine.steps_x", "960")
        expect("machine.steps_y", "480")
        expect("machine.position", "960,320")
        expect("machine.pen_down", "0")
        return problems
    jobs = list(JOBS) if case == "stream" else ["teapot"] if case == "rebind" else ["bump"]
    for job in jobs:
        if case == "silent":
            expect(f"{job}.exit", "3")
            stderr = results.get(f"{job}.stderr", "")
            device = "serial /dev/ttyACM0" if klass == "acm" else f"usb {VID_PID}"
            if device not in stderr or "error" not in stderr:
                problems.append(f"{job}.stderr does not name {device} in an error: {stderr!r}")
            expect(f"{job}.executed", "0")
            continue
        expect(f"{job}.exit", "0")
        ref = references[job]
        for key in ("steps_x", "steps_y", "position", "digest"):
            expect(f"{job}.{key}", ref[key])
        expect(f"{job}.executed", ref["commands"])
        expect(f"{job}.accepted", ref["commands"])
        expect(f"{job}.pen_down", "0")
        expect(f"{job}.idle", "1")
    if case == "rebind":
        expect("unbound", "1")
        at_unbind = results.get("executed_at_unbind", "")
        if not (at_unbind.isdigit() and 0 < int(at_unbind) < int(references["teapot"]["commands"])):
            problems.append(f"unbound after {at_unbind!r} commands executed: not mid-stream")
        # The gadget saw the unbind: FunctionFS ENABLEs again; the ACM tty hangs
        # up (once, or again when reopened before the bind came back).
        if klass == "ffs":
            expect("teapot.enables", "2")
        elif results.get("teapot.hangups", "0") in ("", "0"):
            problems.append("teapot.hangups: the gadget's tty never hung up")
        expect("teapot.duplicates", "0")
        stderr = results.get("teapot.stderr", "")
        if "resum" not in stderr and "reconnect" not in stderr and "back" not in stderr:
            problems.append(f"teapot.stderr says nothing of the reattach: {stderr!r}")
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--class", dest="klass", choices=["acm", "ffs"], required=True)
    parser.add_argument("--case", choices=["stream", "rebind", "silent", "machine"],
                        required=True)
    parser.add_argument("--fdsurf", required=True)
    parser.add_argument("--kernel", required=True)
    parser.add_argument("--initrd", required=True)
    parser.add_argument("--examples", required=True, type=Path)
    parser.add_argument("--timeout", type=float, default=100)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        workdir = Path(temporary)
        references = {job: reference(args.fdsurf, args.examples, job, workdir) for job in JOBS}
        script = workdir / "scenario.sh"
        script.write_text(scenario(args.klass, args.case))
        files = [(str(args.examples / JOBS[job][0]), f"examples/{JOBS[job][0]}") for job in JOBS]
        code, results, console = run_guest.boot(args.kernel, args.initrd, script, files,
                                                args.timeout)
    for key, value in sorted(results.items()):
        print(f"{key} {value}")
    problems = [] if code == 0 else [f"the scenario exited {code} (None: no FDSURF-EXIT)"]
    problems += check(args.klass, args.case, results, references)
    if problems:
        print("\n".join(["FAILED:"] + problems + ["console tail:", run_guest.tail(console)]))
        sys.exit(1)
    print(f"kernel {args.klass} {args.case}: every check holds ({results['_seconds']} s)")


if __name__ == "__main__":
    main()
