"""The conformance scenario through a SOEM binding with pysoem's API shape (pysoem, soemx):
every step is in SOEM's API. `Api` holds what differs between the bindings."""
import struct
import time

from common import (LRW_WKC_PER_SLAVE, check, check_descriptions, check_identity,
                    check_od_list, check_sii_words, check_sizes, LoopbackRun, run_sdo_steps,
                    scan, trigger, while_cycling)

RECEIVE_TIMEOUT_US = 20_000


class Api:
    """pysoem's spelling; the soemx driver overrides what it spells differently."""

    # objects whose entry descriptions are compared (None: all; pysoem reads them all anyway)
    entries_of = None

    def __init__(self, lib):
        self.lib = lib

    def state_check(self, m, state, timeout_us):
        return m.state_check(state, timeout_us)

    def od(self, s0, wanted_entries):
        """{index: (name, {sub: (name, data_type, bits)})} through SDO information."""
        od = {}
        for obj in s0.od:
            entries = {}
            if wanted_entries is None or obj.index in wanted_entries:
                entries = {k: (_text(e.name), e.data_type, e.bit_length)
                           for k, e in enumerate(obj.entries) if e.name}
            od[obj.index] = (_text(obj.name), entries)
        return od

    def pump_emergencies(self, m):
        pass

    def drain_errors(self, m, s0):
        """SOEM keeps an error for every subindex gap it met reading the entry descriptions;
        pysoem raises them one per later call ("unexpected error, Etype: 4"). Returns how
        many were drained."""
        n = 0
        for _ in range(256):
            try:
                s0.sdo_read(0x1018, 1)
                return n
            except Exception as e:  # noqa: BLE001 - pysoem raises a bare Exception here
                if "Etype: 4" not in str(e):
                    raise
                n += 1
        return n

    def dc_readback(self, m):
        return "no register read-back in this API"


def _text(v):
    return v.decode() if isinstance(v, bytes) else v


def run(api, m, rec, exp):
    try:
        scenario(m, rec, exp, api)
    finally:
        m.close()


def go(m, state, api, timeout_us=3_000_000):
    m.state = state
    m.write_state()
    reached = api.state_check(m, state, timeout_us)
    m.read_state()
    bad = [(i, hex(s.state), hex(s.al_status)) for i, s in enumerate(m.slaves)
           if s.state != state or s.al_status != 0]
    check(reached == state and not bad, f"state 0x{state:X} not reached: {bad[:4]}")


