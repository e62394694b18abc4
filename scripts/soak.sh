#!/usr/bin/env bash
# Soak run: rackcat (release build) in a private network namespace, driven by pysoem at 1 kHz
# in OP with concurrent SDO traffic, then with fault injection through the control API.
# Reports working-counter errors, lost frames and rackcat's resident memory at start and end.
#
#   scripts/soak.sh [--minutes N] [--slaves N]      (root; skips with a message otherwise)
#
# RACKCAT_BUILD_DIR selects the build directory holding rackcat (default build/);
# RACKCAT_SOAK_PCAP=FILE makes rackcat record every frame (for diagnosing a failure).
#
# Fails when a cycle without injected faults has a wrong working counter, or when resident
# memory grows. Long runs are recorded in docs/RELIABILITY.md.
set -euo pipefail
cd "$(dirname "$0")/.."
MINUTES=1
SLAVES=1
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) MINUTES=$2; shift 2 ;;
    --slaves) SLAVES=$2; shift 2 ;;
    *) echo "usage: scripts/soak.sh [--minutes N] [--slaves N]" >&2; exit 2 ;;
  esac
done
if [ "$(id -u)" -ne 0 ]; then
  echo "soak: skipped: needs root to create a network namespace and a veth pair"
  exit 0
fi
BUILD=${RACKCAT_BUILD_DIR:-build}
[ -x "$BUILD/rackcat" ] || { cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null;
                             cmake --build "$BUILD" --target rackcat -j "$(nproc)" >/dev/null; }
. scripts/netns.sh
. scripts/python.sh
NS=rackcat-soak-$$
STATE=$(mktemp -d)
cleanup() { netns_down "$NS"; rm -rf "$STATE"; }
trap cleanup EXIT INT TERM
netns_up "$NS" ecat-slave ecat-master
# Real-time priority, as EtherCAT slaves and masters run in the field: on a loaded 2-core
# machine plain scheduling delays exceed SOEM's 2 ms receive timeout now and then.
RT=()
if command -v chrt >/dev/null && chrt -f 40 true 2>/dev/null; then RT=(chrt -f 40); fi
PCAP=()
[ -n "${RACKCAT_SOAK_PCAP:-}" ] && PCAP=(--pcap "$RACKCAT_SOAK_PCAP")
ip netns exec "$NS" "${RT[@]}" "$BUILD/rackcat" run --iface ecat-slave --slaves "$SLAVES" --state-dir "$STATE" \
  --no-pty "${PCAP[@]}" >"$STATE/rackcat.log" 2>&1 &
SLAVE=$!
sleep 0.5
rc=0
ip netns exec "$NS" "$PY" scripts/soak.py ecat-master --pid "$SLAVE" \
  --minutes "$MINUTES" --slaves "$SLAVES" --state-dir "$STATE" || rc=$?
kill -INT "$SLAVE" 2>/dev/null || true
wait "$SLAVE" 2>/dev/null || true
grep -E "stopped" "$STATE/rackcat.log" || true
exit $rc
