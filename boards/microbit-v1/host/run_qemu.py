#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Runs the micro:bit v1 image under `qemu-system-arm -M microbit` as an
emulated board (the harness interface of docs/boards.md and the common brief):

  run_qemu.py --elf FILE --uart-socket PATH --waveform OUT [--time-limit-s N]
              [--measures OUT.tsv] [--plugin SO] [--baud B] [--qemu EXE]
              [--endstop-start X,Y]

- LISTENS on the Unix stream socket PATH (one client at a time; the next one
  is accepted when it leaves; the board keeps running). The client's bytes go
  to the board's UART RX at the line's byte rate in emulated time (10 bits per
  byte at --baud, paced by the guest's instruction clock, in bursts no larger
  than one poll of this loop); what the board sends goes to the client, or is
  dropped when there is none.
- Records every change of the STEP/DIR/ENABLE pins and of the pen (the PEN
  line, or the SERVO pin of a servo image) with its emulated time
  in OUT (waveform format 1), and exits 0 on SIGTERM/SIGINT or when the
  wall-clock time limit passes, after dumping the board's RAM through the
  QEMU monitor for the measures (--measures: a TSV of flash, RAM, stack
  high-water, cycles per tick and per point, late ticks, link counters).
- Prints `ready` once PATH is listening.

