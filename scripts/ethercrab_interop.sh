#!/usr/bin/env bash
# Interop run with the ethercrab master (interop/ethercrab) against rackcat over a veth pair in a
# private network namespace: the slave on one end, ethercrab on the other, nothing on the host's
# interfaces. Runs a single slave and a segment of 16 (override with --sizes).
#
#   scripts/ethercrab_interop.sh [--slave "CMD ARGS"] [--mode rackcat|testslave|op]
#                                [--sizes "1 16"] [--cycles N] [-- extra ethercrab-interop args]
#   scripts/ethercrab_interop.sh --test-line [--cycles N]
#
# --test-line  the user's-own-line test (docs/LINE.md): `rackcat run --line` of coupler + 8-ch
#           DI + 8-ch DO + CoE analog terminal (tests/device/data/rackcat-test-devices.xml) +
#           Fusion.IO rack (examples/tiny-rack.yaml) with the DO wired to the DI; ethercrab
#           (--mode line) checks the 5 product codes in order, maps the process data, reaches
#           OP and sees its DO patterns come back on the DI across the two devices.
# --slave   the slave command; the script appends `--iface IF --slaves N`. Default:
#           `build/rackcat run` when built (mode rackcat), else the ecat test slave
#           build/ecat_wire_slave (mode testslave: no CoE, whole output
#           image echoed on the inputs).
# --mode    which checks ethercrab-interop runs (default: rackcat for rackcat, testslave for
#           the test slave, guessed from the command name); op: only up to OP and --cycles
#           cycles, for lines longer than SOEM configures (interop/ethercrab/src/op.rs).
# Environment: BUILD_DIR (default build), CARGO_JOBS (default 2), SLAVE_START_SECONDS (default 10,
# how long to wait for the slave to come up), MASTER_TIMEOUT_SECONDS (default 600, per run),
# RUST_LOG (ethercrab's log level).
#
# Needs root (network namespaces, raw sockets): without it the script says so and exits 0.
# Exit status: 0 when every run passed (or skipped), 1 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
BUILD_DIR=${BUILD_DIR:-build}
CARGO_JOBS=${CARGO_JOBS:-2}
SLAVE_START_SECONDS=${SLAVE_START_SECONDS:-10}
MASTER_TIMEOUT_SECONDS=${MASTER_TIMEOUT_SECONDS:-600}

slave_cmd=""
mode=""
test_line=0
slaves_arg=1  # append --slaves N to the slave command (not for a line: its file says)
sizes="1 16"
cycles=10000
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --slave) slave_cmd=$2; shift 2 ;;
    --mode) mode=$2; shift 2 ;;
    --sizes) sizes=$2; shift 2 ;;
    --cycles) cycles=$2; shift 2 ;;
    --test-line) test_line=1; shift ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n '2,28p' "$0"; exit 0 ;;
    *) echo "ethercrab_interop: unknown argument $1" >&2; exit 2 ;;
  esac
done

if [ "$(id -u)" -ne 0 ]; then
  echo "ethercrab_interop: SKIPPED: needs root for network namespaces and raw sockets (run as root or under sudo)"
  exit 0
fi
# rustup installs cargo under ~/.cargo/bin, which a non-login shell may not have on PATH.
if ! command -v cargo >/dev/null 2>&1 && [ -x "${CARGO_HOME:-$HOME/.cargo}/bin/cargo" ]; then
  PATH="${CARGO_HOME:-$HOME/.cargo}/bin:$PATH"
fi
for tool in ip cargo; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "ethercrab_interop: FAILED: '$tool' not found (scripts/setup.sh installs it)" >&2
    exit 1
  fi
done

line_dir=""
if [ "$test_line" = 1 ]; then
  line_dir=$(mktemp -d /tmp/ethercrab_line.XXXXXX)
  cp tests/device/data/rackcat-test-devices.xml examples/tiny-rack.yaml "$line_dir/"
  cat >"$line_dir/line.yaml" <<'LINE'
devices:
  - {esi: rackcat-test-devices.xml, device: RC1100}
  - {esi: rackcat-test-devices.xml, device: RC1008, name: di}
  - {esi: rackcat-test-devices.xml, device: RC2008, name: do}
  - {esi: rackcat-test-devices.xml, device: RC3102}
  - {rack: tiny-rack.yaml}
wiring:
  - {from: do, to: di, bits: 8}
LINE
  slave_cmd="$BUILD_DIR/rackcat run --no-pty --no-control --state-dir $line_dir/state --line $line_dir/line.yaml"
  mode=line
  sizes=5
  slaves_arg=0
  # Concatenated images in line order: the DO's 8 output bits are bits 0..7 of all outputs,
  # the DI's 8 input bits are bits 0..7 of all inputs.
  extra=(--wire 0:0,1:1,2:2,3:3,4:4,5:5,6:6,7:7
    --expect-products 0x1100,0x1008,0x2008,0x3102,0x00464E01 "${extra[@]}")
fi

if [ -z "$slave_cmd" ]; then
  if [ -x "$BUILD_DIR/rackcat" ] && "$BUILD_DIR/rackcat" run --help >/dev/null 2>&1; then
    slave_cmd="$BUILD_DIR/rackcat run"
  elif [ -x "$BUILD_DIR/ecat_wire_slave" ]; then
    slave_cmd="$BUILD_DIR/ecat_wire_slave"
    echo "ethercrab_interop: $BUILD_DIR/rackcat run not available, using the ecat test slave"
  else
    echo "ethercrab_interop: FAILED: no slave to test: neither $BUILD_DIR/rackcat (with 'run')" \
      "nor $BUILD_DIR/ecat_wire_slave is built" >&2
    exit 1
  fi
