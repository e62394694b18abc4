#!/usr/bin/env python3
"""rackcat in OP on the wire: cyclic LRW against the floor, SDO round trips, memory, threads.

Sibling of scripts/wire_bench.py (same private namespace with two veth pairs, same floor
bench/ecat/echo_responder and pinger bench/ecat/wire_pinger). For each slave count:

  1. `rackcat run --slaves N --config examples/tiny-rack.yaml` on one pair, the floor on the
     other; a pysoem master (config_init, config_map, process-data watchdog 0 = off so the
     slaves stay in OP once it leaves, SAFEOP, OP) brings the slaves to OP and the master's
     own cyclic frame (its LRW, as send_processdata puts it on the wire) is captured from a
     packet socket on the master end. The master exits without touching the AL state.
     From 200 slaves on (SOEM's EC_MAXSLAVE; --master chooses) the master is ethercrab
     (interop/ethercrab --mode op, built with cargo when missing): same steps, and its image
     comes in LRW datagrams of 1,100 bytes, one per frame - 1,024 tiny racks take two. The
     replay then sends a cycle's frames back to back and times the last reply (wire_pinger
     FILE+FILE), as SOEM does with an image larger than one frame.
  2. RSS and thread count of rackcat in OP (/proc/PID/status).
  3. wire_pinger --frame-file replays the captured frame:
       blocking   both responders sleep in the kernel; the pinger alternates frame by frame;
       busy-poll  both run with --busy-poll; only one spins at a time (the other is stopped with
                  SIGSTOP), alternating rounds; the pinger blocks (2 cores).
     The reply's working counter must be the master's expected one (pysoem expected_wkc).
     --placement adds "one CPU" to each row: the share of samples, taken every 10 ms during the
     replay, that found the pinger and rackcat's loop thread last run on the same CPU (off by
     default: the sampling wakes this script on one of the CPUs it measures). On a 2-vCPU
     machine the round trip runs in one of two regimes the scheduler picks: on two CPUs the reply
     has to wake the pinger's (halted) vCPU, on one the pinger's and rackcat's work (the
     firmware round after the reply included) run in series (docs/PERFORMANCE.md, session 15).
     --cycle-us: 0 replays back to back (each frame as soon as the previous reply came); P > 0
     paces the rounds as a master's cycle does (one frame to each responder every P us), so
     the slaves' work after a reply has the rest of the cycle, as with a real master.

Then (--sdo-calls): 2,000 pysoem sdo_read of 0x1018:01 (expedited upload), blocking rackcat,
unpinned, timed one by one in Python (time.perf_counter_ns around the call), and rackcat's CPU
time over --idle-seconds with no traffic. Then (--brd-slaves): rackcat with that many slaves
answering a BRD (working counter = slave count), with RSS and thread count once it answers.

    sudo scripts/op_bench.py [--build-dir build] [--slaves 1,16,64,128,199,256,1024]
        [--master auto|pysoem|ethercrab] [--ethercrab BIN]
        [--modes blocking,busy-poll] [--samples 10000] [--sdo-calls 2000]
        [--brd-slaves 64,128,256,4096] [--firmware-yield-us N] [--huge-heap auto|on|off] [--cycle-us 0,1000] [--placement]

--guest-halt-poll-ns NS (diagnosis, in a KVM guest with the cpuidle-haltpoll driver): sets
/sys/module/haltpoll/parameters/guest_halt_poll_ns for the run and restores it afterwards.
The guest's idle vCPU then polls up to NS before it halts, so a wake-up from the other vCPU -
the pinger's, when a reply arrives while the responder ran elsewhere - costs no halt exit.
The kernel's default is 200000; some VM images set 0 (every idle halts). The table's first
line says which value was in force.

--kickcat BIN --kickcat-slave JSON puts KickCAT's network_simulator (BIN, built by the user from
KickCAT's own source; rackcat ships none of it) in the same run as a third peer on a third veth
pair, every simulated slave built from the slave config JSON (KickCAT's
simulation/slave_configs/freedom-k64f.json is the one that reproduces issue 16's figures). The
same pysoem master brings its slaves to OP and its own cyclic frame is captured. Blocking rows
then add the issue's own method, "medians of alternating rounds": each round also replays
rackcat's frame to rackcat alone and KickCAT's frame to KickCAT alone, back to back (order
alternating between rounds), and the row adds both p50s and their ratio. KickCAT's simulator
is stopped (SIGSTOP) except for its own turns: with no frame its socket polls (recv, a short
sleep, again), and those wake-ups would change the others' numbers. Alone and back to back,
a responder's work after its reply (rackcat's firmware round, KickCAT's routine() of every
slave) delays the next frame whenever the master's next frame comes before it is done - and a
responder that is still busy then does not sleep, so it pays no wake-up. Frame by frame
interleaving (the floor / rackcat columns) hides the one and adds the other. KickCAT's simulator
has no busy-poll mode, so busy-poll rows leave it out, and rows from 200 slaves on too (there
ethercrab configures, and it drops the simulator's replies, which keep the master's source
MAC). The SDO run alternates rackcat and KickCAT in four blocks.

Prints one table; --json FILE also writes the numbers.
"""
import argparse
import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import wire_bench as wb  # noqa: E402  (namespace, responders, pinger)

