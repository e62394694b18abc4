#!/usr/bin/env bash
# tests/cli/validation.sh RACKCAT: each bad rack file below must be refused by od, esi, sii,
# check and run (before run needs an interface) with exit code 2 and the same one-line
# message FILE:LINE: reason; the good examples pass `check`; --version answers everywhere.
set -u
rackcat=$(realpath "${1:?usage: validation.sh RACKCAT}")
root=$(cd "$(dirname "$0")/../.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir" || exit 1
fail=0
header='rims:
  - rim: 1
    type: 6-slot
    slots:
      - {slot: 1, card: CDO-10}'
declare -A expect
bad() {  # bad NAME EXPECTED-MESSAGE YAML-TAIL
  printf '%s\n%s\n' "$header" "$3" >"$1.yaml"
  expect[$1]=$2
}
bad amplitud "amplitud.yaml:9: RIM 1 slot 2 channel 0: sine: unknown parameter 'amplitud' (known: amplitude, frequency, period_s, offset, phase)" \
'      - slot: 2
        card: CAI-15
        channels:
          - {channel: 0, source: sine, amplitud: 5.0}'
bad cardopt "cardopt.yaml:6: slot 2: card CAI-15 has no option 'colour' (or 'red' is not a number)" \
'      - {slot: 2, card: CAI-15, colour: red}'
bad replay "replay.yaml:9: RIM 1 slot 2 channel 0: missing.csv: no such file below ." \
'      - slot: 2
        card: CAI-15
        channels:
          - {channel: 0, source: replay, file: missing.csv}'
bad noinputs "noinputs.yaml:9: RIM 1 slot 2 channel 0: module 2 (CDO-10) has 0 input channels" \
'      - slot: 2
        card: CDO-10
        channels:
          - {channel: 0, source: constant, value: 1}'
bad crad "crad.yaml:7: slot 2: unknown key 'crad' (a slot entry needs 'card')" \
'      - slot: 2
        crad: CDO-10'
expect[nonexist]="nonexist.yaml: cannot read the rack file: No such file or directory"

for name in "${!expect[@]}"; do
  for cmd in "od" "esi -o out.xml" "sii -o out.bin" "check" "run --iface rackcat-no-such0 --no-control --no-pty --state-dir $dir/state"; do
    if [ "$cmd" = check ]; then args=(check "$name.yaml"); else args=($cmd --config "$name.yaml"); fi
    out=$("$rackcat" "${args[@]}" 2>&1 >/dev/null)
    rc=$?
    if [ "$rc" -ne 2 ] || [ "$out" != "${expect[$name]}" ]; then
      echo "FAIL: rackcat ${args[*]}: exit $rc, said '$out'; expected exit 2 and '${expect[$name]}'"
      fail=1
    fi
  done
done

for f in "$root"/examples/*.yaml; do
  out=$("$rackcat" check "$f" 2>&1) || { echo "FAIL: check $f: $out"; fail=1; continue; }
  grep -q "^$f: ok$" <<<"$out" || { echo "FAIL: check $f printed: $out"; fail=1; }
  grep -q "^process data (default assignment): " <<<"$out" || { echo "FAIL: no summary for $f"; fail=1; }
done
for sub in "" od esi sii check run ctl rim; do
  out=$("$rackcat" $sub --version 2>&1) && [[ $out == "rackcat "[0-9]*" (git "*")" ]] ||
    { echo "FAIL: rackcat $sub --version: $out"; fail=1; }
done
out=$("$rackcat" od --layout) || { echo "FAIL: od --layout"; fail=1; }
grep -qE '^ +0 +0 +0 +16  0x1600  7000:01 ' <<<"$out" || { echo "FAIL: od --layout: first output entry"; fail=1; }
[ "$fail" -eq 0 ] && echo "cli validation: ok"
exit "$fail"
