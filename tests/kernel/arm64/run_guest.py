#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Boots Debian's arm64 kernel under qemu-system-aarch64 -M virt (TCG) with a
tiny initramfs (busybox-static, fdsurf-gpio-stream, a job, an init script) and
checks what the real kernel's GPIO character device did (docs/testing.md,
"GPIO on arm64 under QEMU").

  run_guest.py --scenario stream|serve|errors --cache DIR --streamer BIN --out DIR
               [--job JOB --reference REF --checker CHECK] [--timeout S]

stream: the guest streams JOB on the PL061's lines; every line change is
recorded outside the guest by QEMU's trace events pl061_update and
pl061_set_output, turned into the waveform format (sim/include/fdsurf/sim/
waveform.h) and compared by fdsurf_waveform_check with REF, the simulated
plotter's waveform of the same job.

serve: the same job through `fdsurf serve` on those lines (the second form
of fdsurf-gpio-stream) and a client streaming it through the server's pty
(the third form); the same waveform check, and the server, stopped by
SIGTERM, must say it left the device at rest with the pen lifted and the
drivers disabled, exit 0 and take its link with it.

errors: a line held by another process, a chip and a line that do not exist,
a path that is not a GPIO chip, permission denied (a non-root user after
chmod 600 /dev/gpiochip0), and the line the kernel itself holds (gpio-keys'
power key, when its module is loaded): each must exit 3 with its message.

