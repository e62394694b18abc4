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

echo "== setting up: only what the demo needs (scripts/setup.sh --demo; the tests add the rest)"
bash scripts/setup.sh --demo
. scripts/python.sh
echo "== building the CLI (release, build/rackcat)"
opts=()
# The demo builds only the CLI: without GoogleTest (a test dependency) configure the build
# without the test suite; scripts/test.sh turns it back on.
dpkg-query -W -f='${Status}' libgtest-dev 2>/dev/null | grep -q "install ok installed" ||
  opts+=(-DRACKCAT_TESTS=OFF -DRACKCAT_BENCH=OFF)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "${opts[@]}" >/dev/null
# Ninja's progress ([done/total] step): one updating line on a terminal, every line otherwise;
# on failure, the end of the build's output.
progress() {
  if [ -t 1 ]; then
    local w=$(( $(tput cols 2>/dev/null || echo 100) - 4 ))
    while IFS= read -r line; do printf '\r\033[K   %s' "${line:0:$w}"; done
    echo
  else
    sed 's/^/   /'
  fi
}
BUILD_LOG=$(mktemp)
if ! cmake --build build -j "$(nproc)" --target rackcat 2>&1 | tee "$BUILD_LOG" | progress; then
  echo "demo: the build failed; its last lines:" >&2
  tail -n 40 "$BUILD_LOG" >&2
  rm -f "$BUILD_LOG"
  exit 1
fi
rm -f "$BUILD_LOG"
[ -x build/rackcat ] || { echo "demo: the build failed" >&2; exit 1; }

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

echo "== master: pysoem $("$PY" -c 'import pysoem; print(pysoem.__version__)') on ecat-master"
status=0
ip netns exec "$NS" "$PY" scripts/demo_master.py ecat-master --seconds "$SECONDS_LIVE" || status=$?
kill -INT "$SLAVE"; wait "$SLAVE" || true
echo "== rackcat said:"
sed 's/^/   /' "$STATE/rackcat.log" | tail -n 20
[ "$status" -eq 0 ] || echo "demo: the master saw a problem (exit $status, see above)" >&2
exit "$status"