Time. QEMU runs with -icount shift=6: every guest instruction advances the
emulated clock by 2^6 = 64 ns, i.e. one instruction is counted as one cycle
of a 15.6 MHz core (the nRF51 runs at 16 MHz, and most M0 instructions take
one cycle; loads, stores and taken branches take 2-3, so the real board is
slower than this by its cycles per instruction). The firmware never sleeps
(its main loop polls), so emulated time is exactly instructions x 64 ns and
the same run gives the same times. align=on makes QEMU wait when the guest
gets ahead of the wall clock, so emulated time runs at about real time when
the host is fast enough (the host tool's timeouts are in real time); sleep=on
is what align requires (it only matters for a sleeping guest).

Pins. QEMU's nrf51_gpio_update_output_irq trace event reports each change of
an output pin's level, without guest time (the log backend stamps it with the
host's wall clock, if at all). The TCG plugin microbit_pins_plugin.c writes
`T <instructions>` into the same log after every store to the GPIO block, so
each change is stamped with the exact instruction count of the store that
caused it; the plugin also publishes the count in a shared file, the clock
that paces the UART bytes.

Endstops (--endstop-start X,Y). A simulated carriage starts X, Y steps above
the min switches (pins.h: edge P2 and P12, pulled up, a closed switch reads
LOW) and counts the STEP rising edges as the waveform is read, each towards
negative while DIR is high. When an axis reaches or passes 0 its switch
closes: the harness drives that GPIO input LOW through QEMU's qtest protocol
(`-qtest unix:...`, `set_irq_in /machine/nrf51 unnamed-gpio-in PIN 0`; the
CPU keeps running under TCG), and HIGH again when the carriage leaves. The
harness reads the log every 2 ms of wall time then, and the guest runs at
about wall-clock speed (align=on), so a switch closes up to a few ms of
emulated time late: at a homing rate of 200 steps/s a step or two past it
(simavr's harness, in the same process as the CPU, is exact). At exit it
prints "carriage X n Y m" (steps above each switch) on stderr.
"""
import argparse
import collections
import ctypes
import functools
import mmap
import os
import re
import resource
import selectors
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
DEFAULT_PLUGIN = os.path.join(REPO, "build", "boards", "microbit-v1", "host",
                              "libfdsurf_microbit_pins.so")

ICOUNT_SHIFT = 6
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
NS_PER_INSN = 1 << ICOUNT_SHIFT
RAM_BASE = 0x20000000
RAM_SIZE = 16 * 1024
STACK_PAINT = 0xC0DEFACE
STATS_MAGIC = 0x5354424D
# boards/microbit-v1/src/board_stats.h, in order; all 32-bit words.
STATS_FIELDS = ("magic tick_hz ticks late_ticks missed_ticks late_moving_ticks max_lateness max_tick_cycles "
                "tick_cycles_low tick_cycles_high stepping_ticks max_stepping_tick_cycles "
                "work_cycles_low work_cycles_high points max_work_cycles rx_bytes "
                "rx_overruns uart_errors fault servo_periods servo_max_lateness_us").split()
TIMER_HZ = 16_000_000

# nRF51 GPIO -> waveform signals (src/pins.h). ENABLE is one line shared by
# both drivers: it is written as X_EN and Y_EN. The pen is PEN on P0.03 or,
# in a servo image, SERVO on P0.02 (the image's fdsurf_board_pen says which).
PIN_SIGNALS = {23: ("X_STEP",), 22: ("X_DIR",), 21: ("Y_STEP",), 16: ("Y_DIR",),
               18: ("X_EN", "Y_EN")}
PEN_PIN, SERVO_PIN = 3, 2
MIN_SWITCH_PINS = (1, 20)  # X, Y min endstops (src/pins.h: kXMin, kYMin)
WAVEFORM_HEADER = ("# fdsurf-waveform 1\n# board microbit-v1\n# dir_negative_level 1\n"
                   "# enable_active_level 0\n")
TRACE_RE = re.compile(r"nrf51_gpio_update_output_irq line (\d+) value (-?\d+)")


class Waveform:
    """Turns the QEMU log (trace lines, then the plugin's T line of the store
    that caused them) into waveform lines, incrementally."""

    def __init__(self, path, pen):
        """`pen`: the image's (kind, up_us, down_us), kind 0 a line, 1 a servo."""
        self.out = open(path + ".tmp", "w", encoding="ascii")
        self.path = path
        self.pins = dict(PIN_SIGNALS)
        if pen[0] == 1:
            self.pins[SERVO_PIN] = ("SERVO",)
            pen_line = f"# pen servo {pen[1]} {pen[2]}\n"
        else:
            self.pins[PEN_PIN] = ("PEN",)
            pen_line = "# pen line 1\n"
        self.out.write(WAVEFORM_HEADER + pen_line)
        self.levels = {}
        self.pending = []
        self.partial = ""
        self.end_count = None
        self.changes = collections.Counter()
        self.on_change = None  # called (signal, level) for each change written

    def feed(self, text):
        lines = (self.partial + text).split("\n")
        self.partial = lines.pop()
        for line in lines:
            if line.startswith("T "):
                self._stamp(int(line[2:]))
            elif line.startswith("END "):
                self.end_count = int(line[4:])
            else:
                match = TRACE_RE.search(line)
                if match and int(match.group(1)) in self.pins and int(match.group(2)) >= 0:
                    self.pending.append((int(match.group(1)), int(match.group(2))))

    def _stamp(self, count):
        for pin, level in self.pending:
            for signal_name in self.pins[pin]:
                if self.levels.get(signal_name) != level:
                    self.levels[signal_name] = level
                    self.changes[signal_name] += 1
                    self.out.write(f"{count * NS_PER_INSN} {signal_name} {level}\n")
                    if self.on_change is not None:
                        self.on_change(signal_name, level)
        self.pending = []

    def close(self):
        self.out.close()
        os.replace(self.path + ".tmp", self.path)

    def discard(self):
        self.out.close()
        os.unlink(self.path + ".tmp")


class Carriage:
    """The simulated X/Y carriage above its min switches (--endstop-start),
    fed the waveform's changes; drive(pin, level) sets a switch's input."""

    def __init__(self, start, drive):
        self.position = list(start)
        self.dir_level = [0, 0]
        self.step_level = [0, 0]
        self.drive = drive
        self.closed = [None, None]
        self.update()

    def change(self, signal_name, level):
        axis = "XY".find(signal_name[0])
        if axis < 0:
            return
        if signal_name.endswith("_DIR"):
            self.dir_level[axis] = level
        elif signal_name.endswith("_STEP"):
            if level == 1 and self.step_level[axis] == 0:
                self.position[axis] += -1 if self.dir_level[axis] == 1 else 1
                self.update()
            self.step_level[axis] = level

    def update(self):
        for axis in (0, 1):
            closed = self.position[axis] <= 0
            if closed != self.closed[axis]:
                self.closed[axis] = closed
                self.drive(MIN_SWITCH_PINS[axis], 0 if closed else 1)


class UartPacer:
    """Client bytes waiting for the emulated line; released one byte time
    (10 bits at `baud`, in guest instructions) after the previous one."""

    def __init__(self, baud):
        self.insns_per_byte = 10 / baud * 1e9 / NS_PER_INSN
        self.pending = bytearray()
        self.line_free_at = 0.0

    def due(self, now):
        if not self.pending:
            self.line_free_at = max(self.line_free_at, float(now))
            return b""
        n = 0
        while n < len(self.pending) and self.line_free_at + self.insns_per_byte <= now:
            self.line_free_at += self.insns_per_byte
            n += 1
        out = bytes(self.pending[:n])
        del self.pending[:n]
        return out


def elf_symbols_and_sizes(path, read_words=None):
    """(symbols {name: value}, flash bytes, static RAM bytes) of an ELF32 LE;
    with `read_words` a symbol's name, also the 32-bit words of its initial
    value (a tuple, as many as its size says; None if it is not in the ELF)."""
    data = open(path, "rb").read()
    if data[:4] != b"\x7fELF" or data[4] != 1 or data[5] != 1:
        raise SystemExit(f"run_qemu.py: {path}: not a 32-bit little-endian ELF file")
    shoff, = struct.unpack_from("<I", data, 0x20)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", data, 0x2E)
    sections = [struct.unpack_from("<IIIIIIIIII", data, shoff + i * shentsize)
                for i in range(shnum)]
    names_offset = sections[shstrndx][4]

    def name_at(table_offset, index):
        end = data.index(b"\0", table_offset + index)
        return data[table_offset + index:end].decode()

    symbols, sizes, flash, ram = {}, {}, 0, 0
    for name_index, kind, flags, addr, offset, size, link, _, _, entsize in sections:
        name = name_at(names_offset, name_index)
        if flags & 0x2:  # SHF_ALLOC
            if addr < RAM_BASE:
                flash += size
            else:
                ram += size
                if kind != 8:  # not NOBITS: .data is loaded from flash too
                    flash += size
        if kind == 2:  # SHT_SYMTAB
            strings = sections[link][4]
            for i in range(size // entsize):
                st_name, st_value, st_size = struct.unpack_from("<III", data, offset + i * entsize)
                if st_name:
                    symbols[name_at(strings, st_name)] = st_value
                    sizes[name_at(strings, st_name)] = st_size
    if read_words is None:
        return symbols, flash, ram
    words = None
    address, size = symbols.get(read_words), sizes.get(read_words, 0)
    for _, kind, flags, addr, offset, section_size, _, _, _, _ in sections:
        if address is not None and flags & 0x2 and kind != 8 and \
                addr <= address and address + size <= addr + section_size:
            words = struct.unpack_from(f"<{size // 4}I", data, offset + address - addr)
    return symbols, flash, ram, words


def image_pen(path):
    """The image's pen (fdsurf_board_pen): (0, 0, 0) a line, (1, up, down) a
    servo; an image without the symbol (before the servo) has a line."""
    words = elf_symbols_and_sizes(path, "fdsurf_board_pen")[3]
    if words is None:
        return (0, 0, 0)
    if len(words) != 3 or words[0] not in (0, 1):
        raise SystemExit(f"run_qemu.py: {path}: fdsurf_board_pen is {words}, not "
                         "(0, 0, 0) or (1, up_us, down_us)")
    return words


def build_plugin(directory):
    """Compiles the pin plugin when the host build's copy is not there."""
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise SystemExit("run_qemu.py: no --plugin given and no C compiler to build it")
    out = os.path.join(directory, "libfdsurf_microbit_pins.so")
    subprocess.run([compiler, "-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-o", out,
                    os.path.join(HERE, "microbit_pins_plugin.c")], check=True, timeout=60)
    return out


def bound_qemu(time_limit_s):
    """In the QEMU child before exec: it dies with this harness (SIGKILL when
    the harness exits, however it exits, even by SIGKILL) and may use at most
    the time limit + 30 s of CPU (the kernel kills it then). A `timeout`
    wrapper did not do this: killing the wrapper left QEMU running."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL) != 0:
        os._exit(127)
    if os.getppid() == 1:  # the harness died before prctl
        os._exit(127)
    cpu_s = int(time_limit_s) + 30
    resource.setrlimit(resource.RLIMIT_CPU, (cpu_s, cpu_s + 5))


def qemu_command(args, work, plugin):
    return [args.qemu, "-M", "microbit", "-kernel", args.elf, "-nographic",
            "-icount", f"shift={ICOUNT_SHIFT},align=on,sleep=on",
            "-chardev", f"socket,id=uart,path={work}/uart.sock,server=on,wait=off",
            "-serial", "chardev:uart",
            "-monitor", f"unix:{work}/monitor.sock,server=on,wait=off",
            "-plugin", f"{plugin},clock={work}/clock.bin",
            "-d", "plugin", "-D", f"{work}/qemu.log",
            "-trace", "enable=nrf51_gpio_update_output_irq"] + (
                ["-qtest", f"unix:{work}/qtest.sock,server=on,wait=off"]
                if args.endstop_start is not None else [])


def connect_unix(path, deadline, process=None):
    while True:
        if process is not None and process.poll() is not None:
            raise SystemExit(f"run_qemu.py: QEMU exited at start ({process.returncode})")
        try:
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.connect(path)
            return sock
        except OSError:
            sock.close()
            if time.monotonic() > deadline:
                raise
            time.sleep(0.02)


def monitor(work, commands, deadline):
    """Runs HMP commands (one at a time, waiting for each prompt)."""
    sock = connect_unix(f"{work}/monitor.sock", deadline)
    sock.settimeout(max(0.1, deadline - time.monotonic()))
    received = b""
    try:
        for command in [None] + commands:
            if command is not None:
                sock.sendall(command.encode() + b"\n")
                if command == "quit":
                    break
            while not received.endswith(b"(qemu) "):
                chunk = sock.recv(4096)
                if not chunk:
                    return
                received += chunk
            received = b""
    finally:
        sock.close()


class Harness:
    def __init__(self, args):
        self.args = args
        self.work = tempfile.mkdtemp(prefix="fdsurf-microbit-")
        self.stop_requested = False
        self.selector = selectors.DefaultSelector()
        self.client = None
        self.pacer = UartPacer(args.baud)
        self.waveform = Waveform(args.waveform, image_pen(args.elf))
        self.log = None
        self.tx_bytes = 0
        self.clients = 0
        self.qemu = None
        self.listener = None
        self.qtest = None
        self.carriage = None

    def start(self):
        plugin = self.args.plugin or (DEFAULT_PLUGIN if os.path.exists(DEFAULT_PLUGIN)
                                      else build_plugin(self.work))
        with open(f"{self.work}/clock.bin", "wb") as f:
            f.write(b"\0" * 4096)
        open(f"{self.work}/qemu.log", "w").close()
        self.qemu = subprocess.Popen(qemu_command(self.args, self.work, plugin),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=open(f"{self.work}/qemu.stderr", "w"),
                                     preexec_fn=functools.partial(bound_qemu,
                                                                  self.args.time_limit_s))
        deadline = time.monotonic() + 10
        self.uart = connect_unix(f"{self.work}/uart.sock", deadline, self.qemu)
        self.uart.setblocking(False)
        with open(f"{self.work}/clock.bin", "r+b") as f:
            self.clock = mmap.mmap(f.fileno(), 4096)
        self.log = open(f"{self.work}/qemu.log", "r", encoding="ascii", errors="replace")
        if self.args.endstop_start is not None:
            self.qtest = connect_unix(f"{self.work}/qtest.sock", deadline, self.qemu)
            self.qtest.settimeout(5)
            self.carriage = Carriage(self.args.endstop_start, self.drive_input)
            self.waveform.on_change = self.carriage.change
        if os.path.exists(self.args.uart_socket):
            os.unlink(self.args.uart_socket)
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.listener.bind(self.args.uart_socket)
        self.listener.listen(1)
        self.listener.setblocking(False)
        self.selector.register(self.listener, selectors.EVENT_READ, "accept")
        self.selector.register(self.uart, selectors.EVENT_READ, "board")
        print("ready", flush=True)

    def now(self):
        return struct.unpack_from("<Q", self.clock, 0)[0]

    def drive_input(self, pin, level):
        """Drives the GPIO input `pin` to `level` (qtest set_irq_in)."""
        self.qtest.sendall(b"set_irq_in /machine/nrf51 unnamed-gpio-in %d %d\n" % (pin, level))
        reply = b""
        while not reply.endswith(b"\n"):
            chunk = self.qtest.recv(256)
            if not chunk:
                raise SystemExit("run_qemu.py: QEMU closed the qtest socket")
            reply += chunk
        if not reply.startswith(b"OK"):
            raise SystemExit(f"run_qemu.py: qtest refused set_irq_in: {reply!r}")

    def drop_client(self):
        self.selector.unregister(self.client)
        self.client.close()
        self.client = None
        self.selector.register(self.listener, selectors.EVENT_READ, "accept")

    def handle(self, what):
        if what == "accept":
            self.client, _ = self.listener.accept()
            self.client.setblocking(True)
            self.client.settimeout(5)
            self.clients += 1
            self.selector.unregister(self.listener)
            self.selector.register(self.client, selectors.EVENT_READ, "client")
        elif what == "client":
            data = self.client.recv(65536)
            if data:
                self.pacer.pending += data
            else:
                self.drop_client()
        elif what == "board":
            data = self.uart.recv(65536)
            if not data:
                raise SystemExit("run_qemu.py: QEMU closed the UART")
            self.tx_bytes += len(data)
            if self.client is not None:
                try:
                    self.client.sendall(data)
                except OSError:
                    self.drop_client()

    def run(self):
        deadline = time.monotonic() + self.args.time_limit_s
        while not self.stop_requested and time.monotonic() < deadline:
            if self.qemu.poll() is not None:
                raise SystemExit(f"run_qemu.py: QEMU exited early ({self.qemu.returncode}); "
                                 f"see {self.work}/qemu.stderr")
            timeout = 0.0005 if self.pacer.pending else 0.002 if self.carriage else 0.02
            for key, _ in self.selector.select(timeout):
                self.handle(key.data)
            due = self.pacer.due(self.now())
            if due:
                self.uart.setblocking(True)
                self.uart.sendall(due)
                self.uart.setblocking(False)
            self.waveform.feed(self.log.read())

    def finish(self):
        ram = None
        if self.log is None:  # QEMU never came up: nothing recorded
            if self.qemu is not None and self.qemu.poll() is None:
                self.qemu.kill()
                self.qemu.wait()
            if os.path.exists(f"{self.work}/qemu.stderr"):
                sys.stderr.write(open(f"{self.work}/qemu.stderr").read())
            self.waveform.discard()
            shutil.rmtree(self.work, ignore_errors=True)
            return
        try:
            monitor(self.work, ["stop", f'memsave {RAM_BASE:#x} {RAM_SIZE} "{self.work}/ram.bin"',
                                "quit"], time.monotonic() + 10)
            self.qemu.wait(timeout=10)
        except (OSError, subprocess.TimeoutExpired):
            self.qemu.kill()
            self.qemu.wait()
        if os.path.exists(f"{self.work}/ram.bin"):
            ram = open(f"{self.work}/ram.bin", "rb").read()
        self.waveform.feed(self.log.read() + "\n")
        self.waveform.close()
        if self.carriage is not None:
            print("carriage X %d Y %d" % tuple(self.carriage.position), file=sys.stderr)
        if self.args.measures:
            write_measures(self.args, self, ram)
        if self.client is not None:
            self.client.close()
        if self.listener is not None:
            self.listener.close()
            os.unlink(self.args.uart_socket)
        if self.args.keep and os.path.exists(f"{self.work}/ram.bin"):
            shutil.copy(f"{self.work}/ram.bin", self.args.waveform + ".ram")
        if not self.args.keep:
            shutil.rmtree(self.work, ignore_errors=True)
        else:
            print(f"kept {self.work}", file=sys.stderr)


def stack_high_water(ram, symbols):
    start = symbols["__stack_limit"] - RAM_BASE
    top = symbols["__stack_top"] - RAM_BASE
    for offset in range(start, top, 4):
        if struct.unpack_from("<I", ram, offset)[0] != STACK_PAINT:
            return top - offset
    return 0


def write_measures(args, harness, ram):
    symbols, flash, static_ram = elf_symbols_and_sizes(args.elf)
    rows = [("flash_bytes", flash, "B", ".text + .data (image in flash)"),
            ("static_ram_bytes", static_ram, "B", ".data + .bss, of 16384")]
    if ram is None:
        raise SystemExit("run_qemu.py: no RAM dump from QEMU; no measures")
    stats = dict(zip(STATS_FIELDS, struct.unpack_from(
        f"<{len(STATS_FIELDS)}I", ram, symbols["fdsurf_board_stats"] - RAM_BASE)))
    if stats["magic"] != STATS_MAGIC:
        raise SystemExit("run_qemu.py: fdsurf_board_stats not initialised: did the image start?")
    insns = harness.waveform.end_count or harness.now()
    tick_cycles = stats["tick_cycles_low"] | stats["tick_cycles_high"] << 32
    work_cycles = stats["work_cycles_low"] | stats["work_cycles_high"] << 32
    period = TIMER_HZ // stats["tick_hz"]
    elapsed_cycles = insns * NS_PER_INSN * TIMER_HZ / 1e9
    ticks = max(stats["ticks"], 1)
    rows += [
        ("stack_high_water_bytes", stack_high_water(ram, symbols), "B", "painted at reset"),
        ("stack_space_bytes", symbols["__stack_top"] - symbols["__stack_limit"], "B",
         "between .bss and the top of RAM"),
        ("emulated_s", round(insns * NS_PER_INSN / 1e9, 6), "s", "instructions x 64 ns"),
        ("instructions", insns, "insn", ""),
        ("tick_hz", stats["tick_hz"], "Hz", f"period {period} cycles"),
        ("ticks", stats["ticks"], "", ""),
        ("stepping_ticks", stats["stepping_ticks"], "", "ticks with a unit move"),
        ("late_ticks", stats["late_ticks"], "", "began > half a period after their compare"),
        ("missed_ticks", stats["missed_ticks"], "", "began >= a period late (slot lost)"),
        ("late_moving_ticks", stats["late_moving_ticks"], "", "late while moving (speed > 0)"),
        ("max_lateness_cycles", stats["max_lateness"], "cycles", "compare to handler body"),
        ("mean_tick_cycles", round(tick_cycles / ticks, 1), "cycles", "handler body"),
        ("max_tick_cycles", stats["max_tick_cycles"], "cycles", ""),
        ("max_stepping_tick_cycles", stats["max_stepping_tick_cycles"], "cycles", ""),
        ("tick_load_percent", round(100 * tick_cycles / max(elapsed_cycles, 1), 2), "%", ""),
        ("points", stats["points"], "", "lookahead entries produced by the main loop"),
        ("work_cycles_per_point", round(work_cycles / max(stats["points"], 1), 1), "cycles",
         "main-loop work (receive, validate, evaluate) / points"),
        ("max_work_cycles", stats["max_work_cycles"], "cycles", "longest main-loop round"),
        ("busy_percent", round(100 * (tick_cycles + work_cycles) / max(elapsed_cycles, 1), 2),
         "%", "ticks + main-loop work"),
        ("rx_bytes", stats["rx_bytes"], "B", ""),
        ("tx_bytes", harness.tx_bytes, "B", ""),
        ("rx_overruns", stats["rx_overruns"], "B", "dropped: ring full"),
        ("uart_errors", stats["uart_errors"], "", ""),
        ("fault", stats["fault"], "", "exception number, 0 = none"),
        ("servo_periods", stats["servo_periods"], "", "pen servo periods started (0: a pen line)"),
        ("servo_max_lateness_us", stats["servo_max_lateness_us"], "us",
         "worst delay from a servo period's compare to its handler"),
        ("clients", harness.clients, "", ""),
    ]
    rows += [(f"changes_{name}", n, "", "") for name, n in sorted(harness.waveform.changes.items())]
    with open(args.measures, "w", encoding="ascii") as f:
        f.write("measure\tvalue\tunit\tnote\n")
        for row in rows:
            f.write("\t".join(str(x) for x in row) + "\n")


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--elf", required=True, help="the board image (fdsurf_microbit_v1.elf)")
    p.add_argument("--uart-socket", required=True, help="Unix socket to listen on")
    p.add_argument("--waveform", required=True, help="pin changes out (waveform format 1)")
    p.add_argument("--time-limit-s", type=float, default=600,
                   help="wall-clock seconds before a clean exit (default 600)")
    p.add_argument("--measures", help="TSV of the board's measures, written at exit")
    p.add_argument("--plugin", help="libfdsurf_microbit_pins.so (default: the host build's, "
                                    "else compiled on the fly)")
    p.add_argument("--baud", type=int, default=115200)
    p.add_argument("--qemu", default="qemu-system-arm")
    p.add_argument("--keep", action="store_true", help="keep the work directory (QEMU's log)")
    p.add_argument("--endstop-start", help="X,Y: a carriage that many steps above the min "
                                           "switches, which it drives (see above)")
    # "--endstop-start -40,10" (as the simavr harness takes it): argparse
    # would read the negative value as an option.
    argv = list(argv)
    for i, arg in enumerate(argv[:-1]):
        if arg == "--endstop-start":
            argv[i:i + 2] = ["--endstop-start=" + argv[i + 1]]
            break
    args = p.parse_args(argv)
    if args.endstop_start is not None:
        try:
            args.endstop_start = [int(v) for v in args.endstop_start.split(",")]
        except ValueError:
            args.endstop_start = []
        if len(args.endstop_start) != 2:
            p.error("--endstop-start: X,Y, whole numbers of steps")
    if not os.path.isfile(args.elf):
        p.error(f"--elf: {args.elf}: no such file")
    if args.time_limit_s <= 0:
        p.error("--time-limit-s: must be > 0")
    if args.baud <= 0:
        p.error("--baud: must be > 0")
    if shutil.which(args.qemu) is None:
        p.error(f"--qemu: {args.qemu}: not found")
    return args


def main(argv):
    args = parse_args(argv)
    harness = Harness(args)

    def request_stop(signum, frame):
        harness.stop_requested = True

    signal.signal(signal.SIGTERM, request_stop)
    signal.signal(signal.SIGINT, request_stop)
    try:
        harness.start()
        harness.run()
    finally:
        harness.finish()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