REPO = wb.REPO
NS = wb.NS
# SOEM's EC_MAXSLAVE: pysoem configures fewer slaves than this.
PYSOEM_MAX = 200

# Both capture scripts end the same way: one cycle's frames, in order, each to a file of its own
# (OUT, or OUT.0, OUT.1, ... for several), and one line for configure(): FILE[+FILE...], the
# master's expected working counter, the one seen, the frames' bytes.
WRITE_CYCLE = r"""
def write_cycle(out, frames, expected, wkc):
    files = [out] if len(frames) == 1 else [f"{out}.{k}" for k in range(len(frames))]
    for path, frame in zip(files, frames):
        open(path, "wb").write(frame)
    print(f"{'+'.join(files)} {expected} {wkc} {sum(len(f) for f in frames)}")
"""

CONFIGURE = WRITE_CYCLE + r"""
import socket, sys, time, pysoem
iface, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
m = pysoem.Master(); m.open(iface)
found = m.config_init()
if found != n: sys.exit(f"found {found} slaves, expected {n}")
m.config_map()
for s in m.slaves: s.set_watchdog("processdata", 0)  # 0 disables it (ETG.1000.4 6.5.3)
m.state = pysoem.SAFEOP_STATE; m.write_state()
if m.state_check(pysoem.SAFEOP_STATE, 10_000_000) != pysoem.SAFEOP_STATE: sys.exit("no SAFEOP")
m.send_processdata(); m.receive_processdata(20000)
m.state = pysoem.OP_STATE; m.write_state()
deadline = time.monotonic() + 20
while m.state_check(pysoem.OP_STATE, 50_000) != pysoem.OP_STATE:
    m.send_processdata(); m.receive_processdata(20000)
    if time.monotonic() > deadline: sys.exit("no OP")
    m.write_state()
# The master's cyclic frame. SOEM sends with PACKET_QDISC_BYPASS, which skips packet taps, so
# what a socket on the master end sees is the reply: the same frame with the source-MAC bit
# set, the inputs filled in and the working counters counted (ETG.1000.4 5.1, 5.2). Setting
# every datagram's working counter back to 0 gives the frame the master sends (the pinger puts
# its own source MAC in). An image larger than one frame comes in several (SOEM cuts it at
# EC_MAXLRWDATA), each with its first datagram at another logical address: all of one cycle are
# kept, in address order, until a cycle adds none.
cap = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x88A4))
cap.bind((iface, 0x88A4)); cap.settimeout(0.1)
wkc = 0
for _ in range(10):
    m.send_processdata(); wkc = m.receive_processdata(20000)
frames, known = {}, -1
for _ in range(50):
    m.send_processdata(); wkc = m.receive_processdata(20000)
    try:
        while True:
            data, addr = cap.recvfrom(2048)
            if data[16] in (0x0A, 0x0B, 0x0C):
                frames[int.from_bytes(data[18:22], "little")] = bytearray(data)
    except socket.timeout:
        pass
    if frames and len(frames) == known: break
    known = len(frames)
if not frames: sys.exit("no LRW/LRD/LWR frame captured")
cycle = [frames[address] for address in sorted(frames)]
for frame in cycle:
    pos, end = 16, 16 + (int.from_bytes(frame[14:16], "little") & 0x7FF)
    while pos + 12 <= end:  # datagrams: 10-byte header, data, 2-byte working counter
        n = int.from_bytes(frame[pos + 6:pos + 8], "little")
        frame[pos + 10 + (n & 0x7FF):pos + 12 + (n & 0x7FF)] = b"\0\0"
        if not n & 0x8000: break  # no more datagrams follow
        pos += 12 + (n & 0x7FF)
write_cycle(out, cycle, m.expected_wkc, wkc)
"""

