#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Puts LinuxCNC's sample programs (Debian's linuxcnc-uspace, GPL-2+, files
# under /usr/share/linuxcnc/ncfiles/) into DEST, for the G-code reader's
# third-party test. The package is only downloaded and unpacked, not
# installed. Does nothing when DEST already has them.
set -euo pipefail
dest=${1:?usage: fetch_linuxcnc_ncfiles.sh DEST}
if [ -f "$dest/tort.ngc" ]; then exit 0; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && timeout 300 apt-get download linuxcnc-uspace >/dev/null 2>&1) || {
  echo "fetch_linuxcnc_ncfiles.sh: apt-get download linuxcnc-uspace failed" >&2
  exit 1
}
timeout 120 dpkg-deb --fsys-tarfile "$work"/linuxcnc-uspace_*.deb |
  tar -x -C "$work" ./usr/share/linuxcnc/ncfiles/tort.ngc ./usr/share/linuxcnc/ncfiles/cds.ngc \
    ./usr/share/doc/linuxcnc-uspace/copyright 2>/dev/null || true
mkdir -p "$dest"
cp "$work"/usr/share/linuxcnc/ncfiles/tort.ngc "$work"/usr/share/linuxcnc/ncfiles/cds.ngc "$dest"/
if [ -f "$work"/usr/share/doc/linuxcnc-uspace/copyright ]; then
  cp "$work"/usr/share/doc/linuxcnc-uspace/copyright "$dest"/
fi
