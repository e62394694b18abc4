#!/usr/bin/env python3
"""The EtherCAT side of the RIM link on CAN (docs/CAN.md): a real master (pysoem, SOEM) drives
`rackcat run --rim-bus can:vcan1` to OP over a veth pair while the rack's two RIMs are
`rackcat rim` processes on a CAN bus limited to 1 Mbit/s.

Runs inside the qemu VM of scripts/can_vm.sh (chrooted into the host's root shared over 9p,
so the host's python3, pysoem, iproute2 and build are used as they are), or natively as root
on a kernel with AF_CAN. Prints one line:
    CAN_VM_ECAT_RESULT PASS|FAIL|SKIP key=value ...

What it checks, in order:
1. With Detect Modules Override 0 and no RIM on the bus, the slave refuses OP (stays in SAFEOP
   with AL status 0x0070: the modules of RIMs that are not ONLINE are missing, guide §4.4).
2. The RIM processes start; the master reaches OP once both are ONLINE over CAN.
3. In OP at a 1 ms cycle: the RIMs' inputs are in the master's process image (RIM 1's CAI-11
   channel 1 is a constant 2.5 V; RIM 2's relays, driven by the master over an RPDO, read back
   through its loopback-wired CDI-13 over a TPDO), and the age of RIM 1's channel 0, a
   CLOCK_MONOTONIC time stamp (`clock` source), as the master receives it.
4. RIM 2's process is killed: the time until the master reads OFFLINE in 0x2021:08 over SDO,
   and the slave leaves OP (SAFEOP + error, AL status 0x0070).
5. RIM 2 restarts: ONLINE again, the master acknowledges and is back in OP with the loopback.

The CAN bus rate: vcan has none, so vcan1 gets a netem qdisc at 1 Mbit/s with the vcan module
loaded with echo=1 (the driver, after the qdisc, delivers the frames to the other sockets).
netem charges the 16 bytes of a struct can_frame, 128 bit times per frame; a real classic CAN
frame with 8 data bytes is 111 bit times plus stuff bits (up to about 135).

Usage: ecat_over_can.py RACKCAT_BINARY
"""
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "interop"))

RACK = HERE / "ecat_rack.yaml"
CAN = "vcan1"
SLAVE_IF, MASTER_IF = "ecat0", "ecat1"
CONTROL_PORT = 8766
HEARTBEAT_CONSUMER_MS = 150  # `rackcat run --rim-bus` consumer time (docs/CAN.md)
RIM_HEARTBEAT_MS = 50
# CAN bit rate (netem rate syntax); "none" for an unshaped vcan (for comparison only).
BITRATE = os.environ.get("RACKCAT_CAN_BITRATE", "1mbit")
TICK_US = 10  # ecat_rack.yaml: {source: clock, tick_us: 10}
AGE_CYCLES = 3000
# AL status code when a RIM with mapped process data is not ONLINE (docs/MODULES.md): 0x0070
# "detected module ident list does not match" (ETG.1000.6 Table 11).
AL_MODULES_MISSING = 0x0070

# Objects of ecat_rack.yaml (module 1 = RIM 1 slot 1 CAI-11, 2 = RIM 2 slot 1 CRS-10,
# 3 = RIM 2 slot 2 CDI-13), docs/MDP.md.
AI_CLOCK = (0x6002, 0x01)
AI_CONST = (0x6002, 0x02)
DO_RELAYS = (0x7011, 0x01)
DI_LOOPBACK = (0x6021, 0x01)
RIM2_STATE = (0x2021, 0x08)  # 0x2rr1:08 bits 1..0: 0 OFFLINE, 1 CONNECTED, 2 ONLINE, 3 ERROR

children = []


def result(status, **kv):
    for p in children:
        if p.poll() is None:
            p.kill()
            p.wait()
    text = " ".join(f"{k}={v}" for k, v in kv.items())
    print(f"CAN_VM_ECAT_RESULT {status} {text}", flush=True)
    sys.exit(0 if status in ("PASS", "SKIP") else 1)