# From SOEM's EC_MAXSLAVE (200) on, ethercrab configures the line (interop/ethercrab, --mode
# op: OP with the process-data watchdog off, then a few hundred cycles of its tx_rx, then it
# exits and the line stays in OP). Each cycle ethercrab sends its group image as LRW datagrams
# of up to 1,100 bytes, one per frame, each followed by AL status reads of the SubDevices (its
# state checks). As with SOEM, a packet socket on the master end sees only the replies (the
# frame with the source-MAC bit set, inputs filled in, working counters counted; ETG.1000.4
# 5.1, 5.2); the replay keeps their LRW datagrams, one per frame, with the working counter set
# back to 0: the master's cyclic LRW, in as many frames as its image needs.
CONFIGURE_ETHERCRAB = WRITE_CYCLE + r"""
import socket, subprocess, sys, time
iface, out, n, binary = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
p = subprocess.Popen([binary, "--iface", iface, "--mode", "op", "--expect-slaves", str(n),
                      "--cycles", "300", "-v"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                     text=True)
log, replies = [], {}
for line in p.stdout:
    log.append(line)
    if line.startswith("PASS OP reached"):  # then 300 cycles of about 1 ms: capture 0.2 s
        cap = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x88A4))
        cap.bind((iface, 0x88A4)); cap.settimeout(0.05)
        end = time.monotonic() + 0.2
        while time.monotonic() < end:
            try:
                data = cap.recv(2048)
            except socket.timeout:
                continue
            pos, stop = 16, 16 + (int.from_bytes(data[14:16], "little") & 0x7FF)
            if not data[6] & 0x02 or pos + 12 > stop or data[pos] != 0x0C:  # a reply, LRW first
                continue
            length = int.from_bytes(data[pos + 6:pos + 8], "little") & 0x7FF
            address = int.from_bytes(data[pos + 2:pos + 6], "little")
            wkc = int.from_bytes(data[pos + 10 + length:pos + 12 + length], "little")
            replies[address] = (bytes(data[pos + 10:pos + 10 + length]), wkc)
        cap.close()
if p.wait() != 0:
    sys.exit("ethercrab --mode op failed:\n" + "".join(log[-20:]))
op = [l.split() for l in log if l.startswith("op:")][0]
image, expected = int(op[4]) + int(op[6]), int(op[10])
cycle, covered, wkc = [], 0, 0
for address in sorted(replies):
    data, reply_wkc = replies[address]
    header = bytes(6 * [0xFF] + 6 * [0] + [0x88, 0xA4])  # the pinger puts its own source MAC
    ecat = (10 + len(data) + 2) | 0x1000  # length, type 1 (datagrams)
    dgram = bytes([0x0C, 0]) + address.to_bytes(4, "little") + len(data).to_bytes(2, "little")
    cycle.append(header + ecat.to_bytes(2, "little") + dgram + b"\0\0" + data + b"\0\0")
    covered += len(data); wkc += reply_wkc
if covered != image:
    sys.exit(f"captured LRW datagrams cover {covered} of the {image}-byte image")
write_cycle(out, cycle, expected, wkc)
"""

SDO = r"""
import sys, time, pysoem
iface, calls = sys.argv[1], int(sys.argv[2])
m = pysoem.Master(); m.open(iface)
if m.config_init() < 1: sys.exit("no slave")
s = m.slaves[0]
for _ in range(50): s.sdo_read(0x1018, 1)
t, failed = [], 0
for _ in range(calls):
    t0 = time.perf_counter_ns()
    try:
        s.sdo_read(0x1018, 1)
    except pysoem.WkcError:  # a frame lost or late (SOEM's timeout): counted, not timed
        failed += 1
        continue
    t.append(time.perf_counter_ns() - t0)
m.close()
print(failed, " ".join(map(str, t)))
"""


HALT_POLL = Path("/sys/module/haltpoll/parameters/guest_halt_poll_ns")


def halt_poll_ns():
    """The guest's halt-poll window in ns, or None when the haltpoll driver is not loaded."""
    try:
        return int(HALT_POLL.read_text())
    except (OSError, ValueError):
        return None


def proc_status(pid):
    fields = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        k, _, v = line.partition(":")
        fields[k] = v.strip()
    return int(fields["VmRSS"].split()[0]), int(fields["Threads"])


def stat_fields(path):
    """The fields of a /proc .../stat file after the command name (proc(5): field 3 is [0])."""
    return Path(path).read_text().rsplit(")", 1)[1].split()


