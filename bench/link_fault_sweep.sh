#!/bin/sh
# SPDX-License-Identifier: MIT
# The fault sweep of docs/protocol.md §6: `fdsurf stream FILE --faults P`
# on the simulated plotter for every rate and 20 seeds, one table row per
# rate. Each run's drawing (the SVG of what the plotter drew, from its
# recorded pulses) is compared with the fault-free run's.
#
#   bench/link_fault_sweep.sh build/fdsurf [FILE] [RATES] [SEEDS]
#   bench/link_fault_sweep.sh build/fdsurf examples/teapot.bpt "0.01 0.05 0.12 0.15 0.2 0.25 0.3" 20
#
# The teapot takes about a second of wall time per run; the CI runs the
# link-level sweep instead (fdsurf_link_tests, Rates/LinkSweep.*).
set -eu
fdsurf=${1:?usage: $0 path/to/fdsurf [file] [rates] [seeds]}
file=${2:-examples/teapot.bpt}
rates=${3:-0 0.05 0.12 0.15 0.2 0.25 0.3}
seeds=${4:-20}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

"$fdsurf" stream "$file" --quiet --svg "$tmp/clean.svg" >/dev/null 2>&1
printf '| fault rate (each of 5) | finished | gave up cleanly (exit 3) | other | same drawing | commands resent (median, max) | timeouts (median, max) | frames sent (median) | machine time (max) |\n'
printf '|---|---|---|---|---|---|---|---|---|\n'
for rate in $rates; do
  : >"$tmp/rows"
  finished=0 clean=0 other=0 same=0
  seed=1
  while [ "$seed" -le "$seeds" ]; do
    set +e
    "$fdsurf" stream "$file" --faults "$rate" --seed "$seed" --svg "$tmp/run.svg" \
      >/dev/null 2>"$tmp/log"
    rc=$?
    set -e
    if [ "$rc" -eq 0 ]; then
      finished=$((finished + 1))
      cmp -s "$tmp/clean.svg" "$tmp/run.svg" && same=$((same + 1))
      # link: N frames sent (C commands, R resent), B bytes ..., K NAKs, T timeouts; ...
      sed -n 's/^link: \([0-9]*\) frames sent ([0-9]* commands, \([0-9]*\) resent).* \([0-9]*\) timeouts.*/\1 \2 \3/p' "$tmp/log" >>"$tmp/rows"
      sed -n 's/^machine: \([0-9.]*\) s,.*/\1/p' "$tmp/log" >>"$tmp/times"
    elif [ "$rc" -eq 3 ] && grep -q "no answer from the device after" "$tmp/log"; then
      clean=$((clean + 1))
    else
      other=$((other + 1))
      sed -n '$p' "$tmp/log" >&2
    fi
    seed=$((seed + 1))
  done
  # median and max of a column of "$tmp/rows" (frames resent timeouts)
  col() { cut -d' ' -f"$1" "$tmp/rows" | sort -n | awk '{v[NR] = $1} END {
    if (NR == 0) print "—"; else printf "%d, %d", v[int((NR + 1) / 2)], v[NR] }'; }
  median() { col "$1" | cut -d, -f1; }
  stats="$(col 2) | $(col 3) | $(median 1)"
  tmax=$(sort -n "$tmp/times" 2>/dev/null | tail -1)
  : >"$tmp/times"
  printf '| %s %% | %d of %d | %d | %d | %d of %d | %s | %s s |\n' \
    "$(awk "BEGIN {print $rate * 100}")" "$finished" "$seeds" "$clean" "$other" "$same" "$finished" \
    "$stats" "${tmax:-—}"
done
