#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Debian 12's amd64 kernel and an initramfs for the USB tests under QEMU.

  initramfs.py --cache DIR --out FILE.cpio [--binary PATH]...

1. Fetches `linux-image-amd64`'s kernel into DIR (once): resolves the
   metapackage to its linux-image-<abi>-amd64 (apt-cache depends), then
   `apt-get download` and `dpkg-deb -x DIR/root`. Nothing is installed.
2. Writes FILE.cpio (newc, uncompressed): busybox-static and its applets, the
   USB modules below with every module they depend on (the `depends=` field
   of each module's .modinfo section, which is what depmod writes into
   modules.dep; the .deb ships no modules.dep), our binaries in /bin with
   every shared library ldd names, and /init (tests/kernel/init.sh).
The kernel's path is written to DIR/vmlinuz (a symlink).

Errors name what failed and exit 1; FILE is written whole or not at all.
"""
import argparse
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

MODULES = [
    "configfs", "usb-common", "usbcore", "udc-core", "dummy_hcd", "libcomposite",
    "usb_f_fs", "usb_f_acm", "cdc-acm",
]
BUSYBOX = Path("/bin/busybox")


def fail(text):
    print(f"initramfs.py: {text}", file=sys.stderr)
    sys.exit(1)


def run(args, cwd=None):
    done = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        fail(f"{' '.join(args)} failed ({done.returncode}): {done.stderr.strip()}")
    return done.stdout


def fetch_kernel(cache):
    """DIR/root holds the extracted linux-image package; returns the vmlinuz path."""
    root = cache / "root"
    kernels = sorted((root / "boot").glob("vmlinuz-*")) if root.is_dir() else []
    if not kernels:
        depends = run(["apt-cache", "depends", "linux-image-amd64"])
        match = re.search(r"Depends: (linux-image-\S+-amd64)\b", depends)
        if not match:
            fail(f"apt-cache depends linux-image-amd64 names no kernel package:\n{depends}")
        package = match.group(1)
        cache.mkdir(parents=True, exist_ok=True)
        for old in cache.glob("*.deb"):
            old.unlink()
        run(["apt-get", "download", package], cwd=cache)
        debs = list(cache.glob(f"{package}_*.deb"))
        if len(debs) != 1:
            fail(f"apt-get download {package} left {len(debs)} .deb files in {cache}")
        staging = cache / "root.new"
        run(["rm", "-rf", str(staging)])
        run(["dpkg-deb", "-x", str(debs[0]), str(staging)])
        staging.rename(root)
        debs[0].unlink()
        kernels = sorted((root / "boot").glob("vmlinuz-*"))
        if not kernels:
            fail(f"{debs[0].name} holds no boot/vmlinuz-*")
    link = cache / "vmlinuz"
    if link.is_symlink() or link.exists():
        link.unlink()
    link.symlink_to(kernels[-1].resolve())
    return kernels[-1]


def modinfo_depends(ko):
    """The module names in the `depends=` field of the ELF64 .modinfo section."""
    data = ko.read_bytes()
    if data[:4] != b"\x7fELF" or data[4] != 2:
        fail(f"{ko}: not an ELF64 module")
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", data, 0x3A)

    def section(index):
        base = shoff + index * shentsize
        name, = struct.unpack_from("<I", data, base)
        offset, size = struct.unpack_from("<QQ", data, base + 0x18)
        return name, offset, size

    _, names_offset, _ = section(shstrndx)
    for i in range(shnum):
        name, offset, size = section(i)
        end = data.index(b"\0", names_offset + name)
        if data[names_offset + name:end] == b".modinfo":
            for field in data[offset:offset + size].split(b"\0"):
                if field.startswith(b"depends="):
                    return [d for d in field[8:].decode().split(",") if d]
            return []
    fail(f"{ko}: no .modinfo section")


def module_load_order(modules_dir):
    """Every needed .ko path, each after the modules it depends on."""
    by_name = {}
    for ko in modules_dir.rglob("*.ko"):
        by_name[ko.stem.replace("-", "_")] = ko
    order = []
    seen = set()

    def visit(name, chain):
        key = name.replace("-", "_")
        if key in seen:
            return
        if key not in by_name:
            fail(f"module {name} (needed by {' <- '.join(chain) or 'the tests'}) "
                 f"not in {modules_dir}")
        for dep in modinfo_depends(by_name[key]):
            visit(dep, [name] + chain)
        seen.add(key)
        order.append(by_name[key])

    for name in MODULES:
        visit(name, [])
    return order


def shared_libraries(binary):
    """The absolute paths of every library the dynamic loader maps for binary."""
    out = subprocess.run(["ldd", str(binary)], capture_output=True, text=True)
    if out.returncode != 0 and "not a dynamic executable" in out.stdout + out.stderr:
        return []
    if out.returncode != 0:
        fail(f"ldd {binary} failed: {out.stderr.strip()}")
    libraries = []
    for line in out.stdout.splitlines():
        if "not found" in line:
            fail(f"{binary}: shared library missing: {line.strip()}")
        match = re.search(r"(/\S+) \(0x", line)
        if match:
            libraries.append(match.group(1))
    return libraries


class Cpio:
    """A newc archive, as the kernel's initramfs unpacker reads it."""

    def __init__(self):
        self.chunks = []
        self.inode = 1
        self.dirs = set()

    def _entry(self, name, mode, body):
        header = "070701" + "".join(f"{v:08x}" for v in (
            self.inode, mode, 0, 0, 1, 0, len(body), 0, 0, 0, 0, len(name) + 1, 0))
        self.inode += 1
        record = header.encode() + name.encode() + b"\0"
        record += b"\0" * (-len(record) % 4) + body
        self.chunks.append(record + b"\0" * (-len(record) % 4))

    def directory(self, name):
        name = name.strip("/")
        if not name or name in self.dirs:
            return
        self.directory(os.path.dirname(name))
        self.dirs.add(name)
        self._entry(name, 0o040755, b"")

    def file(self, name, body, mode=0o755):
        name = name.strip("/")
        self.directory(os.path.dirname(name))
        self._entry(name, 0o100000 | mode, body)

    def symlink(self, name, target):
        name = name.strip("/")
        self.directory(os.path.dirname(name))
        self._entry(name, 0o120777, target.encode())

    def bytes(self):
        self._entry("TRAILER!!!", 0, b"")
        return b"".join(self.chunks)


