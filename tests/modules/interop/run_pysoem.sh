#!/usr/bin/env bash
# Interop checks of the modules behaviour with pysoem over a veth pair in a private network
# namespace (root; nothing touches the host's interfaces). Usage:
#   tests/modules/interop/run_pysoem.sh [build-dir]      (default: build)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
build=${1:-$root/build}
rackcat=$build/rackcat
source "$root/scripts/netns.sh"
source "$root/scripts/python.sh"
ns=rackcat-modules-$$
state=$(mktemp -d)
log=$state/run.log
cleanup() { netns_down "$ns"; rm -rf "$state"; }
trap cleanup EXIT
netns_up "$ns" rcm0 rcm1
ip netns exec "$ns" "$rackcat" run --iface rcm0 --control-port 18767 --state-dir "$state" >"$log" 2>&1 &
for _ in $(seq 50); do grep -q "control API on" "$log" && break; sleep 0.1; done
pty=$(grep "channel 0:" "$log" | head -1 | awk '{print $NF}')
ip netns exec "$ns" "$PY" "$here/check_modules.py" rcm1 "$pty" "$rackcat" 18767 "$state"
