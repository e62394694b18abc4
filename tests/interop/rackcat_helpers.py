"""Shared pieces of the rackcat interop tests: the real device (`rackcat run`) in a private
network namespace over a veth pair, driven by pysoem (SOEM) from the host end.

The namespace, veth pair and process handling come from conftest.py (VethNamespace,
SlaveProcess); this module adds what the rackcat tests need on top: the `rackcat` fixture
(start, restart with the same state directory, control API calls inside the namespace), a
pysoem master walking the ESM, the PDO map read back over SDO, and the byte sequences of the
command objects.

RACKCAT_BUILD_DIR selects the build directory (default build/); Release builds only: SOEM
drops replies later than 2 ms during configuration.
"""
import concurrent.futures
import contextlib
import json
from pathlib import Path
import os
import shlex
import shutil
import struct
import subprocess
import time

import pytest

from conftest import (BUILD, SlaveProcess, VethNamespace, go, require_root,  # noqa: F401
                      tshark_problems, wait_watchdog_safeop)
from pdo_map import PdoEntry, PdoMap, get_bits, read_pdo_map, sdo_u, set_bits  # noqa: F401
from raw_master import RawMaster

pysoem = pytest.importorskip("pysoem", reason="pysoem not installed (scripts/setup.sh)")

RACKCAT = BUILD / "rackcat"
CONTROL_PORT = 8765
# Generous per-cycle receive timeout: the machine is shared, a late frame is not a lost one.
RECEIVE_TIMEOUT_US = 20_000
CYCLE_S = 0.001

# Command byte sequences (guide Appendix A, ETG.5003.1 command objects).
STORE_SAVE = b"save"  # 0xFBF2:01, 0x73 0x61 0x76 0x65
EXCEPTION_RESET = bytes([0x74, 0x65, 0x73, 0x65, 0x72])  # 0xFBF1:01, "reset" reversed

# The default rack (examples/default-rack.yaml, docs/MDP.md): module numbers are RIM by RIM,
# slot by slot; RIM 1 has cards in slots 1..19, RIM 2 in slots 1..8 (modules 20..27).
DEFAULT_MODULES = 27
DO_MODULE = 1  # RIM 1 slot 1 CDO-10, 16x sourcing DO, RxPDO 0x1600 -> 0x7000:01 (16 bits)
DI_LOOPBACK_MODULE = 2  # RIM 1 slot 2 CDI-10, loopback-wired to slot 1 -> 0x6010:01
UART_MODULE = 19  # RIM 1 slot 19 CUR-12


def require_rackcat():
    require_root()
    if not RACKCAT.exists():
        pytest.skip(f"{RACKCAT} not built (cmake --build build --target rackcat; "
                    "RACKCAT_BUILD_DIR selects another build directory)")


def rackcat_tool(*args, **kw):
    """Runs a rackcat subcommand that needs no network (sii, esi, od)."""
    return subprocess.run([str(RACKCAT), *map(str, args)], check=True, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, timeout=60, **kw)


def sii_image(tmp_path, config=None):
    """The EEPROM image `rackcat sii -o FILE [--config FILE]` writes."""
    out = tmp_path / f"sii-{time.monotonic_ns()}.bin"
    args = ["sii", "-o", out] + (["--config", config] if config else [])
    rackcat_tool(*args)
    return out.read_bytes()


# Real-time priority for the slave and the master, as EtherCAT masters and slaves normally run:
# on a loaded 2-core machine plain scheduling delays alone (35 ms seen) exceed SOEM's 20 ms
# mailbox-send timeout. Both block in recv/sleep, so SCHED_FIFO does not starve the machine.
RT_PRIORITY = 10


def rt_prefix():
    if shutil.which("chrt") and subprocess.run(["chrt", "-f", str(RT_PRIORITY), "true"],
                                               stderr=subprocess.DEVNULL).returncode == 0:
        return ["chrt", "-f", str(RT_PRIORITY)]
    return []


