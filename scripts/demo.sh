#!/usr/bin/env bash
# The README's run command: set up, build, and show the built-in default rack driven to OP by a
# real EtherCAT master (pysoem/SOEM) over a veth pair in a private network namespace.
#   scripts/demo.sh [--seconds N] [--config FILE]
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_LIVE=3
CONFIG=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) SECONDS_LIVE=$2; shift 2 ;;
    --config) CONFIG=(--config "$(realpath "$2")"); shift 2 ;;
    *) echo "usage: scripts/demo.sh [--seconds N] [--config FILE]" >&2; exit 2 ;;
  esac
done
if [ "$(id -u)" -ne 0 ]; then
  echo "demo: creating a network namespace and a veth pair needs root; run it as root (sudo)." >&2
  exit 2
fi

echo "== setting up (Debian and PyPI packages, once)"
bash scripts/setup.sh >/dev/null
echo "== building (release)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" --target rackcat >/dev/null

. scripts/netns.sh
NS=rackcat-demo-$$
STATE=$(mktemp -d)
cleanup() { netns_down "$NS"; rm -rf "$STATE"; }
trap cleanup EXIT INT TERM
netns_up "$NS" ecat-slave ecat-master

echo "== starting: build/rackcat run --iface ecat-slave (default rack) in namespace $NS"
ip netns exec "$NS" build/rackcat run --iface ecat-slave --state-dir "$STATE" "${CONFIG[@]}" \
  >"$STATE/rackcat.log" 2>&1 &
SLAVE=$!
sleep 0.5
if ! kill -0 "$SLAVE" 2>/dev/null; then cat "$STATE/rackcat.log"; exit 1; fi

echo "== master: pysoem $(python3 -c 'import pysoem; print(pysoem.__version__)') on ecat-master"
ip netns exec "$NS" python3 scripts/demo_master.py ecat-master --seconds "$SECONDS_LIVE"
kill -INT "$SLAVE"; wait "$SLAVE" || true
echo "== rackcat said:"
sed 's/^/   /' "$STATE/rackcat.log" | tail -n 20
