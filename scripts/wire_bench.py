#!/usr/bin/env python3
"""Round-trip latency of EtherCAT frames over veth: the slave under test against the floor.

Creates a private network namespace with two veth pairs. On one pair runs the floor,
bench/ecat/echo_responder (a raw socket that only bumps working counters); on the other the
slave under test (build/ecat_wire_slave by default). bench/ecat/wire_pinger sends one frame at
a time from the master ends and times each round trip.

  blocking mode   both responders sleep in the kernel; the pinger alternates frame by frame
                  between the two pairs, so both see exactly the same machine noise.
  busy-poll mode  each responder spins on its socket; two spinners would starve each other on
                  a 2-core machine, so the targets run one at a time in alternating rounds. The
                  pinger itself blocks unless --pinger-busy-poll.

Frames: BRD of register 0x0000 (2 bytes) and LRW of 8 bytes per slave, which the pinger first
maps onto each slave's process RAM with FMMU0 so the FMMU path is exercised. Prints p50/p90/p99
per mode, frame and target, frames lost (no reply in 10 ms) and the ratios of the slave to the
floor (target: p50 and p99 within 1.3x). Exit status 1 when a ratio is over 1.3.

    sudo scripts/wire_bench.py [--build-dir build] [--samples 20000] [--slaves 1]
        [--slave-cmd "build/ecat_wire_slave --iface {iface} --slaves {slaves}"]

The slave command is a template ({iface}, {slaves}); --busy-poll is appended in busy-poll
mode. The same works for `build/rackcat run --iface {iface}`.

--fifo PRIO runs the pinger and both responders under SCHED_FIFO (chrt), which takes the
other processes of a shared machine out of the comparison (diagnosis; the target is measured
without it).

With --sync-seconds S (and pysoem installed), each mode also runs the slave with DC SYNC0 at
1 ms under a pysoem master cycling at 1 ms for S seconds, and prints the SYNC0 jitter line the
slave reports on exit (ecat_wire_slave prints one; other slaves may not).
"""
import argparse
import json
import os
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
NS = f"rackcat-bench-{os.getpid()}"
PAIRS = {"slave": ("ecat-slave", "ecat-master"), "floor": ("echo-slave", "echo-master")}
FRAMES = ("brd", "lrw")


def sh(*cmd, check=True):
    return subprocess.run(cmd, check=check, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)


def netns_up():
    sh("ip", "netns", "add", NS)
    for a, b in PAIRS.values():
        sh("ip", "-n", NS, "link", "add", a, "type", "veth", "peer", "name", b)
        for i in (a, b):
            sh("ip", "netns", "exec", NS, "sysctl", "-qw", f"net.ipv6.conf.{i}.disable_ipv6=1",
               check=False)
            sh("ip", "-n", NS, "link", "set", i, "up")
    sh("ip", "-n", NS, "link", "set", "lo", "up")


def netns_down():
    for pid in sh("ip", "netns", "pids", NS, check=False).stdout.split():
        try:
            os.kill(int(pid), signal.SIGKILL)
        except (ProcessLookupError, ValueError):
            pass
    sh("ip", "netns", "del", NS, check=False)


# CPU placement (--pin): on a 2-core VM the round trip is bimodal (about 11 us when the
# woken responder runs on the other core, 20-35 us when it shares the pinger's), for the floor
# and the slave alike; pinning the pinger to CPU 0 and the responders to CPU 1 measures both in
# the same placement.
PIN = {"pinger": [], "responder": []}


def find(build, name):
    for cand in (build / "bench" / "ecat" / name, build / name):
        if cand.exists():
            return cand
    sys.exit(f"wire_bench: {name} not found under {build}; build the target '{name}' first")


class Responder:
    def __init__(self, name, cmd, log_dir):
        self.name = name
        self.log_path = log_dir / f"{name}.log"
        self.log = open(self.log_path, "a")
        self.proc = subprocess.Popen(["ip", "netns", "exec", NS] + PIN["responder"] + cmd,
                                     stdout=self.log,
                                     stderr=subprocess.STDOUT)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()
        if self.proc.returncode != 0:
            raise RuntimeError(f"{self.name} exited with {self.proc.returncode}: "
                               f"{self.log_path.read_text()[-2000:]}")