@contextlib.contextmanager
def realtime_master():
    """SCHED_FIFO for this (the master's) process; children forked meanwhile (curl, tshark)
    get the normal policy back (SCHED_RESET_ON_FORK)."""
    old = os.sched_getscheduler(0), os.sched_getparam(0)
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK,
                              os.sched_param(RT_PRIORITY))
    except OSError:
        old = None
    try:
        yield
    finally:
        if old is not None:
            os.sched_setscheduler(0, old[0], old[1])


class Rackcat:
    """One `rackcat run` in its namespace; restart() keeps the namespace and state directory."""

    def __init__(self, tmp_path, slaves, config, state_dir, pcap, extra, prefix=()):
        self.prefix = list(prefix)
        self.tmp_path = tmp_path
        self.slaves = slaves
        self.config = config
        self.state_dir = state_dir or (tmp_path / "state")
        self.pcap_enabled = pcap
        self.extra = list(extra)
        self.ns = VethNamespace().__enter__()
        self.iface = self.ns.master_iface
        self.runs = 0
        self.proc = None
        self.start()

    def start(self):
        self.runs += 1
        args = ["--state-dir", str(self.state_dir)] + self.extra
        if self.config:
            args += ["--config", str(self.config)]
        cap = self.tmp_path / f"rackcat{self.runs}.pcap" if self.pcap_enabled else None
        template = f"{shlex.quote(str(RACKCAT))} run --iface {{iface}} --slaves {{slaves}}"
        self.proc = SlaveProcess(self.ns, template, self.slaves, args, cap,
                                 self.tmp_path / f"rackcat{self.runs}.log",
                                 rt_prefix() + self.prefix)
        self.proc.wait_ready(self.slaves)
        if "--no-control" not in self.extra:
            self._wait_control_api()
        return self

    def stop(self):
        rc = self.proc.stop()
        assert rc == 0, f"rackcat exited with {rc}:\n{self.proc.log()}"
        return rc

    def restart(self):
        self.stop()
        return self.start()

    def close(self):
        if self.proc is not None:
            self.proc.stop()
        self.ns.__exit__(None, None, None)

    def log(self):
        return self.proc.log()

    @property
    def pcap(self):
        return self.proc.pcap

    # --- control API (HTTP + JSON on 127.0.0.1 inside the slave's namespace) -------------

    def cli(self, *args, text=False):
        """`rackcat ctl ARGS`, the command-line client, inside the namespace; returns its JSON
        answer (`--json`), or with text=True what it prints by default. Fails with the
        command's message on a non-zero exit."""
        cmd = self.ns.exec_prefix() + [str(RACKCAT), "ctl", "--port", str(CONTROL_PORT),
                                       "--state-dir", str(self.state_dir)]
        if not text:
            cmd.append("--json")
        cmd += [str(a) for a in args]
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=20)
        assert r.returncode == 0, f"rackcat ctl {' '.join(map(str, args))}: exit " \
            f"{r.returncode}: {r.stderr.strip()}"
        return r.stdout if text else json.loads(r.stdout)

    def module(self, number):
        """One module with live channel values (`rackcat ctl list --module N --json`)."""
        return self.cli("list", "--module", number)

    def ctl(self, method, path, body=None, expect=200):
        """One raw control API request (curl inside the namespace); returns the JSON body."""
        cmd = self.ns.exec_prefix() + ["curl", "-s", "-S", "--max-time", "10", "-X", method,
                                       "-w", "\n%{http_code}", "-H",
                                       f"Authorization: Bearer {self.token()}"]
        if body is not None:
            cmd += ["-H", "Content-Type: application/json", "--data", json.dumps(body)]
        cmd.append(f"http://127.0.0.1:{CONTROL_PORT}{path}")
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=20)
        assert r.returncode == 0, f"control API {method} {path}: {r.stderr}"
        text, _, code = r.stdout.rpartition("\n")
        assert int(code) == expect, f"control API {method} {path} -> {code}: {text}"
        return json.loads(text) if text else None

    def token(self):
        """The control API's secret for this run (STATE/control-token, docs/MODULES.md)."""
        path = Path(self.state_dir) / "control-token"
        return path.read_text().strip() if path.exists() else ""

    def _while_cycling(self, master, fn, *args):
        # In OP the SM watchdog expires after 100 ms without frames (0x0420's default); a
        # control request may take longer, so the master keeps exchanging process data
        # meanwhile. Starting the thread and curl can still stall this process for ~100 ms
        # under load (measured at load 17), so the watchdog time is held at seconds meanwhile.
        with pd_watchdog_held(self.iface):
            with concurrent.futures.ThreadPoolExecutor(1) as pool:
                future = pool.submit(fn, *args)
                while not future.done():
                    cycle(master)
                    time.sleep(CYCLE_S)
                return future.result()

    def ctl_while_cycling(self, master, method, path, body=None):
        return self._while_cycling(master, self.ctl, method, path, body)

    def cli_while_cycling(self, master, *args):
        return self._while_cycling(master, self.cli, *args)

    def _wait_control_api(self):
        deadline = time.monotonic() + 10
        while True:
            try:
                self.ctl("GET", "/api/esm")
                return
            except AssertionError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.05)