def cpu_ticks(path):
    """User + system time of a /proc .../stat file (fields 14 and 15), in clock ticks."""
    parts = stat_fields(path)
    return int(parts[11]) + int(parts[12])


def idle_cpu_pct(pid, seconds):
    """The share of one CPU that `pid` uses over `seconds` with no traffic."""
    t0 = cpu_ticks(f"/proc/{pid}/stat")
    time.sleep(seconds)
    return (cpu_ticks(f"/proc/{pid}/stat") - t0) / os.sysconf("SC_CLK_TCK") / seconds * 100


class Rackcat(wb.Responder):
    def __init__(self, args, slaves, busy, tmp, name="slave"):
        state = tmp / f"state-{slaves}-{int(busy)}"
        state.mkdir(exist_ok=True)
        cmd = [str(args.rackcat), "run", "--iface", wb.PAIRS["slave"][0], "--slaves", str(slaves),
               "--no-control", "--no-pty", "--state-dir", str(state), "--log-level", "warn"]
        if args.config:
            cmd += ["--config", str(args.config)]
        if busy:
            cmd.append("--busy-poll")
        if args.firmware_yield_us:
            cmd += ["--firmware-yield-us", str(args.firmware_yield_us)]
        if args.huge_heap:
            cmd += ["--huge-heap", args.huge_heap]
        super().__init__(name, cmd, tmp)


class Kickcat(wb.Responder):
    """KickCAT's network_simulator with `slaves` copies of one slave config (--kickcat)."""

    def __init__(self, args, slaves, tmp, name="kickcat"):
        cmd = [str(args.kickcat), "-i", wb.PAIRS["kickcat"][0], "-s"] + [str(args.kickcat_slave)] * slaves
        super().__init__(name, cmd, tmp)

    # Its socket never sleeps for long: with no frame it polls, recv then a short sleep, over and
    # over. Left running while the others are measured, those wake-ups keep a vCPU from halting
    # and change their numbers (rackcat's SDO p50 halves here), so it runs only for its own turns.
    def pause(self):
        self.proc.send_signal(signal.SIGSTOP)

    @contextlib.contextmanager
    def turn(self):
        self.proc.send_signal(signal.SIGCONT)
        time.sleep(0.05)
        try:
            yield
        finally:
            self.pause()

    def stop(self):
        self.proc.send_signal(signal.SIGCONT)
        super().stop()


def configure(args, slaves, tmp, attempts=3, pair="slave"):
    """Brings `slaves` slaves on `pair` to OP with a real master and captures its cyclic LRW.
    Returns (frame file, or FILE+FILE+... for a cycle of several frames; the master's expected
    working counter; the working counter seen; frame bytes)."""
    out = tmp / f"lrw-{pair}-{slaves}.bin"
    use_ethercrab = args.master == "ethercrab" or (args.master == "auto" and slaves >= PYSOEM_MAX)
    for _ in range(attempts):  # SOEM's scan times out now and then on a loaded machine
        if use_ethercrab:
            r = wb.sh("ip", "netns", "exec", NS, sys.executable, "-c", CONFIGURE_ETHERCRAB,
                      wb.PAIRS[pair][1], str(out), str(slaves), str(ethercrab_binary(args)),
                      check=False)
        else:
            r = wb.sh("ip", "netns", "exec", NS, sys.executable, "-c", CONFIGURE,
                      wb.PAIRS[pair][1], str(out), str(slaves), check=False)
        if r.returncode == 0:
            break
        time.sleep(1)
    if r.returncode != 0:
        master = "ethercrab" if use_ethercrab else "pysoem"
        raise RuntimeError(f"{master} configuration of {slaves} slaves ({pair}) failed: "
                           f"{r.stderr.strip()[-800:]} {r.stdout.strip()[-200:]}")
    frames, expected, wkc, length = r.stdout.split()[-4:]
    return frames, int(expected), int(wkc), int(length)


def ethercrab_binary(args):
    """interop/ethercrab's program (the ethercrab master), built with cargo when missing."""
    binary = Path(args.ethercrab)
    if not binary.is_file():
        cargo = shutil.which("cargo") or str(Path.home() / ".cargo" / "bin" / "cargo")
        wb.sh(cargo, "build", "--release", "--locked", "--manifest-path",
              str(REPO / "interop" / "ethercrab" / "Cargo.toml"))
    return binary