class Pinger:
    def __init__(self, path, slaves, busy, tmp):
        self.path, self.slaves, self.busy, self.tmp = path, slaves, busy, tmp

    def run(self, names, frame, count, warmup=200):
        """Pings the master ends of `names` in turn; returns {name: (samples_ns, lost)}."""
        out_file = self.tmp / "samples"
        cmd = ["ip", "netns", "exec", NS] + PIN["pinger"] + [str(self.path),
               "--iface", ",".join(PAIRS[n][1] for n in names), "--frame", frame,
               "--count", str(count), "--warmup", str(warmup), "--slaves", str(self.slaves),
               "--lrw-bytes", "8", "--samples-out", str(out_file)]
        if self.busy:
            cmd.append("--busy-poll")
        if frame == "lrw":
            cmd.append("--setup-fmmu")
        r = sh(*cmd, check=False)
        if r.returncode != 0:
            raise RuntimeError(f"pinger failed: {r.stderr.strip()}")
        lines = [json.loads(line) for line in r.stdout.splitlines() if line.strip()]
        result = {}
        for k, (name, line) in enumerate(zip(names, lines)):
            f = out_file if len(names) == 1 else Path(f"{out_file}.{k}")
            result[name] = ([int(x) for x in f.read_text().split()], line["lost"])
        return result

    def wait_answering(self, names, timeout_s=10):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                if all(lost == 0 for _, lost in self.run(names, "brd", 1, warmup=0).values()):
                    return
            except RuntimeError:
                pass
            time.sleep(0.05)
        raise RuntimeError(f"{names} did not answer within {timeout_s} s")


SYNC_MASTER = r"""
import sys, time, pysoem
m = pysoem.Master(); m.open(sys.argv[1])
if m.config_init() <= 0: sys.exit("no slave")
m.config_map(); m.config_dc()
for s in m.slaves: s.dc_sync(True, 1_000_000)
m.state = pysoem.SAFEOP_STATE; m.write_state(); m.state_check(pysoem.SAFEOP_STATE, 2_000_000)
m.send_processdata(); m.receive_processdata(20000)
m.state = pysoem.OP_STATE; m.write_state()
end = time.monotonic() + float(sys.argv[2])
while time.monotonic() < end:
    m.send_processdata(); m.receive_processdata(20000); time.sleep(0.001)
m.state = pysoem.INIT_STATE; m.write_state(); m.close()
"""


def sync_jitter(command, seconds, tmp):
    """Runs the slave under a 1 ms pysoem master with SYNC0 at 1 ms; returns its jitter line."""
    r = Responder("sync", command, tmp)
    try:
        time.sleep(0.3)
        sh("ip", "netns", "exec", NS, sys.executable, "-c", SYNC_MASTER, PAIRS["slave"][1],
           str(seconds))
    finally:
        r.stop()
    lines = [l for l in r.log_path.read_text().splitlines() if "sync0 jitter" in l]
    return lines[-1].strip() if lines else "(the slave printed no sync0 jitter line)"