def sh(*cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def spawn(*cmd, rt=None):
    prefix = ["chrt", "-f", str(rt)] if rt else []
    p = subprocess.Popen(prefix + [str(c) for c in cmd], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    children.append(p)
    return p


def spawn_rim(rackcat, rim):
    return spawn(rackcat, "rim", "--can", CAN, "--rim", rim, "--config", RACK,
                 "--heartbeat-ms", RIM_HEARTBEAT_MS, rt=40)


def start_capture():
    """dumpcap on the CAN interface into $RACKCAT_CAN_CAPTURE (checked by
    check_can_capture.py after the run: every frame must decode as CANopen)."""
    path = os.environ.get("RACKCAT_CAN_CAPTURE")
    if not path or shutil.which("dumpcap") is None:
        return None
    p = subprocess.Popen(["dumpcap", "-q", "-i", CAN, "-w", path], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    children.append(p)
    deadline = time.monotonic() + 10
    while not (Path(path).exists() and Path(path).stat().st_size > 0):
        if time.monotonic() > deadline or p.poll() is not None:
            break
        time.sleep(0.05)
    time.sleep(0.2)  # the capture file exists once dumpcap has opened the interface
    return p


def stop_capture(p, cycle):
    """Stops dumpcap while the master keeps cycling: in OP, a pause longer than the process
    data watchdog (100 ms) would, rightly, put the outputs into their safe state."""
    if p is None:
        return
    p.send_signal(signal.SIGINT)
    deadline = time.monotonic() + 10
    while p.poll() is None and time.monotonic() < deadline:
        cycle()
        time.sleep(0.001)
    if p.poll() is None:
        p.kill()
        p.wait()


def vcan_echoes():
    """netem delays a frame only if the vcan driver, not the CAN core, loops it back."""
    try:
        return Path("/sys/module/vcan/parameters/echo").read_text().strip() in ("Y", "1")
    except OSError:
        return False


def can_counters():
    """Frames the kernel passed through vcan1's qdisc, and the ones it dropped."""
    out = subprocess.run(["tc", "-s", "qdisc", "show", "dev", CAN], stdout=subprocess.PIPE,
                         text=True).stdout
    m = re.search(r"Sent \d+ bytes (\d+) pkt \(dropped (\d+)", out)
    return (int(m.group(1)), int(m.group(2))) if m else (-1, -1)


def ms_since(t0):
    return (time.monotonic() - t0) * 1000.0


def main():
    global BITRATE
    if len(sys.argv) != 2:
        print(__doc__)
        sys.exit(2)
    rackcat = sys.argv[1]
    try:
        import pysoem
    except ImportError:
        result("SKIP", reason="pysoem_not_installed")
    from pdo_map import get_bits, read_pdo_map, sdo_u, set_bits

    # SOEM's default timeouts are for real hardware; under software emulation (qemu TCG, and
    # the sanitizer build on top) the VM runs each process several times slower.
    # t.ret bounds one frame's round trip (a mailbox poll, a state read): under TCG the VM's
    # CPUs can stall for tens of ms on a busy 2-core host.
    t = pysoem.settings.timeouts
    t.ret, t.safe, t.tx_mailbox, t.rx_mailbox = 100_000, 200_000, 200_000, 2_000_000

    try:
        sh("ip", "link", "set", "lo", "up")  # the control API listens on 127.0.0.1
        sh("ip", "link", "add", "dev", CAN, "type", "vcan")
        if BITRATE != "none" and not vcan_echoes():
            # A host that loaded vcan without echo=1: the CAN core loops frames back before
            # the qdisc, so netem could not delay them. Run unshaped and say so.
            BITRATE = "none_vcan_echo_off"
        if not BITRATE.startswith("none"):
            sh("tc", "qdisc", "add", "dev", CAN, "root", "netem", "rate", BITRATE, "limit", "1000")
        sh("ip", "link", "set", CAN, "up")
        sh("ip", "link", "add", SLAVE_IF, "type", "veth", "peer", "name", MASTER_IF)
        sh("ip", "link", "set", SLAVE_IF, "up")
        sh("ip", "link", "set", MASTER_IF, "up")
    except subprocess.CalledProcessError as e:
        result("FAIL", stage="setup", cmd="_".join(e.cmd[:4]),
               error=e.stderr.decode(errors="replace").strip().replace(" ", "_")[:80])

    # TMPDIR: in the VM, /tmp is the host's (read-only, so a checkout below /tmp stays
    # visible) and TMPDIR names a tmpfs.
    state_dir = Path(tempfile.gettempdir()) / "rackcat-ecat-over-can"
    state_dir.mkdir(parents=True, exist_ok=True)
    slave = spawn(rackcat, "run", "--iface", SLAVE_IF, "--config", RACK, "--rim-bus",
                  f"can:{CAN}", "--no-pty", "--control-port", CONTROL_PORT, "--state-dir",
                  state_dir, rt=60)

    master = pysoem.Master()
    master.open(MASTER_IF)
    n = 0
    deadline = time.monotonic() + 20
    while n != 1 and time.monotonic() < deadline and slave.poll() is None:
        n = master.config_init()
        if n != 1:
            time.sleep(0.2)
    if n != 1:
        result("FAIL", stage="config_init", slaves=n, slave_exit=slave.poll())
    s = master.slaves[0]
    # The RIMs are not on the bus yet, so the slave has queued emergencies (0xA001, module
    # missing). pysoem's config_map fails on any emergency it meets; its sdo_read hands them to
    # the callback. SOEM reads the queued messages before the SDO answer, so one read drains.
    emergencies = []
    s.add_emergency_callback(lambda e: emergencies.append(e.error_code))
    retries = 0

    def patiently(read):
        """An SDO exchange that a stalled emulated CPU lost (no reply within the timeout: pysoem
        raises WkcError) is tried again, and counted; an SDO abort is not."""
        nonlocal retries
        for _ in range(3):
            try:
                return read()
            except pysoem.WkcError:
                retries += 1
                time.sleep(0.05)
        return read()

    patiently(lambda: sdo_u(s, 0x1018, 1, "<I"))
    master.config_map()
    # The process-data watchdog (default 100 ms) trips when the master pauses that long; on a
    # loaded host the emulated CPUs can stall for longer. 1 s keeps the test about the CAN link.
    s.set_watchdog("processdata", 1000)
    pdo = patiently(lambda: read_pdo_map(s))  # only reads: safe to repeat whole
    ai_clock = pdo.find(*AI_CLOCK, "in")
    ai_const = pdo.find(*AI_CONST, "in")
    do = pdo.find(*DO_RELAYS, "out")
    di = pdo.find(*DI_LOOPBACK, "in")
    expected_wkc = 3  # LRW: outputs written (2) + inputs read (1)

    def cycle():
        master.send_processdata()
        return master.receive_processdata(20_000)

    def rim2_state():
        """0x2021:08 over SDO."""
        return patiently(lambda: sdo_u(s, *RIM2_STATE, "<I"))

    def request(state, timeout_us=2_000_000):
        master.state = state
        master.write_state()
        got = master.state_check(state, timeout_us)
        master.read_state()
        return got == state

    def try_op(cycles):
        master.state = pysoem.OP_STATE
        master.write_state()
        for _ in range(cycles):
            cycle()
            if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
                return True
        master.read_state()
        return False

    def acknowledge_safeop():
        master.state = pysoem.SAFEOP_STATE | 0x10  # AL control acknowledge bit
        master.write_state()
        master.state_check(pysoem.SAFEOP_STATE, 500_000)

    # 1. No RIM on the bus yet: SAFEOP, but OP is refused.
    if not request(pysoem.SAFEOP_STATE):
        result("FAIL", stage="safeop", al_status=hex(s.al_status))
    cycle()
    if try_op(100):
        result("FAIL", stage="op_without_rims")
    refused = f"{s.state:#x}/{s.al_status:#06x}"
    acknowledge_safeop()

    # 2. The RIMs join the bus: OP once both are ONLINE.
    capture = start_capture()  # boot-up, SDO checks, NMT start, heartbeats, PDOs
    t_rims = time.monotonic()
    rims = {1: spawn_rim(rackcat, 1), 2: spawn_rim(rackcat, 2)}
    reached = False
    while not reached and ms_since(t_rims) < 15_000:
        reached = try_op(50)
        if not reached:
            acknowledge_safeop()
            time.sleep(0.05)
    if not reached:
        result("FAIL", stage="op_with_rims", al_status=hex(s.al_status),
               rim1_exit=rims[1].poll(), rim2_exit=rims[2].poll())
    op_ms = ms_since(t_rims)
    for _ in range(100):
        cycle()
        time.sleep(0.001)
    stop_capture(capture, cycle)
    master.read_state()
    if s.state != pysoem.OP_STATE:
        result("FAIL", stage="op_after_capture", state=hex(s.state), al_status=hex(s.al_status))

    # 3. OP at 1 ms: inputs from the RIMs, input age, relay loopback over CAN.
    ages_ms, rtts_ms, bad_wkc, const_codes = [], [], 0, set()
    pattern, sent_at, loop_ms, loop_ok = 0x01, None, [], 0
    next_t = time.monotonic()
    for i in range(AGE_CYCLES):
        if i % 200 == 0:
            pattern = ((pattern << 1) | (pattern >> 7)) & 0xFF
            s.output = set_bits(s.output, do, pattern)
            sent_at = time.monotonic()
        t_tx = time.monotonic_ns()
        wkc = cycle()
        t_rx = time.monotonic_ns()
        rtts_ms.append((t_rx - t_tx) / 1e6)
        if wkc != expected_wkc:
            bad_wkc += 1
        else:
            code = get_bits(s.input, ai_clock)
            code = code - 0x10000 if code & 0x8000 else code
            ticks_now = (t_rx // (TICK_US * 1000)) % 65535
            ages_ms.append(((ticks_now - (code + 32767)) % 65535) * TICK_US / 1000.0)
            const_codes.add(get_bits(s.input, ai_const))
            if sent_at is not None and get_bits(s.input, di) == pattern:
                loop_ms.append((time.monotonic() - sent_at) * 1000.0)
                loop_ok += 1
                sent_at = None
        next_t += 0.001
        delay = next_t - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        else:
            next_t = time.monotonic()
    master.read_state()
    if s.state != pysoem.OP_STATE:  # e.g. 0x001B: the emulated CPUs stalled past the watchdog
        result("FAIL", stage="left_op_while_cycling", state=hex(s.state),
               al_status=hex(s.al_status), bad_wkc=bad_wkc)
    if len(ages_ms) < AGE_CYCLES * 0.9:
        result("FAIL", stage="op_cycles", bad_wkc=bad_wkc, cycles=AGE_CYCLES)
    ages_ms.sort()
    age = {
        "input_age_mean_ms": f"{statistics.fmean(ages_ms):.3f}",
        "input_age_p50_ms": f"{ages_ms[len(ages_ms) // 2]:.3f}",
        "input_age_p99_ms": f"{ages_ms[len(ages_ms) * 99 // 100]:.3f}",
        "input_age_max_ms": f"{ages_ms[-1]:.3f}",
        # The master's own share: send_processdata to receive_processdata returning.
        "frame_rtt_mean_ms": f"{statistics.fmean(rtts_ms):.3f}",
    }
    # 2.5 V on a ±10 V channel: round(2.5 * 32767 / 10) = 8192 (docs/MODULES.md).
    if const_codes != {8192}:
        result("FAIL", stage="rim_inputs", const_codes=sorted(const_codes)[:4])
    if loop_ok < AGE_CYCLES // 200 - 1:
        result("FAIL", stage="loopback_over_can", loopbacks=loop_ok, do=hex(pattern),
               di=hex(get_bits(s.input, di)), rim2_exit=rims[2].poll())

    # 4. Unplug RIM 2: OFFLINE in 0x2021:08 as the master reads it, and the ESM leaves OP.
    t_kill = time.monotonic()
    rims[2].kill()
    rims[2].wait()
    def wait_rim2(state, since, limit_ms, pause_s):
        """ms from `since` until 0x2021:08 bits 1..0 read `state`, cycling meanwhile; None
        after limit_ms."""
        while ms_since(since) < limit_ms:
            cycle()
            if rim2_state() & 0x3 == state:
                return ms_since(since)
            time.sleep(pause_s)
        return None

    offline_ms = wait_rim2(0, t_kill, 3000, 0.001)
    if offline_ms is None:
        result("FAIL", stage="kill_rim2", state=hex(rim2_state()))
    for _ in range(100):
        cycle()
        master.read_state()
        if s.state != pysoem.OP_STATE:
            break
        time.sleep(0.001)
    master.read_state()
    left_op = f"{s.state:#x}/{s.al_status:#06x}"

    # 5. Plug it back: ONLINE, acknowledge, OP again with the loopback working.
    t_restart = time.monotonic()
    rims[2] = spawn_rim(rackcat, 2)
    online_ms = wait_rim2(2, t_restart, 10_000, 0.005)
    if online_ms is None:
        result("FAIL", stage="restart_rim2", state=hex(rim2_state()))
    acknowledge_safeop()
    cycle()
    back = try_op(500)
    s.output = set_bits(s.output, do, 0xA5)
    seen = None
    for _ in range(500):
        cycle()
        seen = get_bits(s.input, di)
        if seen == 0xA5:
            break
        time.sleep(0.001)
    if not back or seen != 0xA5:
        master.read_state()
        result("FAIL", stage="reop", state=hex(s.state), al_status=hex(s.al_status),
               di=hex(seen or 0))
    master.state = pysoem.INIT_STATE
    master.write_state()
    master.close()

    code = f"{AL_MODULES_MISSING:#06x}"
    ok = offline_ms <= HEARTBEAT_CONSUMER_MS + RIM_HEARTBEAT_MS + 100 and \
        left_op.endswith(code) and refused.endswith(code)
    frames, dropped = can_counters()
    result("PASS" if ok else "FAIL", bus=BITRATE, can_frames=frames, can_dropped=dropped,
           op_without_rims=refused,
           rims_to_op_ms=f"{op_ms:.0f}", **age, cycles=len(ages_ms), bad_wkc=bad_wkc,
           loopback_mean_ms=f"{statistics.fmean(loop_ms):.2f}" if loop_ms else "-",
           kill_to_offline_0x2021_ms=f"{offline_ms:.1f}", after_kill=left_op,
           restart_to_online_ms=f"{online_ms:.0f}",
           emcy=",".join(f"{c:04X}" for c in sorted(set(emergencies))) or "-",
           sdo_retries=retries)


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, lambda *_: result("FAIL", stage="terminated"))
    try:
        main()
    except Exception as e:  # one result line whatever happens, with what went wrong
        import traceback
        traceback.print_exc()
        result("FAIL", stage="exception", error=repr(e).replace(" ", "_")[:120])
