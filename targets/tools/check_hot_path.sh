#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Fails when the stepping code calls a divide, multiply or floating-point
# routine: the steppers must add, shift and compare only, on every target
# (the set-up may divide; it is not in this object).
# Usage: check_hot_path.sh NM OBJECT...
set -euo pipefail
nm=$1
shift
undefined=$("$nm" --undefined-only "$@" | awk 'NF >= 2 {print $NF}' | sort -u)
# Compiler helper names: __aeabi_[u]idiv/ldivmod/lmul/f*/d*, __[u]divdi3,
# __muldi3, __mulsi3, __udivmodsi4, __addsf3, __fixsfsi, __floatsisf, ...
bad=$(echo "$undefined" | grep -E 'div|mod|mul|^__aeabi_([fd]|[iu]2[fd]|u?l2[fd])|[sdt]f[23]$|^__fix|^__float|^__extend|^__trunc' || true)
if [ -n "$bad" ]; then
  echo "the stepping code calls routines a hot loop must not:" >&2
  echo "$bad" >&2
  exit 1
fi
echo "stepping code: $(echo "$undefined" | grep -c . || true) undefined symbols, none a divide, multiply or float routine:"
echo "$undefined"
