#!/usr/bin/env bash
# Instructions per slave of the application's cyclic work (bench_modules' BM_TinyRackRound:
# mdp::Device::write_outputs + read_inputs of N tiny racks in OP, drivers and process image
# included), counted by callgrind: the inclusive cost of those calls divided by their number.
# Independent of the machine's load, so two builds can be compared on a busy machine (the
# application's share of issue 16's per-slave cost; scripts/callgrind_frame.sh counts the ESC
# and firmware side). Needs valgrind (Debian package valgrind).
#
#   scripts/callgrind_app.sh BENCH_MODULES SLAVES...   e.g. build/bench/modules/bench_modules 16
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 BENCH_MODULES SLAVES..." >&2
  exit 2
fi
bench=$1
shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for n in "$@"; do
  valgrind --tool=callgrind --callgrind-out-file="$out/cg.$n" "$bench" \
    --benchmark_filter="BM_TinyRackRound/$n\$" --benchmark_min_time=0.02 >/dev/null 2>&1
  callgrind_annotate --inclusive=yes --tree=caller "$out/cg.$n" |
    grep -B3 -E '\* .*Device::(write_outputs|read_inputs)\(' | grep 'BM_TinyRackRound' |
    sed -E 's/^ *([0-9,]+) .*\(([0-9,]+)x\).*/\1 \2/' | tr -d , |
    awk -v n="$n" '{ ir += $1; calls[NR] = $2 }
      END { printf "%d slaves: %.0f instructions per slave (outputs + inputs, %d calls)\n",
                   n, ir / calls[1], calls[1] }'
done