def scenario(m, rec, exp, api):
    pysoem = api.lib
    n = exp["slaves"]

    if not rec.run("scan", lambda: scan(m.config_init, n)):
        return
    s0 = m.slaves[0]
    rec.run("identity", lambda: check_identity([(s.man, s.id, s.rev) for s in m.slaves], exp))

    def sii_words(i):
        s = m.slaves[i]
        words = []
        for w in range(0, 64, 2):
            words += struct.unpack("<HH", s.eeprom_read(w))
        return words

    rec.run("sii", lambda: check_sii_words(sii_words, exp))
    rec.run("preop", lambda: go(m, pysoem.PREOP_STATE, api))

    def read(index, sub):
        return s0.sdo_read(index, sub)

    def write(index, sub, data):
        s0.sdo_write(index, sub, bytes(data))

    def read_ca(index):
        return s0.sdo_read(index, 0, 1024, ca=True)

    pre = ("preop",)
    run_sdo_steps(rec, read, write, read_ca, exp)

    def aborts():
        codes = []
        for fn, a in ((s0.sdo_read, (0x1234, 0)), (s0.sdo_write, (0x1018, 1, b"\1\0\0\0"))):
            try:
                fn(*a)
                codes.append(None)
            except pysoem.SdoError as e:
                codes.append(e.abort_code)
        check(codes == [0x06020000, 0x06010002], f"abort codes {codes}")
        check(struct.unpack("<I", s0.sdo_read(0x1018, 2))[0] == exp["identity"][1],
              "no normal answer after the aborts")
        return "0x06020000, 0x06010002"

    rec.run("sdo_abort", aborts, pre)
    def mapping():
        m.config_map()
        return check_sizes([(len(s.output), len(s.input)) for s in m.slaves], exp)

    rec.run("pdo_sizes", mapping, pre)

    # SDO information after the mapping: SOEM reads every subindex up to MaxSub and keeps an
    # error for each gap, which rackcat rightly answers with an SDO information error
    # (0x06090011); pysoem's config_map then fails on any error SOEM kept ("unexpected error").
    od = {}

    def od_list():
        od.update(api.od(s0, api.entries_of))
        text = check_od_list(list(od), exp)
        kept = api.drain_errors(m, s0)
        return text + (f"; {kept} SDO information errors for subindex gaps drained" if kept
                       else "")

    rec.run("sdo_info_list", od_list, pre)
    # SOEM keeps EC_MAXNAME = 40 characters of a name (ec_coe.h)
    rec.run("sdo_info_desc", lambda: check_descriptions(od, exp, name_limit=40),
            ("sdo_info_list",))

    def dc():
        check(m.config_dc(), "config_dc: no slave with a distributed clock")
        for s in m.slaves:
            s.dc_sync(True, exp["cycle_us"] * 1000)
        return f"SYNC0 {exp['cycle_us']} us on {n} slave(s), {api.dc_readback(m)}"

    rec.run("dc_sync0", dc, ("pdo_sizes",))

    def cycle():
        m.send_processdata()
        return m.receive_processdata(RECEIVE_TIMEOUT_US)

    def safeop():
        go(m, pysoem.SAFEOP_STATE, api)

    rec.run("safeop", safeop, ("pdo_sizes",))

    def op():
        cycle()
        m.state = pysoem.OP_STATE
        m.write_state()
        for _ in range(300):
            cycle()
            if api.state_check(m, pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
                break
        go(m, pysoem.OP_STATE, api)
        return f"expected WKC {m.expected_wkc}"

    rec.run("op", op, ("safeop",))
    expected = LRW_WKC_PER_SLAVE * n
    run = LoopbackRun(exp)

    def cycles():
        check(m.expected_wkc == expected, f"pysoem expects WKC {m.expected_wkc}, not {expected}")
        slaves = m.slaves

        def set_out(i, data):
            slaves[i].output = data

        run.run(cycle, lambda i: slaves[i].output, set_out, lambda i: slaves[i].input,
                expected, exp["cycles"])
        return run.wkc_result(expected, exp["cycles"])

    rec.run("cycles", cycles, ("op",))
    rec.run("loopback", run.loopback_result, ("cycles",))

    def emergency():
        seen = []
        s0.add_emergency_callback(lambda e: seen.append(e.error_code))
        while_cycling(cycle, lambda: trigger(exp["emergency"]["raise"]))
        deadline = time.monotonic() + 3
        # Until the master reports an Emergency (its code is judged below), as an application
        # polls: one SDO read and one process-data cycle per millisecond. A loop without the
        # pause spins the master's real-time thread for 3 s and measures the host, not rackcat.
        while not seen and time.monotonic() < deadline:
            # SOEM picks Emergencies up while it waits for a mailbox reply
            s0.sdo_read(0x1018, 1)
            api.pump_emergencies(m)
            cycle()
            time.sleep(exp["cycle_us"] / 1e6)
        while_cycling(cycle, lambda: trigger(exp["emergency"]["clear"]))
        check(exp["emergency"]["code"] in seen, f"no Emergency 0x{exp['emergency']['code']:04X};"
                                                f" got {[hex(c) for c in seen]}")
        return f"0x{exp['emergency']['code']:04X}"

    rec.run("emergency", emergency, ("op",))

    def back_to_init():
        for state in (pysoem.SAFEOP_STATE, pysoem.PREOP_STATE, pysoem.INIT_STATE):
            go(m, state, api)
        return "OP -> SAFE-OP -> PRE-OP -> INIT"

    rec.run("init", back_to_init, ("scan",))


