"""[diagnostics] The 0x10F3 diagnosis history (ETG.1020 ch. 13) read by a real master (pysoem)
over the wire: every fault class injected with `rackcat ctl`, the history read by complete
access and by single subindices, each message decoded (diag code, type, text ID, time stamp,
parameters RIM / module / channel / detail), appears/removed pairs, DC time stamps while SYNC0
runs, New Messages Available mapped into the process data (TxPDO 0x1BFF), acknowledge, clear
and overflow in both modes.

Message layout (ETG.1020 ch. 13, little-endian): diag code u32 (bits 0..15 0xE800: the
Emergency code is in bits 16..31), flags u16 (bits 0..3 type 0 info / 1 warning / 2 error, bit 4
local time stamp, bits 8..15 parameter count), text ID u16, time stamp u64 ns, then per
parameter a u16 data type (ETG.1000.6 index) and the value.
"""
import struct
import time

from rackcat_helpers import (abort_code, go, pysoem, rack_with_master, rackcat,
                             read_pdo_map, get_bits, run_cycles, to_op)

assert rackcat  # the fixture, imported for pytest

DIAG = 0x10F3
MAX_MESSAGES = 64
MESSAGE_BYTES = 32
FIRST = 6
# Default rack (examples/default-rack.yaml): RIM 1 slot n = module n.
DO_MODULE, AO_MODULE, AI_MODULE, TC_MODULE, UART_MODULE = 1, 11, 12, 15, 19
TYPE_SIZE = {0x0001: 1, 0x0002: 1, 0x0005: 1, 0x0003: 2, 0x0006: 2, 0x0004: 4, 0x0007: 4}


def decode(raw):
    """One diagnosis message slot -> dict, None for an empty slot."""
    if not any(raw):
        return None
    code, flags, text, ts = struct.unpack_from("<IHHQ", raw, 0)
    params, pos = [], 16
    for _ in range(flags >> 8):
        dtype, = struct.unpack_from("<H", raw, pos)
        size = TYPE_SIZE[dtype]
        params.append(int.from_bytes(raw[pos + 2:pos + 2 + size], "little"))
        pos += 2 + size
    assert code & 0xFFFF == 0xE800, f"diag code 0x{code:08X} is not an Emergency-code diag code"
    return {"emcy": code >> 16, "type": flags & 0x0F, "local": bool(flags & 0x10),
            "text": text, "time": ts, "rim": params[0], "module": params[1],
            "channel": params[2], "detail": params[3]}


def read_history(slave):
    """0x10F3 by complete access, checked against single-subindex reads; returns
    (header dict, messages oldest first)."""
    ca = slave.sdo_read(DIAG, 0, 4096, ca=True)
    slots = ca[len(ca) - MAX_MESSAGES * MESSAGE_BYTES:]
    flags_ca, = struct.unpack_from("<H", ca, len(ca) - MAX_MESSAGES * MESSAGE_BYTES - 2)
    head = {"sub0": ca[0], "max": ca[2], "newest": ca[3], "acked": ca[4],
            "flags": flags_ca}
    assert head["sub0"] == 5 + MAX_MESSAGES and head["max"] == MAX_MESSAGES
    # Single subindices agree with the complete access.
    assert slave.sdo_read(DIAG, 1)[0] == MAX_MESSAGES
    assert slave.sdo_read(DIAG, 2)[0] == head["newest"]
    assert slave.sdo_read(DIAG, 3)[0] == head["acked"]
    assert struct.unpack("<H", slave.sdo_read(DIAG, 5))[0] == head["flags"]
    messages = {}
    for i in range(MAX_MESSAGES):
        raw = slots[i * MESSAGE_BYTES:(i + 1) * MESSAGE_BYTES]
        m = decode(raw)
        if m is not None:
            messages[FIRST + i] = m
    if head["newest"]:
        single = slave.sdo_read(DIAG, head["newest"])
        start = (head["newest"] - FIRST) * MESSAGE_BYTES
        assert single == slots[start:start + MESSAGE_BYTES]
    # Oldest first: the ring runs up to the newest and wraps.
    order = []
    if head["newest"]:
        n = len(messages)
        newest = head["newest"] - FIRST
        for age in range(n):
            order.append(FIRST + (newest - (n - 1) + age) % MAX_MESSAGES)
    return head, [dict(messages[s], sub=s) for s in order]


