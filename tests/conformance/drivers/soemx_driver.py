"""The conformance scenario through soemx (Cython bindings of SOEM 2.x with EoE): every step
is in its API; it reads the DC registers back, which pysoem cannot."""
import struct

import soemx

from common import Recorder, check, parse_args
from soem_family import Api, run


class SoemxApi(Api):
    entries_of = (0x1018, 0x2000, 0x1C12)  # one SDO information exchange per entry list
    def state_check(self, m, state, timeout_us):
        return m.state_check(state, 0, timeout_us)

    def od(self, s0, wanted_entries):
        od = {}
        for obj in s0.sdo_info():
            entries = {}
            if wanted_entries is None or obj["index"] in wanted_entries:
                entries = {e["subindex"]: (e["name"].decode(), e["data_type"], e["bit_length"])
                           for e in s0.sdo_entries(obj["index"]) if e["name"]}
            od[obj["index"]] = (obj["name"].decode(), entries)
        return od

    def drain_errors(self, m, s0):
        return len(m.errors())

    def pump_emergencies(self, m):
        # soemx hands Emergencies to the callbacks when SOEM's error list is read
        m.errors()

    def dc_readback(self, m):
        # ETG.1000.4: 0x0981 activation (0x03 = cyclic + SYNC0), 0x09A0 SYNC0 cycle time
        for i, s in enumerate(m.slaves):
            act = m.read_register(i + 1, 0x0981, 1)[0]
            cyc = struct.unpack("<I", m.read_register(i + 1, 0x09A0, 4))[0]
            check(act & 0x03 == 0x03, f"slave {i}: 0x0981 = 0x{act:02X}")
            check(cyc == 1_000_000, f"slave {i}: 0x09A0 = {cyc} ns")
        return "0x0981 = 0x03 and 0x09A0 = 1 ms read back"


def main():
    args, exp = parse_args()
    rec = Recorder(args.out, "soemx", f"soemx {soemx.__version__} (SOEM 2.x vendored)")
    m = soemx.Master()
    m.open(args.iface)
    run(SoemxApi(soemx), m, rec, exp)


if __name__ == "__main__":
    main()