REG_WATCHDOG_DIVIDER = 0x0400
REG_WATCHDOG_PROCESS_DATA = 0x0420
HELD_WATCHDOG_S = 5.0  # 0x0420 holds at most 65535 units (6.5 s with the default divider)


@contextlib.contextmanager
def pd_watchdog_held(iface, seconds=HELD_WATCHDOG_S):
    """Every slave's process-data watchdog time (0x0420) at `seconds` inside the block, its
    old value restored afterwards (BWR from a raw socket beside the master). The ESC reads
    0x0420 at each retrigger (ESC datasheet 0x0420), so the next process-data frame runs with
    it; the unit is (0x0400 + 2) x 40 ns."""
    raw = RawMaster(iface)
    try:
        wkc, old = raw.brd(REG_WATCHDOG_PROCESS_DATA, 2)
        assert wkc >= 1, f"BRD 0x0420: working counter {wkc}"
        wkc, divider = raw.brd(REG_WATCHDOG_DIVIDER, 2)
        assert wkc >= 1, f"BRD 0x0400: working counter {wkc}"
        unit_s = (struct.unpack("<H", divider)[0] + 2) * 40e-9
        held = min(0xFFFF, round(seconds / unit_s))
        assert raw.bwr(REG_WATCHDOG_PROCESS_DATA, struct.pack("<H", held)) >= 1
        try:
            yield
        finally:
            assert raw.bwr(REG_WATCHDOG_PROCESS_DATA, old) >= 1
    finally:
        raw.close()


@pytest.fixture
def rackcat(tmp_path):
    """Factory: rackcat(slaves=1, config=None, state_dir=None, pcap=True, extra=()) -> Rackcat.

    Starts `rackcat run` on the slave end of a fresh veth pair and waits until it answers a
    BRD; everything is torn down after the test."""
    require_rackcat()
    started = []

    def start(slaves=1, config=None, state_dir=None, pcap=True, extra=(), prefix=()):
        sub = tmp_path / f"run{len(started)}"
        sub.mkdir()
        r = Rackcat(sub, slaves, config, state_dir, pcap, extra, prefix)
        started.append(r)
        return r

    with realtime_master():
        yield start
    for r in reversed(started):
        r.close()


# --- the master ------------------------------------------------------------------------


@contextlib.contextmanager
def rack_with_master(rackcat):
    """A fresh `rackcat run` of the default rack (the rackcat fixture) and a pysoem master that
    has scanned it (PREOP): yields (rc, master); the master is closed afterwards and rackcat
    stopped when the block succeeded."""
    rc = rackcat()
    master = open_master(rc.iface, 1)
    try:
        yield rc, master
    finally:
        master.close()
    rc.stop()


def open_master(iface, expected_slaves=1):
    master = pysoem.Master()
    master.open(iface)
    n = 0
    for _ in range(20):
        n = master.config_init()
        if n == expected_slaves:
            break
        time.sleep(0.1)
    assert n == expected_slaves, f"config_init found {n} slaves, expected {expected_slaves}"
    assert master.state_check(pysoem.PREOP_STATE, 2_000_000) == pysoem.PREOP_STATE
    master.read_state()
    return master


