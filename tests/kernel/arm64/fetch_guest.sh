#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The guest's Debian parts for the GPIO test under QEMU arm64, extracted from
# their .deb files (apt-get download, dpkg-deb -x), never installed:
#   CACHE/vmlinuz   the kernel of linux-image-arm64 (PL061 built in)
#   CACHE/busybox   busybox-static:arm64
#   CACHE/gpio_keys.ko  the kernel's gpio-keys module (the power key on line 3)
# Usage: fetch_guest.sh CACHE. Needs `dpkg --add-architecture arm64` and an
# apt-get update (scripts/setup.sh does both). Does nothing when both files
# are there already.
set -euo pipefail
cache=${1:?usage: fetch_guest.sh CACHE}
mkdir -p "$cache"
cache=$(cd "$cache" && pwd)
if [ -s "$cache/vmlinuz" ] && [ -s "$cache/busybox" ] && [ -s "$cache/gpio_keys.ko" ]; then exit 0; fi
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  echo "fetch_guest.sh: dpkg has no arm64 architecture: run scripts/setup.sh (dpkg --add-architecture arm64)" >&2
  exit 1
fi
# The versioned kernel package that the metapackage depends on.
kernel_pkg=$(apt-cache depends linux-image-arm64:arm64 2>/dev/null |
  sed -n 's/^ *Depends: \(linux-image-[0-9][^ :]*-arm64\).*/\1/p' | head -n 1)
if [ -z "$kernel_pkg" ]; then
  echo "fetch_guest.sh: apt knows no linux-image-arm64:arm64 (run apt-get update after dpkg --add-architecture arm64)" >&2
  exit 1
fi
work=$(mktemp -d "$cache/fetch.XXXXXX")
trap 'rm -rf "$work"' EXIT
(cd "$work" && apt-get download -qq "$kernel_pkg:arm64" busybox-static:arm64 2>&1 |
  grep -v 'unsandboxed' >&2 || true)
for deb in "$work"/*.deb; do
  [ -e "$deb" ] || { echo "fetch_guest.sh: apt-get download fetched nothing" >&2; exit 1; }
  dpkg-deb -x "$deb" "$work/root"
done
kernel=$(ls "$work"/root/boot/vmlinuz-*-arm64 | head -n 1)
cp "$kernel" "$cache/vmlinuz.tmp" && mv "$cache/vmlinuz.tmp" "$cache/vmlinuz"
cp "$work/root/bin/busybox" "$cache/busybox.tmp" && mv "$cache/busybox.tmp" "$cache/busybox"
cp "$work"/root/boot/config-*-arm64 "$cache/kernel.config"
cp "$work"/root/lib/modules/*/kernel/drivers/input/keyboard/gpio_keys.ko "$cache/gpio_keys.ko"
echo "fetch_guest.sh: $kernel_pkg and busybox-static:arm64 in $cache"
