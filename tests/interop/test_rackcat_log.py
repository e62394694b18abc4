"""What `rackcat run --log-level info` tells a user while pysoem drives it:
every ESM transition with the master's AL control, a refused transition with its AL status code
and meaning (an SM2 length that no longer matches the PDO assignment: 0x001D, ETG.1000.6 Table
11), and a master that stops sending in OP: the process-data watchdog expiry and the fall to
SAFEOP with 0x001B (ETG.1000.4 §6.5.3). The same events as JSON lines with --log-format json.
SDO aborts (at most 10 a second, the rest counted in the next line), injected faults, RIM state
changes and parameter stores in the text log.

Needs root (network namespace, veth, raw sockets); skips otherwise. About 14 s.
"""
import json
import re
import struct
import time

from rackcat_helpers import (cycle, go, open_master, pysoem, rackcat, store_parameters, to_op,
                             wait_watchdog_safeop)

assert rackcat  # the fixture, imported for pytest

RXPDO_ASSIGN = 0x1C12


def wait_for(rc, pattern, timeout=3.0):
    """The first log line matching `pattern` (a regex), waiting for the logging thread."""
    deadline = time.monotonic() + timeout
    while True:
        for line in rc.log().splitlines():
            if re.search(pattern, line):
                return line
        assert time.monotonic() < deadline, f"no log line /{pattern}/ in:\n{rc.log()}"
        time.sleep(0.05)


def drive(rc):
    """INIT -> PREOP, a refused SAFEOP (SM2 length vs PDO assignment), SAFEOP, OP, then the
    master goes silent until the watchdog sends the slave to SAFEOP."""
    master = open_master(rc.iface)
    try:
        s = master.slaves[0]
        master.config_map()  # SM2/SM3 lengths from the current assignment (SOEM: to SAFEOP)
        go(master, pysoem.PREOP_STATE)
        # Drop the last RxPDO from the assignment: the SM2 length the master wrote no longer
        # matches, so SAFEOP is refused with 0x001D (ETG.1000.6 §5.3, Table 11).
        n = struct.unpack("<B", s.sdo_read(RXPDO_ASSIGN, 0))[0]
        s.sdo_write(RXPDO_ASSIGN, 0, struct.pack("<B", n - 1))
        s.state = pysoem.SAFEOP_STATE
        s.write_state()
        master.state_check(pysoem.SAFEOP_STATE, 500_000)
        s.sdo_write(RXPDO_ASSIGN, 0, struct.pack("<B", n))
        s.state = pysoem.PREOP_STATE | 0x10  # acknowledge the error flag
        s.write_state()
        go(master, pysoem.PREOP_STATE)
        to_op(master)
        for _ in range(50):
            cycle(master)
            time.sleep(0.001)
        # The master stops: the SM2 watchdog (100 ms by default) expires.
        wait_watchdog_safeop(master)
        assert s.state == pysoem.SAFEOP_STATE | 0x10, hex(s.state)
        assert s.al_status == 0x001B, hex(s.al_status)
    finally:
        master.close()


def test_esm_transitions_refusals_and_watchdog_in_the_text_log(rackcat):
    rc = rackcat(pcap=False, extra=("--log-level", "info"))
    drive(rc)
    # SOEM asks for PREOP with the acknowledge bit set (0x12).
    wait_for(rc, r" info: ESM INIT -> PREOP \(master's AL control 0x[01]2\)")
    wait_for(rc, r" warning: ESM refused PREOP -> SAFEOP requested by the master \(AL control "
                 r"0x04\): AL status code 0x001D \(Invalid output configuration\); stays in PREOP")
    wait_for(rc, r" info: ESM PREOP -> SAFEOP \(master's AL control 0x04\)")
    wait_for(rc, r" info: ESM SAFEOP -> PREOP \(master's AL control 0x02\)")
    wait_for(rc, r" info: ESM SAFEOP -> OP \(master's AL control 0x08\)")
    wait_for(rc, r" warning: process-data watchdog expired in OP")
    wait_for(rc, r" warning: ESM error in OP: AL status code 0x001B \(Sync manager watchdog\); "
                 r"falls to SAFEOP with the error flag")


def test_the_same_events_as_json_lines(rackcat):
    rc = rackcat(pcap=False, extra=("--log-level", "info", "--log-format", "json"))
    drive(rc)
    wait_for(rc, r'"event": ?"watchdog_expired"')
    events = []
    for line in rc.log().splitlines():
        if line.startswith("{"):
            events.append(json.loads(line))
    kinds = [(e.get("event"), e.get("from"), e.get("to"), e.get("al_status_code"))
             for e in events if "event" in e]
    assert ("esm_transition", "INIT", "PREOP", 0) in kinds, kinds
    assert ("esm_refused", "PREOP", "PREOP", 0x001D) in kinds, kinds
    assert ("esm_transition", "SAFEOP", "OP", 0) in kinds, kinds
    assert ("esm_error", "OP", "SAFEOP", 0x001B) in kinds, kinds
    for e in events:
        assert {"time", "level", "msg"} <= e.keys(), e


SOUT = 1  # default rack: CDO-10 16xDout Source (detects wiring faults, guide 4.7)


def test_aborts_faults_rim_states_and_stores_in_the_log(rackcat):
    rc = rackcat(pcap=False, extra=("--log-level", "info"))
    master = open_master(rc.iface)
    try:
        s = master.slaves[0]
        # A burst of SDO aborts (object does not exist, 0x06020000): logged at most 10 a second.
        for _ in range(25):
            try:
                s.sdo_read(0x5FFF, 0)
                raise AssertionError("0x5FFF exists")
            except pysoem.SdoError:
                pass
        time.sleep(1.1)  # the next second: the next abort says how many were not logged
        try:
            s.sdo_read(0x5FFF, 0)
        except pysoem.SdoError:
            pass
        assert store_parameters(s) == 0  # 0xFBF2 "save"
    finally:
        master.close()
    rc.cli("wiring-fault", "--module", SOUT, "--channel", 3, "--fault", "unsafe")
    rc.cli("unplug", "--rim", 2)
    abort = r" info: SDO abort 0x5FFF:00: 0x06020000 \(The object does not exist in the object " \
            r"dictionary\)"
    wait_for(rc, abort + r" \(\d+ more not logged\)$")
    aborts = [line for line in rc.log().splitlines() if re.search(abort, line)]
    assert 2 <= len(aborts) <= 21, aborts  # at most 10 a second of the 26
    wait_for(rc, r" info: fault injected: module 1 channel 3 wiring fault unsafe "
                 r"\(short to supply\)")
    wait_for(rc, r" warning: RIM 2 ONLINE -> OFFLINE$")
    wait_for(rc, r" info: store parameters: done$")
