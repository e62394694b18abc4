"""The conformance scenario through pyecm (nanobind bindings of SOEM 2.x's ecx_ API).

Offered: scan (ecx_config_init, SII identity), states, SDO read/write with complete access,
SOEM's error list (aborts, Emergencies), distributed clocks with SYNC0, and only the
*overlapping* process image (ecx_config_overlap_map: inputs and outputs share logical
addresses). Not offered: EEPROM access and SDO information.
"""
import time

import numpy as np
from pyecm.soem import SOEM

from common import (LRW_WKC_PER_SLAVE, LoopbackRun, Recorder, check, check_identity,
                    check_sizes, parse_args, run_sdo_steps, scan, trigger, while_cycling)

SDO_TIMEOUT_US = 700_000
RECEIVE_TIMEOUT_US = 20_000
INIT, PREOP, SAFEOP, OP = 1, 2, 4, 8
EC_ERR_TYPE_SDO_ERROR = "SDO_ERROR"
EC_ERR_TYPE_EMERGENCY = "EMERGENCY"


def version():
    from importlib.metadata import version as v
    return f"pyecm {v('pyecm')} (SOEM 2.x)"


class SdoFailed(Exception):
    def __init__(self, what, errors):
        self.abort_codes = [e.AbortCode & 0xFFFFFFFF for e in errors
                            if e.Etype.name.endswith(EC_ERR_TYPE_SDO_ERROR)]
        kept = [(e.Etype.name, hex(e.AbortCode & 0xFFFFFFFF)) for e in errors]
        super().__init__(f"{what}: SOEM errors {kept}")


def main():
    args, exp = parse_args()
    rec = Recorder(args.out, "pyecm", version())
    m = SOEM()
    check(m.init(args.iface) > 0, f"ecx_init({args.iface}) failed")
    try:
        scenario(m, rec, exp)
    finally:
        m.close()


def errors(m, seen_emergencies):
    out = []
    while m.iserror():
        ok, e = m.poperror()
        if not ok:
            break
        if e.Etype.name.endswith(EC_ERR_TYPE_EMERGENCY):
            seen_emergencies.append(e.ErrorCode)
        else:
            out.append(e)
    return out