def last_cpu(pid, tid=None):
    """The CPU a task last ran on (/proc/PID[/task/TID]/stat field 39), None once it is gone."""
    path = f"/proc/{pid}/stat" if tid is None else f"/proc/{pid}/task/{tid}/stat"
    try:
        return int(stat_fields(path)[36])
    except (OSError, IndexError, ValueError):
        return None


def busiest_thread(pid):
    """The thread of `pid` with the most CPU time: rackcat's loop thread during a replay."""
    best, best_ticks = None, -1
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            ticks = cpu_ticks(task / "stat")
        except OSError:
            continue
        if ticks > best_ticks:
            best, best_ticks = task.name, ticks
    return best


def replay(pinger_path, names, frame_file, count, tmp, warmup=100, period_us=0, watch=None,
           placement=None):
    """Replays the frame (or, given a dict, each responder's own); with `watch` (a responder's
    pid) also samples every 10 ms on which CPU the pinger and that responder's busiest thread
    last ran, and adds the samples that found them on the same one and all samples to
    `placement` ([same, all]): the placement a 2-vCPU machine runs the round trip in (on one
    CPU the work of both is in series, on two the reply wakes the pinger's CPU)."""
    out = tmp / "samples"
    files = frame_file if isinstance(frame_file, dict) else {n: frame_file for n in names}
    cmd = ["ip", "netns", "exec", NS, str(pinger_path), "--iface",
           ",".join(wb.PAIRS[n][1] for n in names), "--frame-file",
           ",".join(str(files[n]) for n in names),
           "--count", str(count), "--warmup", str(warmup), "--samples-out", str(out),
           "--period-us", str(period_us)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    same = seen = 0
    if watch is not None:
        tid = busiest_thread(watch)
        while proc.poll() is None:
            time.sleep(0.01)
            a, b = last_cpu(proc.pid), last_cpu(watch, tid)
            if a is not None and b is not None:
                seen += 1
                same += a == b
    stdout, stderr = proc.communicate()
    if proc.returncode != 0:
        raise RuntimeError(f"pinger failed: {stderr.strip()}")
    lines = [json.loads(x) for x in stdout.splitlines() if x.strip()]
    res = {}
    for k, (name, line) in enumerate(zip(names, lines)):
        f = out if len(names) == 1 else Path(f"{out}.{k}")
        res[name] = ([int(x) for x in f.read_text().split()], line["lost"], line["wkc"])
    if placement is not None:
        placement[0] += same
        placement[1] += seen
    return res


def lrw_run(args, slaves, mode, tmp, report, cycle_us=0):
    busy = mode == "busy-poll"
    echo = wb.find(args.build, "echo_responder")
    pinger = wb.find(args.build, "wire_pinger")
    slave = Rackcat(args, slaves, busy, tmp)
    floor = wb.Responder("floor", [str(echo), "--iface", wb.PAIRS["floor"][0]] +
                         (["--busy-poll"] if busy else []), tmp)
    # From 200 slaves on ethercrab configures, and it drops every frame KickCAT's simulator
    # returns: the simulator leaves the master's source MAC as it was (docs/INTEROP.md, "source
    # MAC of returned frames"), so KickCAT has no rows there.
    kickcat = (Kickcat(args, slaves, tmp)
               if args.kickcat and not busy and slaves < PYSOEM_MAX else None)
    samples = {"floor": [], "slave": [], "kickcat": [], "alone": []}
    lost = {"floor": 0, "slave": 0, "kickcat": 0, "alone": 0}
    wkcs = set()
    kc = {}
    placement = [0, 0]  # samples with the pinger and rackcat's loop thread on one CPU, samples
    try:
        if busy:
            floor.proc.send_signal(signal.SIGSTOP)
        time.sleep(0.3)
        t0 = time.monotonic()
        frame, expected, wkc, length = configure(args, slaves, tmp)
        config_s = time.monotonic() - t0
        rss_kib, threads = proc_status(slave.proc.pid)
        frames = {"floor": frame, "slave": frame}
        if kickcat:
            frames["kickcat"], kc["expected"], _, kc["frame_bytes"] = configure(
                args, slaves, tmp, pair="kickcat")
            kc["rss_kib"], kc["threads"] = proc_status(kickcat.proc.pid)
            kickcat.pause()
        per_round = max(1, args.samples // args.rounds)
        if not busy:
            for rnd in range(args.rounds):
                res = replay(pinger, ["floor", "slave"], frames, per_round, tmp,
                             period_us=cycle_us,
                             watch=slave.proc.pid if args.placement else None,
                             placement=placement)
                if kickcat:
                    # The method: each alone, back to back, alternating rounds.
                    for name in (("slave", "kickcat") if rnd % 2 == 0 else ("kickcat", "slave")):
                        with kickcat.turn() if name == "kickcat" else contextlib.nullcontext():
                            one = replay(pinger, [name], frames, per_round, tmp,
                                         period_us=cycle_us)
                        res[name if name == "kickcat" else "alone"] = one[name]
                for name, (vals, n_lost, w) in res.items():
                    samples[name] += vals
                    lost[name] += n_lost
                    if name in ("slave", "alone"):
                        wkcs.add(w)
                    if name == "kickcat":
                        kc.setdefault("wkc", set()).add(w)
        else:
            procs = {"floor": floor.proc, "slave": slave.proc}
            running = "slave"
            for rnd in range(args.rounds):
                for name in (("floor", "slave") if rnd % 2 == 0 else ("slave", "floor")):
                    if running != name:
                        procs[running].send_signal(signal.SIGSTOP)
                        procs[name].send_signal(signal.SIGCONT)
                        running = name
                        time.sleep(0.05)
                    vals, n_lost, w = replay(
                        pinger, [name], frame, per_round, tmp, period_us=cycle_us,
                        watch=slave.proc.pid if name == "slave" and args.placement else None,
                        placement=placement)[name]
                    samples[name] += vals
                    lost[name] += n_lost
                    if name == "slave":
                        wkcs.add(w)
            for p in procs.values():
                p.send_signal(signal.SIGCONT)
    finally:
        for r in (floor, slave, kickcat):
            if r is None:
                continue
            try:
                r.proc.send_signal(signal.SIGCONT)
                r.stop()
            except RuntimeError as e:
                print(f"op_bench: {e}", file=sys.stderr)
    f50, s50 = wb.pct(samples["floor"], 50), wb.pct(samples["slave"], 50)
    row = {"mode": mode, "cycle_us": cycle_us, "slaves": slaves, "frame_bytes": length,
           "expected_wkc": expected,
           "wkc": sorted(wkcs), "config_s": round(config_s, 1), "rss_kib": rss_kib,
           "threads": threads,
           "floor_us": [wb.pct(samples["floor"], p) for p in (50, 90, 99)],
           "slave_us": [wb.pct(samples["slave"], p) for p in (50, 90, 99)],
           "ratio_p50": s50 / f50, "per_slave_ns": (s50 - f50) * 1000 / slaves,
           "lost": lost,
           "same_cpu_pct": 100 * placement[0] / placement[1] if placement[1] else None}
    if kickcat:
        k50, a50 = wb.pct(samples["kickcat"], 50), wb.pct(samples["alone"], 50)
        row["kickcat"] = dict(kc, wkc=sorted(kc.get("wkc", ())), lost=lost["kickcat"],
                              us=[wb.pct(samples["kickcat"], p) for p in (50, 90, 99)],
                              rackcat_alone_us=[wb.pct(samples["alone"], p) for p in (50, 90, 99)],
                              rackcat_alone_lost=lost["alone"], ratio_p50=a50 / k50)
    report["lrw"].append(row)
    cycle = "b2b" if cycle_us == 0 else f"{cycle_us}us"
    print(f"{mode:9s} {cycle:>7s} {slaves:5d} {length:5d} B  wkc {sorted(wkcs)} (expected {expected})  "
          f"floor {f50:7.1f}  rackcat {s50:7.1f} us p50  x{s50 / f50:5.2f}  "
          f"p99 {row['floor_us'][2]:7.1f} / {row['slave_us'][2]:7.1f}  "
          f"RSS {rss_kib / 1024:6.1f} MiB ({rss_kib / slaves:7.0f} KiB/slave)  "
          f"threads {threads}  lost {lost['floor']}/{lost['slave']}"
          + (f"  one CPU {row['same_cpu_pct']:3.0f} %" if row["same_cpu_pct"] is not None else ""),
          flush=True)
    if kickcat:
        k = row["kickcat"]
        print(f"{'alone':9s} {cycle:>7s} {'':5s} {k['frame_bytes']:5d} B  wkc {k['wkc']} (expected "
              f"{k['expected']})  KickCAT {k['us'][0]:7.1f}  rackcat {k['rackcat_alone_us'][0]:7.1f} "
              f"us p50  rackcat/KickCAT x{k['ratio_p50']:5.2f}  p99 {k['us'][2]:7.1f} / "
              f"{k['rackcat_alone_us'][2]:7.1f}  KickCAT RSS {k['rss_kib'] / 1024:6.1f} MiB  "
              f"threads {k['threads']}  lost {k['lost']}/{k['rackcat_alone_lost']}", flush=True)


def sdo_calls(pair, calls):
    """pysoem expedited uploads against the slave on `pair`: (failed, [ns per call])."""
    r = wb.sh("ip", "netns", "exec", NS, sys.executable, "-c", SDO, wb.PAIRS[pair][1],
              str(calls), check=False)
    if r.returncode != 0:
        raise RuntimeError(f"SDO run ({pair}) failed: {r.stderr.strip()[-800:]}")
    failed, *t = [int(x) for x in r.stdout.split()]
    return failed, t


def sdo_row(t, failed):
    return {"calls": len(t), "failed": failed, "p50_us": wb.pct(t, 50), "p90_us": wb.pct(t, 90),
            "p99_us": wb.pct(t, 99), "mean_us": sum(t) / len(t) / 1000}


def sdo_run(args, tmp, report):
    slave = Rackcat(args, 1, False, tmp, name="sdo")
    kickcat = Kickcat(args, 1, tmp, name="kickcat-sdo") if args.kickcat else None
    peers = ["slave"] + (["kickcat"] if kickcat else [])
    times = {p: [] for p in peers}
    failed = {p: 0 for p in peers}
    try:
        time.sleep(0.5)
        if kickcat:
            kickcat.pause()
        # With KickCAT, four blocks in the order rackcat, KickCAT, KickCAT, rackcat, so that the
        # machine's drift over the run falls on both alike.
        order = peers if not kickcat else ["slave", "kickcat", "kickcat", "slave"]
        share = args.sdo_calls * len(peers) // len(order)
        for pair in order:
            with kickcat.turn() if pair == "kickcat" else contextlib.nullcontext():
                f, t = sdo_calls(pair, share)
            failed[pair] += f
            times[pair] += t
        time.sleep(0.5)
        idle = idle_cpu_pct(slave.proc.pid, args.idle_seconds)
        if kickcat:
            with kickcat.turn():
                kickcat_idle = idle_cpu_pct(kickcat.proc.pid, args.idle_seconds)
    finally:
        slave.stop()
        if kickcat:
            kickcat.stop()
    row = dict(sdo_row(times["slave"], failed["slave"]), idle_cpu_pct=idle)
    if kickcat:
        row["kickcat"] = dict(sdo_row(times["kickcat"], failed["kickcat"]),
                              idle_cpu_pct=kickcat_idle)
        row["ratio_p50"] = row["p50_us"] / row["kickcat"]["p50_us"]
    report["sdo"] = row
    print(f"SDO upload 0x1018:01, {row['calls']} calls ({row['failed']} failed), blocking, unpinned: "
          f"p50 {row['p50_us']:.1f} "
          f"p90 {row['p90_us']:.1f} p99 {row['p99_us']:.1f} mean {row['mean_us']:.1f} us; "
          f"idle CPU {idle:.2f} % over {args.idle_seconds} s", flush=True)
    if kickcat:
        k = row["kickcat"]
        print(f"  KickCAT, same run: {k['calls']} calls ({k['failed']} failed) p50 {k['p50_us']:.1f} "
              f"p90 {k['p90_us']:.1f} p99 {k['p99_us']:.1f} us, idle CPU {k['idle_cpu_pct']:.2f} %; "
              f"rackcat/KickCAT x{row['ratio_p50']:.2f}", flush=True)


def brd_run(args, n, tmp, report):
    """rackcat with n slaves, started and answering a BRD: working counter, RSS, threads."""
    pinger = wb.find(args.build, "wire_pinger")
    slave = Rackcat(args, n, False, tmp, name=f"brd{n}")
    row = {"slaves": n}
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and slave.proc.poll() is None:
            r = wb.sh("ip", "netns", "exec", NS, str(pinger), "--iface", wb.PAIRS["slave"][1],
                      "--frame", "brd", "--count", "20", "--warmup", "0", check=False)
            if r.returncode == 0:
                line = json.loads(r.stdout.splitlines()[0])
                if line["count"] > 0:
                    row.update(wkc=line["wkc"], p50_us=line["p50_us"],
                               start_s=round(time.monotonic() - deadline + 120, 1))
                    row["rss_kib"], row["threads"] = proc_status(slave.proc.pid)
                    break
            time.sleep(0.5)
    finally:
        try:
            slave.stop()
        except RuntimeError as e:
            row["error"] = str(e).splitlines()[-1] if str(e) else "exited"
    report["brd"].append(row)
    print(f"BRD with {n} slaves (INIT, tiny racks): {row}", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir", default=str(REPO / "build"))
    ap.add_argument("--config", default=str(REPO / "examples" / "tiny-rack.yaml"))
    # pysoem (SOEM's EC_MAXSLAVE) configures fewer than 200 slaves; ethercrab the rest.
    ap.add_argument("--slaves", default="1,16,64,128,199,256,1024")
    ap.add_argument("--master", choices=("auto", "pysoem", "ethercrab"), default="auto",
                    help="the master that configures the slaves and whose LRW is replayed "
                    "(auto: pysoem below 200 slaves, ethercrab from 200)")
    ap.add_argument("--ethercrab", metavar="BIN",
                    default=str(REPO / "interop" / "ethercrab" / "target" / "release" /
                                "ethercrab-interop"),
                    help="interop/ethercrab's program (built with cargo when missing)")
    ap.add_argument("--modes", default="blocking,busy-poll")
    ap.add_argument("--samples", type=int, default=10000)
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--sdo-calls", type=int, default=2000, help="0 = skip")
    ap.add_argument("--idle-seconds", type=float, default=5)
    ap.add_argument("--brd-slaves", default="64,128,256,4096",
                    help="slave counts for the start-up BRD / RSS / thread count run ('' = skip)")
    ap.add_argument("--huge-heap", choices=["auto", "on", "off"], default=None,
                    help="rackcat run --huge-heap (default: not given, rackcat's auto)")
    ap.add_argument("--firmware-yield-us", type=int, default=0,
                    help="rackcat run --firmware-yield-us (0 = off, rackcat's default)")
    ap.add_argument("--cycle-us", default="0",
                    help="master cycle times to replay at, us (0 = back to back); e.g. 0,1000")
    ap.add_argument("--guest-halt-poll-ns", type=int, default=None,
                    help="set the guest's haltpoll window for the run (diagnosis; restored after)")
    ap.add_argument("--placement", action="store_true",
                    help="sample the CPUs of the pinger and rackcat's loop thread (one CPU %%)")
    ap.add_argument("--kickcat", default=None, metavar="BIN",
                    help="KickCAT's network_simulator as a third peer (blocking rows, SDO)")
    ap.add_argument("--kickcat-slave", default=None, metavar="JSON",
                    help="the slave config each KickCAT slave is built from")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    if args.kickcat:
        if not args.kickcat_slave:
            sys.exit("op_bench: --kickcat needs --kickcat-slave JSON")
        args.kickcat = Path(args.kickcat).resolve()
        args.kickcat_slave = Path(args.kickcat_slave).resolve()
        for f in (args.kickcat, args.kickcat_slave):
            if not f.is_file():
                sys.exit(f"op_bench: {f}: no such file")
        wb.PAIRS["kickcat"] = ("kc-slave", "kc-master")
    if os.geteuid() != 0:
        sys.exit("op_bench: needs root (network namespace, veth pairs, raw sockets)")
    args.build = Path(args.build_dir).resolve()
    args.rackcat = args.build / "rackcat"
    if not args.rackcat.exists():
        args.rackcat = wb.find(args.build, "rackcat")
    report = {"lrw": [], "brd": [], "started": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
              "load": os.getloadavg()}
    tmp = Path(tempfile.mkdtemp(prefix="op_bench_"))
    saved_halt_poll = halt_poll_ns()
    if args.guest_halt_poll_ns is not None:
        if saved_halt_poll is None:
            sys.exit(f"op_bench: --guest-halt-poll-ns needs {HALT_POLL} (cpuidle-haltpoll)")
        HALT_POLL.write_text(str(args.guest_halt_poll_ns))
    report["guest_halt_poll_ns"] = halt_poll_ns()
    print(f"guest_halt_poll_ns {report['guest_halt_poll_ns']}", flush=True)
    wb.netns_up()
    try:
        for n in [int(x) for x in args.slaves.split(",") if x]:
            for mode in [m for m in args.modes.split(",") if m]:
                for cycle_us in [int(x) for x in args.cycle_us.split(",") if x]:
                    lrw_run(args, n, mode, tmp, report, cycle_us)
        if args.sdo_calls > 0:
            sdo_run(args, tmp, report)
        for n in [int(x) for x in args.brd_slaves.split(",") if x]:
            brd_run(args, n, tmp, report)
    finally:
        wb.netns_down()
        if args.guest_halt_poll_ns is not None:
            HALT_POLL.write_text(str(saved_halt_poll))
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
