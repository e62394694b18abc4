#!/usr/bin/env bash
# Runs tests/mdp/interop_mdp.py against `rackcat run` over a veth pair in a private network
# namespace (needs root): store a parameter, restart rackcat, read it back, check OP refusals.
#   tests/mdp/interop_mdp.sh [BUILD_DIR]      (default: build)
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${1:-build}
[ "$(id -u)" -eq 0 ] || { echo "interop_mdp: needs root (network namespace, raw socket)" >&2; exit 2; }
. scripts/netns.sh
. scripts/python.sh
NS=rackcat-mdp-$$
STATE=$(mktemp -d)
SLAVE=
cleanup() { [ -n "$SLAVE" ] && kill "$SLAVE" 2>/dev/null; netns_down "$NS"; rm -rf "$STATE"; }
trap cleanup EXIT INT TERM
netns_up "$NS" mdp-slave mdp-master
start() {
  ip netns exec "$NS" "$BUILD/rackcat" run --iface mdp-slave --state-dir "$STATE" --no-control \
    --no-pty >>"$STATE/rackcat.log" 2>&1 &
  SLAVE=$!
  sleep 0.5
}
stop() { kill -INT "$SLAVE"; wait "$SLAVE" || true; SLAVE=; }
rc=0
echo "== phase 1: read the dictionary, write 0x2000:04 and store"
start
ip netns exec "$NS" "$PY" tests/mdp/interop_mdp.py mdp-master store 10.20.30.40 || rc=1
stop
echo "== phase 2: after a restart"
start
ip netns exec "$NS" "$PY" tests/mdp/interop_mdp.py mdp-master check 10.20.30.40 || rc=1
stop
[ $rc -eq 0 ] || { echo "== rackcat log:"; tail -n 30 "$STATE/rackcat.log"; }
exit $rc