def scenario(m, rec, exp):
    n = exp["slaves"]
    emcy = []

    def request(state):
        # `subdevices` is a copy of SOEM's slave list and its items are copies too: change
        # entry 0 (the whole segment), put it back, hand the list back
        subs = m.subdevices
        everyone = subs[0]
        everyone.state = state
        subs[0] = everyone
        m.subdevices = subs
        m.writestate(0)

    def go(state, timeout_us=3_000_000):
        request(state)
        reached = m.statecheck(0, state, timeout_us)
        m.readstate()
        bad = [(i, hex(s.state), hex(s.ALstatuscode)) for i, s in
               enumerate(list(m.subdevices)[1:n + 1]) if s.state != state or s.ALstatuscode]
        check(reached == state and not bad, f"state 0x{state:X} not reached: {bad[:4]}")

    if not rec.run("scan", lambda: scan(m.config_init, n, "ecx_config_init")):
        return
    rec.run("identity", lambda: check_identity(
        [(s.eep_man, s.eep_id, s.eep_rev) for s in list(m.subdevices)[1:n + 1]], exp))
    rec.not_offered("sii", "no EEPROM access in the bindings")
    rec.run("preop", lambda: go(PREOP))

    def read(index, sub, ca=0):
        wkc, size, data = m.SDOread(1, index, sub, ca, 1024, SDO_TIMEOUT_US)
        if wkc <= 0:
            raise SdoFailed(f"SDOread 0x{index:04X}:{sub}", errors(m, emcy))
        return bytes(data[:size])

    def write(index, sub, data):
        wkc = m.SDOwrite(1, index, sub, 0, np.array(list(bytes(data)), dtype=np.uint8),
                         SDO_TIMEOUT_US)
        if wkc <= 0:
            raise SdoFailed(f"SDOwrite 0x{index:04X}:{sub}", errors(m, emcy))

    def read_ca(index):
        return read(index, 0, 1)

    pre = ("preop",)
    run_sdo_steps(rec, read, write, read_ca, exp)

    def aborts():
        codes = []
        for fn in (lambda: read(0x1234, 0), lambda: write(0x1018, 1, b"\1\0\0\0")):
            try:
                fn()
                codes.append(None)
            except SdoFailed as e:
                codes.append(e.abort_codes[0] if e.abort_codes else str(e))
        check(codes == [0x06020000, 0x06010002], f"abort codes {codes}")
        return "0x06020000, 0x06010002 (SOEM's error list)"

    rec.run("sdo_abort", aborts, pre)
    rec.not_offered("sdo_info_list", "no SDO information in the bindings")
    rec.not_offered("sdo_info_desc", "no SDO information in the bindings")

    def mapping():
        m.config_overlap_map()
        subs = list(m.subdevices)[1:n + 1]
        return check_sizes([(s.Obytes, s.Ibytes) for s in subs], exp) + \
            " (overlapping map: ecx_config_overlap_map)"

    rec.run("pdo_sizes", mapping, pre)

    def dc():
        check(m.configdc(), "ecx_configdc: no slave with a distributed clock")
        for i in range(1, n + 1):
            m.dcsync0(i, 1, exp["cycle_us"] * 1000, 0)
        return f"SYNC0 {exp['cycle_us']} us on {n} slave(s)"

    rec.run("dc_sync0", dc, ("pdo_sizes",))

    def cycle():
        m.send_overlap_processdata_group(0)
        return m.receive_processdata_group(0, RECEIVE_TIMEOUT_US)

    rec.run("safeop", lambda: go(SAFEOP), ("pdo_sizes",))

    def op():
        cycle()
        request(OP)
        for _ in range(300):
            cycle()
            if m.statecheck(0, OP, 1000) == OP:
                break
        go(OP)

    rec.run("op", op, ("safeop",))
    expected = LRW_WKC_PER_SLAVE * n
    run = LoopbackRun(exp)

    def cycles():
        # get_iomap(slave) -> (inputs, outputs) views into the process image
        views = [m.get_iomap(i) for i in range(1, n + 1)]

        def set_out(i, data):
            views[i][1][:] = np.frombuffer(data, dtype=np.uint8)

        run.run(cycle, lambda i: views[i][1].tobytes(), set_out, lambda i: views[i][0].tobytes(),
                expected, exp["cycles"])
        return run.wkc_result(expected, exp["cycles"])

    rec.run("cycles", cycles, ("op",))
    rec.run("loopback", run.loopback_result, ("cycles",))

    def emergency():
        while_cycling(cycle, lambda: trigger(exp["emergency"]["raise"]))
        deadline = time.monotonic() + 3
        code = exp["emergency"]["code"]
        # until SOEM reports an Emergency, paced like an application (soem_family.py)
        while code not in emcy and time.monotonic() < deadline:
            m.SDOread(1, 0x1018, 1, 0, 4, SDO_TIMEOUT_US)  # SOEM reads Emergencies meanwhile
            errors(m, emcy)
            cycle()
            time.sleep(exp["cycle_us"] / 1e6)
        while_cycling(cycle, lambda: trigger(exp["emergency"]["clear"]))
        check(code in emcy, f"no Emergency 0x{code:04X}; got {[hex(c) for c in emcy]}")
        return f"0x{code:04X} from SOEM's error list"

    rec.run("emergency", emergency, ("op",))

    def back_to_init():
        for state in (SAFEOP, PREOP, INIT):
            go(state)
        return "OP -> SAFE-OP -> PRE-OP -> INIT"

    rec.run("init", back_to_init, ("scan",))


if __name__ == "__main__":
    main()
