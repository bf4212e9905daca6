#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A serial line between the host tool and an emulated board.

Connects to the board harness's Unix socket (its UART), creates a real kernel
pseudo-terminal (os.openpty), publishes the pty's slave under LINK (a symlink,
as /dev/serial/by-id/... names a USB serial port) and forwards bytes both ways.
On a schedule it can misbehave as a real line does:

  --hangup-after N --hangup-for S   after N bytes towards the board, close the
                                    pty and remove LINK (the host sees a
                                    hang-up, as on an unplug), wait S seconds,
                                    create a new pty and point LINK at it (the
                                    board replugged)
  --corrupt-after N --corrupt-bytes K
                                    once, after N bytes towards the board,
                                    flip every bit of the next K bytes

Prints `ready` (flushed) once LINK exists; logs what it did on stderr. Exits
on SIGTERM/SIGINT or when the harness closes the socket (exit 0), or with 2
if the socket cannot be reached within --connect-timeout seconds.
"""
import argparse
import os
import select
import signal
import socket
import sys
import time
import tty


def log(message):
    sys.stderr.write("serial_relay: %s\n" % message)
    sys.stderr.flush()


def connect(path, timeout):
    deadline = time.monotonic() + timeout
    while True:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            sock.connect(path)
            return sock
        except OSError as error:
            sock.close()
            if time.monotonic() > deadline:
                raise OSError("%s: cannot connect to the board's UART socket: %s" % (path, error))
            time.sleep(0.05)


class Pty:
    """A pty pair; the slave stays open here too, so the master reads no EIO
    while the host has it closed, and is raw from the start (no echo of the
    board's bytes before the host configures the line)."""

    def __init__(self, link):
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.name = os.ttyname(self.slave)
        temporary = link + ".new"
        if os.path.lexists(temporary):
            os.unlink(temporary)
        os.symlink(self.name, temporary)
        os.replace(temporary, link)

    def close(self):
        os.close(self.master)
        os.close(self.slave)


class Relay:
    def __init__(self, args):
        self.args = args
        self.sock = connect(args.socket, args.connect_timeout)
        self.pty = Pty(args.link)
        self.to_board = 0  # bytes forwarded towards the board
        self.to_host = 0
        self.hung_up = args.hangup_after is None
        self.corrupted = args.corrupt_after is None
        self.replug_at = None
        log("%s -> %s, socket %s" % (args.link, self.pty.name, args.socket))

    def corrupt(self, data):
        """Flips the bits of the scheduled burst, if it falls in `data`."""
        if self.corrupted:
            return data
        start = self.args.corrupt_after - self.to_board
        end = start + self.args.corrupt_bytes
        if end <= 0 or start >= len(data):
            return data
        out = bytearray(data)
        for i in range(max(start, 0), min(end, len(data))):
            out[i] ^= 0xFF
        if end <= len(data):
            self.corrupted = True
            log("corrupted %d bytes after byte %d" % (self.args.corrupt_bytes,
                                                       self.args.corrupt_after))
        return bytes(out)

    def from_host(self):
        try:
            data = os.read(self.pty.master, 4096)
        except BlockingIOError:
            return
        except OSError:  # EIO: nobody has the slave open (cannot happen: we hold it)
            return
        if not self.hung_up and self.to_board + len(data) >= self.args.hangup_after:
            data = data[:max(self.args.hangup_after - self.to_board, 0)]
        data = self.corrupt(data)
        self.sock.sendall(data)
        self.to_board += len(data)
        if not self.hung_up and self.to_board >= self.args.hangup_after:
            self.hang_up()

    def hang_up(self):
        """Unplugs: LINK goes first (as udev removes /dev/serial/by-id/...), then
        the pty, so a host that sees the hang-up never finds the old LINK."""
        self.hung_up = True
        os.unlink(self.args.link)
        self.pty.close()
        self.pty = None
        self.replug_at = time.monotonic() + self.args.hangup_for
        log("hung up after %d bytes towards the board; back in %.1f s" %
            (self.to_board, self.args.hangup_for))

    def from_board(self):
        data = self.sock.recv(4096)
        if not data:
            return False
        self.to_host += len(data)
        if self.pty is not None:
            try:
                os.write(self.pty.master, data)
            except BlockingIOError:
                log("dropped %d bytes towards the host (pty full)" % len(data))
        return True

    def run(self):
        print("ready", flush=True)
        while True:
            if self.pty is None and time.monotonic() >= self.replug_at:
                self.pty = Pty(self.args.link)
                log("plugged back in: %s -> %s" % (self.args.link, self.pty.name))
            readers = [self.sock] + ([self.pty.master] if self.pty is not None else [])
            ready, _, _ = select.select(readers, [], [], 0.05)
            if self.sock in ready and not self.from_board():
                log("the board closed the socket")
                return
            if self.pty is not None and self.pty.master in ready:
                self.from_host()


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--socket", required=True, help="the harness's UART socket")
    parser.add_argument("--link", required=True, help="the symlink to publish the pty under")
    parser.add_argument("--connect-timeout", type=float, default=30)
    parser.add_argument("--hangup-after", type=int, help="bytes towards the board")
    parser.add_argument("--hangup-for", type=float, default=1.0, help="seconds unplugged")
    parser.add_argument("--corrupt-after", type=int, help="bytes towards the board")
    parser.add_argument("--corrupt-bytes", type=int, default=8)
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    signal.signal(signal.SIGINT, lambda *_: sys.exit(0))
    try:
        relay = Relay(args)
    except OSError as error:
        log(str(error))
        return 2
    try:
        relay.run()
    finally:
        if os.path.lexists(args.link):
            os.unlink(args.link)
        log("%d bytes to the board, %d to the host" % (relay.to_board, relay.to_host))
    return 0


if __name__ == "__main__":
    sys.exit(main())
