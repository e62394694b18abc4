#!/usr/bin/env bash
# Instructions per slave of one master cycle (one LRW frame; 1,024 slaves: two) through `rackcat run`'s line of tiny racks, whole
# stack (bench_rack_line: Segment::process of the master's LRW, then the firmware and
# application round after_frame runs), counted by callgrind: the inclusive cost of
# rack_line_cycle over its calls and the slaves. The in-process counterpart of op_bench's
# per-slave figure; load-independent, so two builds can be compared on a busy machine. Needs
# valgrind (Debian package valgrind).
#
#   scripts/callgrind_line.sh BENCH_RACK_LINE SLAVES...   e.g. build/bench/ecat/bench_rack_line 16 199
# BENCHMARK=BM_RackLineCycle: outputs changing every frame (default BM_RackLineCycleSteady, the
# master repeating them, as op_bench's replay); DC=1 adds the FRMW 0x0910 to the frame.
# CACHE=1 also simulates the caches and prints the L1 data misses (reads + writes) per slave
# and frame: at 199 slaves the round is bound by the cache lines each slave touches.
# MIN_TIME (default 0.1 s of benchmark time): fewer frames let the first one, which still
# changes the outputs, weigh in the "repeated" figures.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 BENCH_RACK_LINE SLAVES..." >&2
  exit 2
fi
bench=$1
shift
benchmark=${BENCHMARK:-BM_RackLineCycleSteady}
dc=${DC:-0}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for n in "$@"; do
  cache=()
  show=Ir
  if [ "${CACHE:-0}" = 1 ]; then
    cache=(--cache-sim=yes)
    show=Ir,D1mr,D1mw
  fi
  valgrind --tool=callgrind "${cache[@]}" --callgrind-out-file="$out/cg.$n" "$bench" \
    --benchmark_filter="^$benchmark/$n/$dc\$" --benchmark_min_time="${MIN_TIME:-0.1}" >/dev/null 2>&1
  # The callers' lines above rack_line_cycle's own line carry its inclusive cost and call count.
  callgrind_annotate --show="$show" --inclusive=yes --threshold=100 --tree=caller "$out/cg.$n" |
    awk -v n="$n" '
      /^$/ { cost = 0; misses = 0; calls = 0; next }
      / < .*\([0-9,]+x\)/ {
        split($0, head, " < "); k = split(head[1], f, " "); v = 0
        for (i = 1; i <= k; ++i) {
          if (f[i] !~ /^[0-9,]+$/) continue
          x = f[i]; gsub(/,/, "", x); ++v
          if (v == 1) cost += x; else misses += x
        }
        match($0, /\(([0-9,]+)x\)/)
        c = substr($0, RSTART + 1, RLENGTH - 3); gsub(/,/, "", c); calls += c; next }
      / \* .*rack_line_cycle/ && calls > 0 && !done {
        printf "%d slaves: %.0f instructions per cycle (%.0f per slave, %d cycles)",
               n, cost / calls, cost / calls / n, calls
        if (misses > 0) printf ", %.1f L1 data misses per slave", misses / calls / n
        printf "\n"; done = 1 }'
done
