#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The freestanding core may only need what a bare-metal C runtime provides
# (memcpy, memset, compiler helpers): no heap, no exceptions, no RTTI, no C++
# library, no stdio. Lists the core's undefined symbols and fails on any other.
set -euo pipefail
library=$1
undefined=$(nm --undefined-only --format=posix "$library" | awk 'NF >= 2 && $2 == "U" {print $1}' | sort -u)
allowed='^(memcpy|memset|memmove|_ZN6fdsurf.*|__(u)?(div|mod)[sdt]i3|__udivmod[dt]i4)$'
bad=$(echo "$undefined" | grep -Ev "$allowed" | grep -v '^$' || true)
if [ -n "$bad" ]; then
  echo "the core needs symbols a freestanding target does not provide:"
  echo "$bad" | c++filt
  exit 1
fi
echo "core undefined symbols: $(echo "$undefined" | grep -c . || true), all allowed"