def resolve(path):
    """A library path with its symlinks followed (the copy is the file itself)."""
    return Path(os.path.realpath(path)).read_bytes()


def build(cache, out, binaries):
    kernel = fetch_kernel(cache)
    release = kernel.name[len("vmlinuz-"):]
    modules_dir = cache / "root" / "lib" / "modules" / release / "kernel"
    if not BUSYBOX.exists():
        fail(f"{BUSYBOX} missing (apt-get install busybox-static; scripts/setup.sh)")
    archive = Cpio()
    for d in ("proc", "sys", "dev", "tmp", "run", "mnt"):
        archive.directory(d)
    archive.file("bin/busybox", BUSYBOX.read_bytes())
    applets = run([str(BUSYBOX), "--list"]).split()
    for applet in applets:
        if applet != "busybox":
            archive.symlink(f"bin/{applet}", "busybox")
    archive.symlink("sbin", "bin")
    order = []
    for ko in module_load_order(modules_dir):
        archive.file(f"lib/modules/{ko.name}", ko.read_bytes(), 0o644)
        order.append(ko.name)
    archive.file("modules.order", ("\n".join(order) + "\n").encode(), 0o644)
    archive.file("init", (Path(__file__).parent / "init.sh").read_bytes())
    libraries = set()
    for binary in binaries:
        archive.file(f"bin/{Path(binary).name}", Path(binary).read_bytes())
        libraries.update(shared_libraries(binary))
    for library in sorted(libraries):
        archive.file(library, resolve(library))
    staging = out.with_name(out.name + ".new")
    staging.write_bytes(archive.bytes())
    staging.rename(out)
    print(f"{out}: kernel {release}, modules {' '.join(order)}, "
          f"{len(binaries)} binaries, {len(libraries)} libraries")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", required=True, type=Path)
    parser.add_argument("--out", required=True, type=Path)
    parser.add_argument("--binary", action="append", default=[])
    args = parser.parse_args()
    build(args.cache, args.out, args.binary)


if __name__ == "__main__":
    main()