def wait_for(master, rc, predicate, timeout_s=3.0):
    slave = master.slaves[0]
    deadline = time.monotonic() + timeout_s
    while True:
        run_cycles(master, 5)
        head, msgs = read_history(slave)
        if predicate(msgs):
            return head, msgs
        assert time.monotonic() < deadline, f"history: {msgs[-8:]}"


def test_fault_classes_in_the_history_with_dc_time(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        # Process data: one RxPDO (the DO card) and the diagnosis TxPDO (New Messages
        # Available, 1 bit + 7 padding), assigned in PREOP.
        s.sdo_write(0x1C12, 0, b"\x00")
        s.sdo_write(0x1C12, 1, struct.pack("<H", 0x1600 + DO_MODULE - 1))
        s.sdo_write(0x1C12, 0, b"\x01")
        s.sdo_write(0x1C13, 0, b"\x00")
        s.sdo_write(0x1C13, 1, struct.pack("<H", 0x1BFF))
        s.sdo_write(0x1C13, 0, b"\x01")
        pdo = read_pdo_map(s)
        nma = pdo.find(DIAG, 4, "in")
        master.config_map()
        assert master.config_dc(), "no distributed clock"
        s.dc_sync(True, 1_000_000)
        to_op(master)
        run_cycles(master, 300)  # SOEM starts SYNC0 100 ms after dc_sync
        _, before = read_history(s)
        start = len(before)
        emergencies = []
        s.add_emergency_callback(lambda e: emergencies.append(e.error_code))

        faults = [
            (("sensor", "--module", TC_MODULE, "--channel", 2, "--open"),
             ("sensor", "--module", TC_MODULE, "--channel", 2, "--close"),
             0x8606, 0xFF06, TC_MODULE, 2),
            (("set", "--module", AI_MODULE, "--channel", 5, "--value", 12),
             ("set", "--module", AI_MODULE, "--channel", 5, "--value", 0),
             0x4607, 0xFF07, AI_MODULE, 5),
            (("output-fault", "--module", AO_MODULE, "--channel", 4, "--overload", "true"),
             ("output-fault", "--module", AO_MODULE, "--channel", 4, "--overload", "false"),
             0x8604, 0x2310, AO_MODULE, 4),
            (("output-fault", "--module", AO_MODULE, "--channel", 6, "--overtemperature", "true"),
             ("output-fault", "--module", AO_MODULE, "--channel", 6, "--overtemperature",
              "false"),
             0x8605, 0x4200, AO_MODULE, 6),
            (("fan", "--rim", 1, "--zone", "slot_card", "--rpm", 2400),
             ("fan", "--rim", 1, "--zone", "slot_card", "--rpm", 3000),
             0x4211, 0x5000, 0, None),
            (("mcm-error", "--rim", 1, "--error", "slot_machine_mcm0"),
             ("mcm-error", "--rim", 1),
             0x8221, 0x6000, 0, None),
            (("cpu-temp", "--celsius", 90, "--now"), ("cpu-temp", "--celsius", 40, "--now"),
             0x8101, 0x4210, 0, None),
            (("unplug", "--rim", 2), ("replug", "--rim", 2), 0x8202, 0xA001, 0, None),
        ]
        for appear, disappear, text, emcy, module, channel in faults:
            rc.cli_while_cycling(master, *appear)
            _, msgs = wait_for(master, rc, lambda m: any(x["text"] == text for x in m[start:]))
            # Overwrite mode: New Messages Available (mapped into the process data) stays
            # set until the newest message is read by SDO.
            for _ in range(5):
                s.sdo_read(DIAG, s.sdo_read(DIAG, 2)[0])
                run_cycles(master, 5)
                if get_bits(s.input, nma) == 0:
                    break
            assert get_bits(s.input, nma) == 0
            rc.cli_while_cycling(master, *disappear)
            run_cycles(master, 300, until=lambda _: get_bits(s.input, nma) == 1)
            assert get_bits(s.input, nma) == 1, "New Messages Available not set in the PDO"
            _, msgs = wait_for(master, rc,
                               lambda m: any(x["text"] == (text & 0x0FFF) | 0x1000
                                             for x in m[start:]))
            new = msgs[start:]
            a = next(x for x in new if x["text"] == text)
            r = next(x for x in new if x["text"] == (text & 0x0FFF) | 0x1000)
            assert a["emcy"] == emcy and a["type"] == text >> 14 and r["type"] == 0, (a, r)
            assert r["emcy"] == 0 and new.index(r) > new.index(a)
            if module:
                assert (a["module"], a["channel"]) == (module, channel), a
                assert (r["module"], r["channel"]) == (module, channel), r
            start = len(msgs)
        # UART line errors are events (no removal message).
        rc.cli_while_cycling(master, "uart", "--module", UART_MODULE, "--channel", 1,
                             "--error", "framing")
        _, msgs = wait_for(master, rc, lambda m: any(x["text"] == 0x4702 for x in m))
        u = next(x for x in msgs if x["text"] == 0x4702)
        assert (u["module"], u["channel"], u["emcy"]) == (UART_MODULE, 1, 0xFF72)
        # Every stored message went out as Emergency, in the same order, and nothing else
        # (ETG.1020 ch. 13 with 0x10F3:05 bit 0, the default).
        s.sdo_read(0x1018, 1)
        assert emergencies == [x["emcy"] for x in msgs[len(before):]]
        # DC system time while SYNC0 runs, never going back.
        times = [x["time"] for x in msgs[len(before):]]
        assert not any(x["local"] for x in msgs[len(before):]), msgs[len(before):]
        assert times == sorted(times), times
        assert times[0] > 0
        go(master, pysoem.INIT_STATE)


def toggle_sensor(rc, n):
    for i in range(n):
        rc.cli("sensor", "--module", TC_MODULE, "--channel", i % 8, "--open")
        rc.cli("sensor", "--module", TC_MODULE, "--channel", i % 8, "--close")


def test_acknowledge_clear_and_overflow(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        s.add_emergency_callback(lambda e: None)
        s.sdo_write(DIAG, 3, b"\x00")  # clear (overwrite mode: every message)
        head, msgs = read_history(s)
        assert head["newest"] == 0 and msgs == [] and head["flags"] == 0x0001
        toggle_sensor(rc, 2)
        head, msgs = read_history(s)
        assert [m["text"] for m in msgs] == [0x8606, 0x1606] * 2
        assert s.sdo_read(DIAG, 4) in (b"\x00", b"\x01")
        # Acknowledge the second message: 0x10F3:03 reads it back.
        s.sdo_write(DIAG, 3, bytes([msgs[1]["sub"]]))
        assert s.sdo_read(DIAG, 3)[0] == msgs[1]["sub"]
        assert abort_code(s.sdo_write, DIAG, 3, b"\x05") == 0x06090032
        assert abort_code(s.sdo_write, DIAG, 3, bytes([FIRST + MAX_MESSAGES])) == 0x06090031
        assert abort_code(s.sdo_write, DIAG, 3, bytes([FIRST + 10])) == 0x06090030
        assert abort_code(s.sdo_write, DIAG, 5, struct.pack("<H", 0x0100)) == 0x06090030
        # Overwrite mode: 70 messages overwrite unacknowledged ones: bit 5.
        toggle_sensor(rc, 35)
        head, msgs = read_history(s)
        assert len(msgs) == MAX_MESSAGES and head["flags"] & 0x20 and head["acked"] == 0
        s.sdo_write(DIAG, 3, b"\x00")
        head, msgs = read_history(s)
        assert msgs == [] and head["flags"] == 0x0001
        # Acknowledge mode: full of unacknowledged messages, the next one is discarded.
        s.sdo_write(DIAG, 5, struct.pack("<H", 0x0011))
        toggle_sensor(rc, 32)
        head, msgs = read_history(s)
        assert len(msgs) == MAX_MESSAGES and not head["flags"] & 0x20
        newest = head["newest"]
        toggle_sensor(rc, 1)
        head, msgs = read_history(s)
        assert head["newest"] == newest and head["flags"] == 0x0031
        assert s.sdo_read(DIAG, 4) == b"\x01"
        # Acknowledge 10, delete the acknowledged ones, room for new messages again.
        s.sdo_write(DIAG, 3, bytes([msgs[9]["sub"]]))
        s.sdo_write(DIAG, 3, b"\x00")
        head, msgs = read_history(s)
        assert len(msgs) == MAX_MESSAGES - 10 and head["acked"] == 0
        toggle_sensor(rc, 1)
        head, msgs = read_history(s)
        assert len(msgs) == MAX_MESSAGES - 8
        # Filters: errors disabled, the line break is not stored, its removal (info) is.
        s.sdo_write(DIAG, 5, struct.pack("<H", 0x0008))
        toggle_sensor(rc, 1)
        head, msgs = read_history(s)
        assert [m["text"] for m in msgs[-1:]] == [0x1606]
        # The history as text.
        text = rc.cli("diag", text=True)
        assert "line break removed" in text and "overwrite mode" in text, text
        go(master, pysoem.INIT_STATE)