def ride_through_rim_loss(slave, on_emergency=lambda e: None):
    """Prepares `slave` (PREOP) for a RIM going offline: Detect Modules Override 0 (0x2000:0B,
    guide Table 23) takes the RIM's modules out of the rack instead of refusing it; the RIM
    loss's Emergency 0xA001 goes to on_emergency (dropped by default)."""
    slave.add_emergency_callback(on_emergency)
    slave.sdo_write(0x2000, 0x0B, b"\x00")


def device_reset(master, slave, timeout_s=3.0):
    """0xFBF0:01 device reset with its signature (docs/MDP.md commands): returns once the
    slave reports INIT (its ESC restarted), fails after timeout_s."""
    slave.sdo_write(0xFBF0, 1, b"teser\x00")
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        master.read_state()
        if slave.state == pysoem.INIT_STATE:
            break
        time.sleep(0.01)
    assert slave.state == pysoem.INIT_STATE, (hex(slave.state), hex(slave.al_status))


def cycle(master):
    master.send_processdata()
    return master.receive_processdata(RECEIVE_TIMEOUT_US)


def to_op(master):
    go(master, pysoem.SAFEOP_STATE)
    cycle(master)
    master.state = pysoem.OP_STATE
    master.write_state()
    for _ in range(300):
        cycle(master)
        if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
            break
    go(master, pysoem.OP_STATE)


def run_cycles(master, n, until=None, sleep=True):
    """n process-data cycles at about 1 ms; returns the last working counter. `until(wkc)`
    stops early when it returns True."""
    wkc = None
    next_t = time.monotonic()
    for _ in range(n):
        wkc = cycle(master)
        if until is not None and until(wkc):
            break
        if sleep:
            next_t += CYCLE_S
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
    return wkc


def run_command(slave, index, command, timeout_s=5.0):
    """A command object (ETG.5003.1, docs/MDP.md): write the command bytes to :01, then poll
    :02 until it leaves 255 (executing); returns it (0/1 = done, 2 = error)."""
    slave.sdo_write(index, 1, command)
    deadline = time.monotonic() + timeout_s
    while True:
        status = slave.sdo_read(index, 2)[0]
        if status != 255:
            return status
        assert time.monotonic() < deadline, f"0x{index:04X} still executing"
        time.sleep(0.02)


def store_parameters(slave, timeout_s=5.0):
    """0xFBF2 Store Parameters: "save"."""
    return run_command(slave, 0xFBF2, STORE_SAVE, timeout_s)


def loopback_entries(slave):
    """The default rack's loopback pair in `slave`'s PDO map (read over SDO): the DO card's
    output word (module DO_MODULE, 0x7nn0:01) and the entry of the DI card wired to it
    (DI_LOOPBACK_MODULE, 0x6nn0:01), as (do, di) for set_bits/get_bits."""
    pdo = read_pdo_map(slave)
    return (pdo.find(0x7000 + (DO_MODULE - 1) * 0x10, 1, "out"),
            pdo.find(0x6000 + (DI_LOOPBACK_MODULE - 1) * 0x10, 1, "in"))


def wait_loopback(master, do, di, value, cycles=300):
    """Writes `value` to the DO card's entry `do` and cycles until the loopback-wired DI card's
    entry `di` shows it; returns what the DI card showed last."""
    s = master.slaves[0]
    got = None
    for _ in range(cycles):
        s.output = set_bits(s.output, do, value)
        cycle(master)
        got = get_bits(s.input, di)
        if got == value:
            return got
        time.sleep(0.001)
    return got


def check_capture(pcap):
    """Every captured frame dissects as EtherCAT and tshark finds nothing malformed."""
    total, ecat, bad = tshark_problems(pcap)
    assert total > 0, "empty capture"
    assert ecat == total, f"{total - ecat} of {total} captured frames not dissected as EtherCAT"
    assert bad == [], "tshark reports malformed frames / errors:\n" + "\n".join(bad[:20])


def abort_code(fn, *args, **kw):
    """The SDO abort code `fn` raised as pysoem.SdoError (fails if it succeeded)."""
    try:
        fn(*args, **kw)
    except pysoem.SdoError as e:
        return e.abort_code
    raise AssertionError(f"{fn.__name__}{args} succeeded, an SDO abort was expected")
