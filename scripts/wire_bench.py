#!/usr/bin/env python3
"""Round-trip latency of EtherCAT frames over a veth pair: our slave against the floor.

Creates a private network namespace holding a veth pair (ecat-slave, ecat-master). On the
slave end it runs, in turn, (a) bench/ecat/echo_responder, which only bumps working counters
(the floor: a raw socket and nothing else), and (b) the slave under test; on the master end
bench/ecat/wire_pinger sends one frame at a time and times each round trip. Both wait modes
(blocking receive, busy-poll) are measured; the targets alternate in several rounds so that
machine noise hits both alike. Prints p50/p90/p99 per mode, frame and target, and the ratios
of the slave to the floor (target: p50 and p99 within 1.3x).

    sudo scripts/wire_bench.py [--build-dir build] [--samples 20000] [--slaves 1]
        [--slave-cmd "build/ecat_wire_slave --iface {iface} --slaves {slaves}"]

The slave command is a template ({iface}, {slaves}); --busy-poll is appended in busy-poll
mode. Frames: BRD of register 0x0000 (2 bytes) and LRW of 8 bytes per slave, which the pinger
first maps onto each slave's process RAM with FMMU0 so the FMMU path is exercised.
"""
import argparse
import os
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
NS = f"rackcat-bench-{os.getpid()}"
SLAVE_IF = "ecat-slave"
MASTER_IF = "ecat-master"


def sh(*cmd, check=True):
    return subprocess.run(cmd, check=check, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)


def netns_up():
    sh("ip", "netns", "add", NS)
    sh("ip", "-n", NS, "link", "add", SLAVE_IF, "type", "veth", "peer", "name", MASTER_IF)
    for i in (SLAVE_IF, MASTER_IF):
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


def find(build, name):
    for cand in (build / "bench" / "ecat" / name, build / name):
        if cand.exists():
            return cand
    sys.exit(f"wire_bench: {name} not found under {build}; build the target '{name}' first")


class Target:
    def __init__(self, cmd, log):
        self.log = log
        self.proc = subprocess.Popen(["ip", "netns", "exec", NS] + cmd, stdout=log,
                                     stderr=subprocess.STDOUT)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode


def ping(pinger, frame, count, slaves, busy, samples_file, setup_fmmu=False, warmup=200):
    cmd = ["ip", "netns", "exec", NS, str(pinger), "--iface", MASTER_IF, "--frame", frame,
           "--count", str(count), "--warmup", str(warmup), "--slaves", str(slaves),
           "--lrw-bytes", "8", "--samples-out", str(samples_file)]
    if busy:
        cmd.append("--busy-poll")
    if setup_fmmu:
        cmd.append("--setup-fmmu")
    r = sh(*cmd, check=False)
    if r.returncode != 0:
        raise RuntimeError(f"pinger failed: {r.stderr.strip()}")
    return r.stdout


def wait_answering(pinger, slaves, busy, tmp):
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            out = ping(pinger, "brd", 1, slaves, busy, tmp / "probe.txt", warmup=0)
            if '"lost":0' in out:
                return
        except RuntimeError:
            pass
        time.sleep(0.05)
    raise RuntimeError("target did not answer within 10 s")


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
    args = ap.parse_args()
    if os.geteuid() != 0:
        sys.exit("wire_bench: needs root (network namespace, veth pair, raw sockets)")
    build = Path(args.build_dir).resolve()
    echo = find(build, "echo_responder")
    pinger = find(build, "wire_pinger")
    slave_cmd = args.slave_cmd or f"{build}/ecat_wire_slave --iface {{iface}} --slaves {{slaves}}"
    modes = [m for m in args.modes.split(",") if m]
    per_round = max(1, args.samples // args.rounds)

    results = {}  # (mode, frame, target) -> [ns]
    started = time.monotonic()
    tmp = Path(tempfile.mkdtemp(prefix="wire_bench_"))
    netns_up()
    try:
        for mode in modes:
            busy = mode == "busy-poll"
            for rnd in range(args.rounds):
                targets = [("floor", [str(echo), "--iface", SLAVE_IF]),
                           ("slave", [p.format(iface=SLAVE_IF, slaves=args.slaves)
                                      for p in shlex.split(slave_cmd)])]
                if rnd % 2:
                    targets.reverse()
                for name, cmd in targets:
                    if busy:
                        cmd = cmd + ["--busy-poll"]
                    with open(tmp / f"{name}.log", "a") as log:
                        t = Target(cmd, log)
                        try:
                            wait_answering(pinger, args.slaves, busy, tmp)
                            for frame in ("brd", "lrw"):
                                f = tmp / "samples.txt"
                                ping(pinger, frame, per_round, args.slaves, busy, f,
                                     setup_fmmu=(frame == "lrw"))
                                vals = [int(x) for x in f.read_text().split()]
                                results.setdefault((mode, frame, name), []).extend(vals)
                        finally:
                            rc = t.stop()
                        if rc != 0:
                            log.flush()
                            raise RuntimeError(f"{name} exited with {rc}: "
                                               f"{(tmp / f'{name}.log').read_text()[-2000:]}")
    finally:
        netns_down()

    print(f"wire round trip over veth, {args.slaves} slave(s), "
          f"{args.samples} samples per row, {args.rounds} alternating rounds, "
          f"{time.monotonic() - started:.0f} s")
    print(f"{'mode':10s} {'frame':5s} {'target':6s} {'p50 us':>8s} {'p90 us':>8s} "
          f"{'p99 us':>8s} {'p50 x':>6s} {'p99 x':>6s}  verdict")
    ok = True
    for mode in modes:
        for frame in ("brd", "lrw"):
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
                      f"{p99:8.1f} {r50:5.2f}x {r99:5.2f}x  {verdict}")
    print(f"mean of all slave samples: "
          f"{statistics.fmean(v for k, vs in results.items() if k[2] == 'slave' for v in vs) / 1000:.1f} us")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
