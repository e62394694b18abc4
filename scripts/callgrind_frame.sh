#!/usr/bin/env bash
# Instructions per cyclic frame of bench_ecat's BM_CyclicLrwFrmw, counted by callgrind: the
# inclusive cost of the Segment::process calls made by the benchmark loop (the frame, the
# firmware and application work after_frame() runs for the previous one) divided by their
# number. Unlike the benchmark's time it does not depend on the machine's load, so two builds
# can be compared on a busy machine. Needs valgrind (Debian package valgrind).
#
#   scripts/callgrind_frame.sh BENCH_ECAT SLAVES...   e.g. build/bench/ecat/bench_ecat 16 128
# BENCHMARK=BM_CyclicLrwReplyPath counts the reply path alone (the frame, no firmware).
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 BENCH_ECAT SLAVES..." >&2
  exit 2
fi
bench=$1
shift
benchmark=${BENCHMARK:-BM_CyclicLrwFrmw}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for n in "$@"; do
  valgrind --tool=callgrind --callgrind-out-file="$out/cg.$n" "$bench" \
    --benchmark_filter="$benchmark/$n\$" --benchmark_min_time=0.02 >/dev/null 2>&1
  callgrind_annotate --inclusive=yes --tree=caller "$out/cg.$n" |
    grep -B3 '\* .*Segment::process(std' | grep -E "$benchmark|run_cyclic_frames" |
    sed -E 's/^ *([0-9,]+) .*\(([0-9,]+)x\).*/\1 \2/' | tr -d , |
    awk -v n="$n" '{ printf "%d slaves: %.0f instructions per frame (%.0f per slave, %d frames)\n",
                     n, $1 / $2, $1 / $2 / n, $2 }'
done
