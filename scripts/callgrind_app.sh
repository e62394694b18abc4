#!/usr/bin/env bash
# Instructions per slave of the application's cyclic work (bench_modules' BM_TinyRackRound:
# mdp::Device::write_outputs + read_inputs of N tiny racks in OP, drivers and process image
# included), counted by callgrind: the inclusive cost of its round function over the rounds
# and slaves.
# Independent of the machine's load, so two builds can be compared on a busy machine (the
# application's share of issue 16's per-slave cost; scripts/callgrind_frame.sh counts the ESC
# and firmware side). Needs valgrind (Debian package valgrind).
#
#   scripts/callgrind_app.sh BENCH_MODULES SLAVES...   e.g. build/bench/modules/bench_modules 16
#   ROUND=BM_TinyRackRoundSteady scripts/callgrind_app.sh ...   the master repeating its outputs
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 BENCH_MODULES SLAVES..." >&2
  exit 2
fi
bench=$1
shift
round=${ROUND:-BM_TinyRackRound}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for n in "$@"; do
  valgrind --tool=callgrind --callgrind-out-file="$out/cg.$n" "$bench" \
    --benchmark_filter="$round/$n\$" --benchmark_min_time=0.02 >/dev/null 2>&1
  # The inclusive cost of tiny_rack_round (one round over the N slaves) over its calls.
  callgrind_annotate --inclusive=yes --threshold=100 --tree=caller "$out/cg.$n" |
    grep -B1 -E '\* .*tiny_rack_round' | grep "$round(" |
    sed -E 's/^ *([0-9,]+) .*\(([0-9,]+)x\).*/\1 \2/' | tr -d , |
    awk -v n="$n" '{ printf "%d slaves: %.0f instructions per slave (%d rounds)\n",
                     n, $1 / $2 / n, $2 }'
done