A boot that fails or hangs past --timeout is killed; the test then fails
with the tail of the guest's console. Exit 0 when everything held, 1 if not.
"""
import argparse
import os
import re
import stat
import subprocess
import sys
import time

# The PL061 of -M virt has 8 lines; line 3 is the power key (the device
# tree's gpio-keys node). STEPX, DIRX, STEPY, DIRY, EN (active low), PEN.
LINES = {"X_STEP": 0, "X_DIR": 1, "Y_STEP": 2, "Y_DIR": 4, "EN": 5, "PEN": 6}
POWER_KEY_LINE = 3
DEVICE = "gpio:gpiochip0:%d,%d,%d,%d,%d,%d" % (
    LINES["X_STEP"], LINES["X_DIR"], LINES["Y_STEP"], LINES["Y_DIR"], LINES["EN"], LINES["PEN"])
RESULT = re.compile(r"^FDSURF-RESULT (\S+) rc=(\d+)$")


# ---- the initramfs (cpio "newc", written here: no cpio tool needed)

def cpio_entry(name, mode, data=b"", nlink=1):
    fields = [1, mode, 0, 0, nlink, 0, len(data), 0, 0, 0, 0, len(name) + 1, 0]
    header = b"070701" + b"".join(b"%08X" % f for f in fields)
    blob = header + name.encode() + b"\0"
    blob += b"\0" * (-len(blob) % 4) + data
    return blob + b"\0" * (-len(blob) % 4)


def write_initramfs(path, files):
    """files: [(name, mode, bytes)] with directories as (name, S_IFDIR|mode, b"")."""
    out = b"".join(cpio_entry(n, m, d) for n, m, d in files)
    out += cpio_entry("TRAILER!!!", 0)
    with open(path, "wb") as f:
        f.write(out)


INIT_COMMON = r"""#!/bin/sh
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t debugfs debugfs /sys/kernel/debug 2>/dev/null
result() { echo "FDSURF-RESULT $1 rc=$2"; }
run() {  # NAME COMMAND...: the command's stderr on the console, then its exit code
  name=$1; shift
  "$@" 2>/tmp/err; rc=$?
  sed "s/^/FDSURF-STDERR $name: /" /tmp/err
  result "$name" "$rc"
}
echo "FDSURF-BOOTED"
ls /dev/gpiochip* | sed 's/^/FDSURF-CHIP /'
[ -r /sys/kernel/debug/gpio ] && sed 's/^/FDSURF-DEBUGFS /' /sys/kernel/debug/gpio
"""

INIT_STREAM = r"""
run stream /bin/fdsurf-gpio-stream /job --device {device} --tick-hz {tick_hz}
echo FDSURF-DONE
poweroff -f
"""

INIT_SERVE = r"""
# `fdsurf serve` on the lines, a client streaming the job through its pty,
# then SIGTERM: the server stops the device, lifts the pen, disables the
# drivers and exits 0. Ptys need devpts, as on any full system.
mkdir -p /dev/pts
mount -t devpts devpts /dev/pts
/bin/fdsurf-gpio-stream serve --device {device} --link /tmp/fdsurf-gpio --tick-hz {tick_hz} 2>/tmp/serve &
server=$!
for i in $(seq 100); do [ -e /tmp/fdsurf-gpio ] && break; sleep 0.1; done
run client /bin/fdsurf-gpio-stream /job --serial /tmp/fdsurf-gpio
kill -TERM $server
wait $server; rc=$?
sed "s/^/FDSURF-STDERR serve: /" /tmp/serve
result serve $rc
[ -e /tmp/fdsurf-gpio ] && echo "FDSURF-STDERR serve: the link outlived the server"
echo FDSURF-DONE
poweroff -f
"""

INIT_ERRORS = r"""
# A line held by another process: a second fdsurf-gpio-stream on the same
# lines while the first streams (it requests them all before its first tick).
/bin/fdsurf-gpio-stream /job --device {device} --tick-hz {tick_hz} --quiet 2>/tmp/holder &
holder=$!
# Until the kernel lists the holder as its lines' consumer (debugfs), 20 s at most.
for i in $(seq 200); do grep -q '|fdsurf' /sys/kernel/debug/gpio && break; sleep 0.1; done
sed 's/^/FDSURF-HELD /' /sys/kernel/debug/gpio
run busy /bin/fdsurf-gpio-stream /job --device {device} --tick-hz {tick_hz}
wait $holder; result holder $?
run no_chip /bin/fdsurf-gpio-stream /job --device gpio:gpiochip9:0,1,2,4,5,6
run no_line /bin/fdsurf-gpio-stream /job --device gpio:gpiochip0:0,1,2,4,5,9
run not_a_chip /bin/fdsurf-gpio-stream /job --device gpio:/dev/null:0,1,2,4,5,6
# The power key's line, once the gpio-keys driver (a module) holds it.
insmod /gpio_keys.ko
run kernel_line /bin/fdsurf-gpio-stream /job --device gpio:gpiochip0:0,1,2,{power_key},5,6
chmod 600 /dev/gpiochip0
run permission su -s /bin/sh nobody -c "/bin/fdsurf-gpio-stream /job --device {device}"
echo FDSURF-DONE
poweroff -f
"""

# What each error case must print (a substring of stderr) and its exit code.
EXPECTED_ERRORS = {
    "busy": (3, "gpio gpiochip0: line 0 (STEPX) is busy: used by 'fdsurf'"),
    "holder": (0, None),
    "no_chip": (3, "gpio: no GPIO chip 'gpiochip9' (chips present: gpiochip0)"),
    "no_line": (3, "gpio gpiochip0: line 9 (PEN) does not exist: the chip has 8 lines (0-7)"),
    "not_a_chip": (3, "gpio: '/dev/null' is not a GPIO chip"),
    "kernel_line": (3, "gpio gpiochip0: line 3 (DIRY) is busy: used by "),
    "permission": (3, "gpio: permission denied opening GPIO chip 'gpiochip0'"),
}


def build_initramfs(args, init_text, path):
    def read(p):
        with open(p, "rb") as f:
            return f.read()
    d = stat.S_IFDIR | 0o755
    x = stat.S_IFREG | 0o755
    r = stat.S_IFREG | 0o644
    files = [(n, d, b"") for n in ("bin", "dev", "proc", "sys", "tmp", "etc")]
    files += [("bin/busybox", x, read(os.path.join(args.cache, "busybox"))),
              ("gpio_keys.ko", r, read(os.path.join(args.cache, "gpio_keys.ko")))]
    for tool in ("sh", "mount", "sed", "ls", "sleep", "chmod", "su", "poweroff", "cat", "insmod",
                 "grep", "seq", "kill", "mkdir"):
        files.append(("bin/" + tool, stat.S_IFLNK | 0o777, b"busybox"))
    files += [("bin/fdsurf-gpio-stream", x, read(args.streamer)),
              ("job", r, read(args.job)),
              ("etc/passwd", r, b"root:x:0:0:root:/:/bin/sh\nnobody:x:65534:65534::/:/bin/sh\n"),
              ("etc/group", r, b"root:x:0:\nnogroup:x:65534:\n"),
              ("init", x, init_text.encode())]
    write_initramfs(path, files)


# ---- the boot

def boot(args, initrd, trace):
    console = os.path.join(args.out, "console.log")
    command = [args.qemu, "-M", "virt", "-cpu", "cortex-a53", "-accel", "tcg", "-m", "512",
               "-smp", "1", "-nographic", "-no-reboot", "-kernel",
               os.path.join(args.cache, "vmlinuz"), "-initrd", initrd,
               "-append", "console=ttyAMA0 rdinit=/init panic=-1 quiet loglevel=3",
               "-msg", "timestamp=on",
               "-trace", "pl061_update,file=" + trace, "-trace", "pl061_set_output,file=" + trace]
    start = time.monotonic()
    with open(console, "wb") as out:
        process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=out,
                                   stderr=subprocess.STDOUT)
        try:
            process.wait(timeout=args.timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            fail_with_console(console, "QEMU still running after %.0f s: killed" % args.timeout)
    with open(console, "rb") as f:
        text = f.read().decode(errors="replace").replace("\r", "")
    print("boot: %.1f s (QEMU exit %d)" % (time.monotonic() - start, process.returncode))
    if "FDSURF-DONE" not in text:
        fail_with_console(console, "the guest did not finish its script")
    return text


def fail_with_console(console, why):
    with open(console, "rb") as f:
        tail = f.read().decode(errors="replace").replace("\r", "").splitlines()[-40:]
    print("FAIL: %s; the guest's console (%s), last %d lines:" % (why, console, len(tail)))
    for line in tail:
        print("  | " + line)
    sys.exit(1)


def results(console_text):
    found = {}
    stderr = {}
    for line in console_text.splitlines():
        m = RESULT.match(line.strip())
        if m:
            found[m.group(1)] = int(m.group(2))
        elif line.startswith("FDSURF-STDERR "):
            name, _, message = line[len("FDSURF-STDERR "):].partition(": ")
            stderr.setdefault(name, []).append(message)
    return found, stderr


# ---- the trace as a waveform

# QEMU 7.2's log backend with -msg timestamp=on (hw/gpio/trace-events):
#   PID@SEC.USEC:pl061_update PATH GPIODIR 0x.. GPIODATA 0x.. pullups 0x.. floating 0x..
#   PID@SEC.USEC:pl061_set_output PATH setting output LINE to LEVEL
TRACE_UPDATE = re.compile(r"^\d+@(\d+)\.(\d+):pl061_update \S+ GPIODIR 0x([0-9a-f]+) "
                          r"GPIODATA 0x([0-9a-f]+)")
TRACE_OUTPUT = re.compile(r"^\d+@(\d+)\.(\d+):pl061_set_output \S+ setting output (\d+) "
                          r"to (-?\d+)")


def trace_events(path):
    """[(time_ns, "dir", mask) | (time_ns, "level", line, level)] in order."""
    events = []
    with open(path) as f:
        for line in f:
            m = TRACE_UPDATE.match(line)
            if m:
                t = int(m.group(1)) * 10**9 + int(m.group(2)) * 1000
                events.append((t, "dir", int(m.group(3), 16)))
                continue
            m = TRACE_OUTPUT.match(line)
            if m:
                t = int(m.group(1)) * 10**9 + int(m.group(2)) * 1000
                events.append((t, "level", int(m.group(3)), int(m.group(4))))
    return events


def waveform_from_trace(events, path):
    """The lines' changes while all of ours are outputs (GPIODIR), as a waveform.

    Levels come from pl061_set_output (the level QEMU drives on the line); the
    recording starts when the last of our lines became an output (the levels
    then are the initial ones: what fdsurf requested) and ends when one stops
    being an output (the lines released)."""
    ours = 0
    for offset in LINES.values():
        ours |= 1 << offset
    level = {}
    transitions = []
    start = None
    for event in events:
        t, kind = event[0], event[1]
        if kind == "level":
            level[event[2]] = event[3]
            if start is not None and event[2] in LINES.values():
                transitions.append((t - start, event[2], event[3]))
        elif start is None and event[2] & ours == ours:
            start = t
            initial = dict(level)
        elif start is not None and event[2] & ours != ours:
            break
    if start is None:
        raise SystemExit("FAIL: the trace never shows all of the lines %s as outputs" % LINES)
    names = {offset: name for name, offset in LINES.items()}
    with open(path, "w") as out:
        out.write("# fdsurf-waveform 1\n# board qemu-virt-pl061\n# dir_negative_level 1\n"
                  "# enable_active_level 0\n# pen line 1\n")

        def emit(t, offset, value):
            for signal in (["X_EN", "Y_EN"] if names[offset] == "EN" else [names[offset]]):
                out.write("%d %s %d\n" % (t, signal, value))
        for offset in sorted(names):
            emit(0, offset, initial.get(offset, 0))
        for t, offset, value in transitions:
            emit(t, offset, value)
    return len(transitions)


def check_waveform(args, trace, messages):
    """The trace's waveform against the simulated plotter's (0 when the same)."""
    recorded = os.path.join(args.out, "recorded.wave")
    changes = waveform_from_trace(trace_events(trace), recorded)
    print("trace: %d line changes while the lines were outputs -> %s" % (changes, recorded))
    check = subprocess.run([args.checker, "--reference", args.reference, "--recorded", recorded],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    print(check.stdout, end="")
    if check.returncode == 0:
        return 0
    # The checker groups STEP edges of different axes less than half a tick
    # apart; a host that stalled the guest longer than that between the two
    # ioctls of one tick splits a diagonal step (docs/testing.md).
    window_ms = 500.0 / args.tick_hz
    for line in messages:
        m = re.search(r"late \(longest ([0-9.]+) ms\)", line)
        if m and float(m.group(1)) > window_ms:
            print("note: the guest's tick loop stalled %s ms, more than the checker's %.1f ms "
                  "grouping window: if the first difference is a diagonal step split in two, "
                  "the host was too loaded for this check" % (m.group(1), window_ms))
    return 1


def check_stream(args, text, trace):
    found, stderr = results(text)
    for line in stderr.get("stream", []):
        print("guest: " + line)
    if found.get("stream") != 0:
        print("FAIL: fdsurf-gpio-stream exited %s in the guest" % found.get("stream"))
        return 1
    return check_waveform(args, trace, stderr.get("stream", []))


def check_serve(args, text, trace):
    found, stderr = results(text)
    for name in ("client", "serve"):
        for line in stderr.get(name, []):
            print("guest %s: %s" % (name, line))
    said = " / ".join(stderr.get("serve", []))
    failures = []
    if found.get("client") != 0:
        failures.append("the client exited %s" % found.get("client"))
    if found.get("serve") != 0:
        failures.append("the server exited %s" % found.get("serve"))
    for expected in ("at rest, pen lifted, drivers disabled", "1 sessions"):
        if expected not in said:
            failures.append("the server did not say '%s'" % expected)
    if "outlived" in said:
        failures.append("the link outlived the server")
    for failure in failures:
        print("FAIL: " + failure)
    return check_waveform(args, trace, stderr.get("serve", [])) or (1 if failures else 0)


def check_errors(text):
    found, stderr = results(text)
    failures = 0
    for name, (code, message) in EXPECTED_ERRORS.items():
        said = " / ".join(stderr.get(name, [])) or "(nothing on stderr)"
        ok = found.get(name) == code and (message is None or message in said)
        print("%s %s: exit %s (expected %d): %s" % ("ok  " if ok else "FAIL", name,
                                                    found.get(name), code, said))
        if not ok and message is not None:
            print("     expected on stderr: %s" % message)
        failures += 0 if ok else 1
    return 1 if failures else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", choices=["stream", "serve", "errors"], required=True)
    parser.add_argument("--cache", required=True, help="vmlinuz and busybox (fetch_guest.sh)")
    parser.add_argument("--streamer", required=True, help="the arm64 fdsurf-gpio-stream")
    parser.add_argument("--job", required=True, help="the job (fdsurf_kernel_gpio_job)")
    parser.add_argument("--reference", help="the simulated plotter's waveform of the job")
    parser.add_argument("--checker", help="fdsurf_waveform_check")
    parser.add_argument("--out", required=True, help="where the console, trace and waveform go")
    parser.add_argument("--qemu", default="qemu-system-aarch64")
    parser.add_argument("--tick-hz", type=int, default=500)
    parser.add_argument("--timeout", type=float, default=120)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    template = {"stream": INIT_STREAM, "serve": INIT_SERVE, "errors": INIT_ERRORS}[args.scenario]
    init = INIT_COMMON + template.format(device=DEVICE, tick_hz=args.tick_hz,
                                         power_key=POWER_KEY_LINE)
    initrd = os.path.join(args.out, "initrd.cpio")
    build_initramfs(args, init, initrd)
    trace = os.path.join(args.out, "trace.log")
    if os.path.exists(trace):
        os.remove(trace)
    text = boot(args, initrd, trace)
    if args.scenario == "stream":
        return check_stream(args, text, trace)
    if args.scenario == "serve":
        return check_serve(args, text, trace)
    return check_errors(text)


if __name__ == "__main__":
    sys.exit(main())
