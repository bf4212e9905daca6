#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The serial relay against an echoing "board" (a Unix socket that sends back
what it gets), on real kernel ptys: bytes go through unchanged both ways; the
corrupt schedule flips exactly the scheduled burst once; the hang-up schedule
hangs the host's end up after N bytes (a read sees end of file or EIO, as on an
unplug) and re-points the link at a new pty that works.

  relay_test.py [RELAY]   (default: serial_relay.py beside this file)
"""
import os
import shutil
import select
import socket
import subprocess
import sys
import tempfile
import termios
import threading
import time
import tty

RELAY = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__),
                                                           "serial_relay.py")


def echo_board(path):
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(path)
    server.listen(1)

    def serve():
        client, _ = server.accept()
        while True:
            data = client.recv(4096)
            if not data:
                return
            client.sendall(data)

    threading.Thread(target=serve, daemon=True).start()
    return server


def start_relay(sock, link, *options):
    relay = subprocess.Popen([sys.executable, RELAY, "--socket", sock, "--link", link] +
                             list(options), stdout=subprocess.PIPE, text=True)
    line = relay.stdout.readline()  # the relay prints `ready` at once or exits
    assert line == "ready\n", "relay said %r" % line
    return relay


def open_line(link):
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)
    termios.tcflush(fd, termios.TCIOFLUSH)
    return fd


def read_exactly(fd, n, timeout_s=5):
    data = b""
    deadline = time.monotonic() + timeout_s
    while len(data) < n and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            chunk = os.read(fd, n - len(data))
            if not chunk:
                break
            data += chunk
    return data


def check(condition, what):
    print("%s: %s" % ("ok  " if condition else "FAIL", what))
    return 0 if condition else 1


def test_corrupt(work):
    sock, link = os.path.join(work, "c.sock"), os.path.join(work, "ttyC")
    server = echo_board(sock)
    relay = start_relay(sock, link, "--corrupt-after", "10", "--corrupt-bytes", "4")
    fd = open_line(link)
    sent = bytes(range(32))
    os.write(fd, sent)
    got = read_exactly(fd, 32)
    expected = bytes(b ^ 0xFF if 10 <= i < 14 else b for i, b in enumerate(sent))
    failed = check(got == expected, "corrupt: bytes 10..13 flipped, the rest unchanged")
    os.write(fd, sent)
    failed += check(read_exactly(fd, 32) == sent, "corrupt: only once")
    os.close(fd)
    relay.terminate()
    relay.wait(10)
    server.close()
    return failed


def test_hangup(work):
    sock, link = os.path.join(work, "h.sock"), os.path.join(work, "ttyH")
    server = echo_board(sock)
    relay = start_relay(sock, link, "--hangup-after", "16", "--hangup-for", "2")
    fd = open_line(link)
    os.write(fd, bytes(range(16)))
    hung_up = False
    deadline = time.monotonic() + 3
    while time.monotonic() < deadline and not hung_up:
        select.select([fd], [], [], 0.1)
        try:
            hung_up = os.read(fd, 64) == b""
        except OSError:  # EIO: the other end is gone
            hung_up = True
    failed = check(hung_up, "hang-up: the host's end reads end of file or EIO")
    os.close(fd)
    failed += check(not os.path.lexists(link), "hang-up: the link is gone while unplugged")
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and not os.path.lexists(link):
        time.sleep(0.05)
    failed += check(os.path.lexists(link), "hang-up: the link is back (a new pty)")
    fd = open_line(link)
    os.write(fd, b"again")
    failed += check(read_exactly(fd, 5) == b"again", "hang-up: the new pty carries bytes")
    os.close(fd)
    relay.terminate()
    relay.wait(10)
    failed += check(not os.path.lexists(link), "the link is removed on exit")
    server.close()
    return failed


def main():
    work = tempfile.mkdtemp(prefix="fdsurf-relay-test-")
    if test_corrupt(work) + test_hangup(work):
        print("files in %s" % work)
        return 1
    shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