def pct(values, p):
    values = sorted(values)
    k = min(len(values) - 1, int(round(p / 100 * (len(values) - 1))))
    return values[k] / 1000.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir", default=str(REPO / "build"))
    ap.add_argument("--slave-cmd", default=None,
                    help="slave command template (default: BUILD/ecat_wire_slave ...)")
    ap.add_argument("--samples", type=int, default=20000, help="per mode, frame and target")
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--slaves", type=int, default=1)
    ap.add_argument("--modes", default="blocking,busy-poll")
    ap.add_argument("--pinger-busy-poll", action="store_true",
                    help="the pinger spins too in busy-poll mode")
    ap.add_argument("--sync-seconds", type=float, default=0,
                    help="also measure SYNC0 jitter under a 1 ms pysoem master for S seconds")
    ap.add_argument("--pin", action="store_true",
                    help="pin the pinger to CPU 0 and the responders to CPU 1 (taskset)")
    ap.add_argument("--fifo", type=int, default=0, metavar="PRIO",
                    help="run pinger and responders as SCHED_FIFO PRIO (chrt), so that other "
                         "processes on a shared machine do not delay them; 0 = off")
    args = ap.parse_args()
    if args.pin:
        PIN["pinger"] = ["taskset", "-c", "0"]
        PIN["responder"] = ["taskset", "-c", "1"]
    if args.fifo > 0:
        # Diagnostic isolation, not the target's measurement: a spinning SCHED_FIFO responder
        # keeps its core to itself except for the kernel's RT throttling share (5 %).
        for k in PIN:
            PIN[k] = ["chrt", "-f", str(args.fifo)] + PIN[k]
    if os.geteuid() != 0:
        sys.exit("wire_bench: needs root (network namespace, veth pairs, raw sockets)")
    build = Path(args.build_dir).resolve()
    echo = find(build, "echo_responder")
    pinger_path = find(build, "wire_pinger")
    slave_cmd = args.slave_cmd or (f"{shlex.quote(str(build / 'ecat_wire_slave'))} --iface {{iface}} "
                                  f"--slaves {{slaves}}")
    modes = [m for m in args.modes.split(",") if m]
    per_round = max(1, args.samples // args.rounds)

    def command(name, busy):
        iface = PAIRS[name][0]
        if name == "floor":
            cmd = [str(echo), "--iface", iface]
        else:
            cmd = [p.format(iface=iface, slaves=args.slaves) for p in shlex.split(slave_cmd)]
        return cmd + (["--busy-poll"] if busy else [])

    results = {}  # (mode, frame, target) -> [ns]
    lost = {}
    seconds = {}
    started = time.monotonic()
    tmp = Path(tempfile.mkdtemp(prefix="wire_bench_"))
    netns_up()
    try:
        for mode in modes:
            busy = mode == "busy-poll"
            pinger = Pinger(pinger_path, args.slaves, busy and args.pinger_busy_poll, tmp)
            mode_started = time.monotonic()

            def collect(names, frame):
                for name, (vals, n_lost) in pinger.run(names, frame, per_round).items():
                    results.setdefault((mode, frame, name), []).extend(vals)
                    lost[(mode, frame, name)] = lost.get((mode, frame, name), 0) + n_lost

            if not busy:
                # Both responders up at once; the pinger interleaves them frame by frame.
                running = [Responder(n, command(n, False), tmp) for n in ("floor", "slave")]
                try:
                    pinger.wait_answering(["floor", "slave"])
                    for _ in range(args.rounds):
                        for frame in FRAMES:
                            collect(["floor", "slave"], frame)
                finally:
                    for r in running:
                        r.stop()
            else:
                for rnd in range(args.rounds):
                    order = ["floor", "slave"] if rnd % 2 == 0 else ["slave", "floor"]
                    for name in order:
                        r = Responder(name, command(name, True), tmp)
                        try:
                            pinger.wait_answering([name])
                            for frame in FRAMES:
                                collect([name], frame)
                        finally:
                            r.stop()
            seconds[mode] = time.monotonic() - mode_started
        jitter = {}
        if args.sync_seconds > 0:
            for mode in modes:
                jitter[mode] = sync_jitter(command("slave", mode == "busy-poll"),
                                           args.sync_seconds, tmp)
    finally:
        netns_down()

    print(f"wire round trip over veth, {args.slaves} slave(s), {args.samples} samples per row "
          f"({args.rounds} rounds), {time.monotonic() - started:.0f} s")
    print(f"{'mode':10s} {'frame':5s} {'target':6s} {'p50 us':>8s} {'p90 us':>8s} "
          f"{'p99 us':>8s} {'p50 x':>6s} {'p99 x':>6s} {'lost':>5s}  verdict")
    ok = True
    for mode in modes:
        for frame in FRAMES:
            floor = results[(mode, frame, "floor")]
            f50, f99 = pct(floor, 50), pct(floor, 99)
            for name in ("floor", "slave"):
                v = results[(mode, frame, name)]
                p50, p90, p99 = pct(v, 50), pct(v, 90), pct(v, 99)
                r50, r99 = p50 / f50, p99 / f99
                verdict = ""
                if name == "slave":
                    good = r50 <= 1.3 and r99 <= 1.3
                    ok &= good
                    verdict = "ok (<= 1.3x)" if good else "OVER 1.3x"
                print(f"{mode:10s} {frame.upper():5s} {name:6s} {p50:8.1f} {p90:8.1f} "
                      f"{p99:8.1f} {r50:5.2f}x {r99:5.2f}x {lost[(mode, frame, name)]:5d}  "
                      f"{verdict}")
    print("wall time per mode: " + ", ".join(f"{m} {t:.0f} s" for m, t in seconds.items()))
    for mode, line in jitter.items():
        print(f"{mode:10s} {line}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