fi
if [ -z "$mode" ]; then
  case "$slave_cmd" in
    *ecat_wire_slave*) mode=testslave ;;
    *) mode=rackcat ;;
  esac
fi

# Real-time priority for the slave and the master, as an EtherCAT master normally runs: on a
# loaded 2-core machine plain scheduling delays alone exceed ethercrab's 10 ms EEPROM and 30 ms
# PDU timeouts. Both block in recv, so SCHED_FIFO does not starve the machine.
rt=()
if command -v chrt >/dev/null 2>&1 && chrt -f 10 true 2>/dev/null; then
  rt=(chrt -f 10)
else
  echo "ethercrab_interop: note: chrt -f unavailable, running at normal priority (timeouts more likely under load)"
fi

echo "ethercrab_interop: building interop/ethercrab (cargo, crates.io)"
cargo build --release --locked -j "$CARGO_JOBS" --manifest-path interop/ethercrab/Cargo.toml
# the program's own unit tests (SII decoding, loopback checker, WKC model, raw CoE counters)
cargo test --release --locked -j "$CARGO_JOBS" --manifest-path interop/ethercrab/Cargo.toml --quiet
master="$ROOT/interop/ethercrab/target/release/ethercrab-interop"

logdir=$(mktemp -d /tmp/ethercrab_interop.XXXXXX)
ns=""
slave_pid=""
cleanup() {
  if [ -n "$slave_pid" ]; then
    kill "$slave_pid" 2>/dev/null || true
    # SIGTERM ends the slave cleanly; SIGKILL after 5 s so cleanup never hangs
    for _ in $(seq 1 50); do kill -0 "$slave_pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$slave_pid" 2>/dev/null || true
    wait "$slave_pid" 2>/dev/null || true
    slave_pid=""
  fi
  if [ -n "$ns" ]; then
    ip netns del "$ns" 2>/dev/null || true
    ns=""
  fi
  if [ -n "$line_dir" ] && [ "${1:-}" = final ]; then
    rm -rf "$line_dir"
  fi
}
trap 'cleanup final' EXIT
trap 'exit 130' INT TERM

failed=0
summary=()
for n in $sizes; do
  ns="rcecrab-$$-$n"
  if_slave="ecs$n"
  if_master="ecm$n"
  ip netns add "$ns"
  ip -n "$ns" link add "$if_slave" type veth peer name "$if_master"
  for i in "$if_slave" "$if_master"; do
    # no IPv6 router solicitations or other chatter on the EtherCAT link
    ip netns exec "$ns" sysctl -qw "net.ipv6.conf.$i.disable_ipv6=1" || true
    ip -n "$ns" link set "$i" up
  done
  # the slave's control API (rackcat run) listens on 127.0.0.1 inside the namespace
  ip -n "$ns" link set lo up

  slave_log="$logdir/slave-$n.log"
  master_log="$logdir/ethercrab-$n.log"
  count=()
  [ "$slaves_arg" = 1 ] && count=(--slaves "$n")
  echo "ethercrab_interop: [$n slave(s)] $slave_cmd --iface $if_slave ${count[*]}"
  # shellcheck disable=SC2086  # the slave command is a command line on purpose
  ip netns exec "$ns" "${rt[@]}" $slave_cmd --iface "$if_slave" "${count[@]}" >"$slave_log" 2>&1 &
  slave_pid=$!

  # The slave is up when its raw socket is open on the interface (it shows in the
  # namespace's packet sockets); give up after SLAVE_START_SECONDS.
  up=0
  for _ in $(seq 1 $((SLAVE_START_SECONDS * 10))); do
    if ! kill -0 "$slave_pid" 2>/dev/null; then break; fi
    if ip netns exec "$ns" cat /proc/net/packet 2>/dev/null | awk 'NR>1' | grep -q .; then
      up=1
      break
    fi
    sleep 0.1
  done
  if [ "$up" != 1 ]; then
    echo "ethercrab_interop: FAILED [$n]: the slave did not come up; its output:" >&2
    tail -n 40 "$slave_log" >&2 || true
    failed=1
    summary+=("$n slave(s): FAILED (slave did not start)")
    cleanup
    continue
  fi
  # Let the slave finish whatever it does after opening the socket.
  sleep 0.3

  rc=0
  # bounded whatever happens: ethercrab's own timeouts end every wait, this is the backstop
  timeout --signal=KILL "$MASTER_TIMEOUT_SECONDS" ip netns exec "$ns" "${rt[@]}" "$master" --iface "$if_master" --expect-slaves "$n" --mode "$mode" \
    --cycles "$cycles" "${extra[@]}" 2>&1 | tee "$master_log" || rc=${PIPESTATUS[0]}
  if ! kill -0 "$slave_pid" 2>/dev/null; then
    echo "ethercrab_interop: the slave exited during the run; its output:" >&2
    tail -n 40 "$slave_log" >&2 || true
    rc=${rc:-1}
    [ "$rc" -eq 0 ] && rc=1
  fi
  if [ "$rc" -eq 0 ]; then
    summary+=("$n slave(s): passed")
  else
    failed=1
    summary+=("$n slave(s): FAILED (exit $rc), logs in $logdir")
    echo "ethercrab_interop: slave output (last 20 lines):" >&2
    tail -n 20 "$slave_log" >&2 || true
  fi
  cleanup
done

echo
echo "ethercrab_interop summary ($mode, slave: $slave_cmd):"
for line in "${summary[@]}"; do echo "  $line"; done
if [ "$failed" -eq 0 ]; then
  rm -rf "$logdir"
  exit 0
fi
exit 1
