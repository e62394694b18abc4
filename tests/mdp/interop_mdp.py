#!/usr/bin/env python3
"""mdp interop with a real master (pysoem/SOEM) over veth, the issue's scenario.

  phase "store":  PREOP: read 0x2000:01, 0x3000, 0x3nn1 of several modules and 0xF050; write
                  0x2000:04 and store it with 0xFBF2 ("save").
  phase "check":  (after a restart of rackcat) 0x2000:04 reads the stored address; in OP a write
                  of 0x2000:04 is refused with 0x08000022; 0xF030 with a wrong ident 0x06090033.
Exit code 0 on success; every check prints one line.
"""
import struct
import sys
import time

import pysoem

FAILED = []


def check(what, ok, detail=""):
    print(f"  {'ok  ' if ok else 'FAIL'} {what}{(': ' + detail) if detail else ''}")
    if not ok:
        FAILED.append(what)


def text(b):
    return b.rstrip(b"\0").decode(errors="replace")


def go(master, state):
    master.state = state
    master.write_state()
    return master.state_check(state, 3_000_000) == state


def abort_of(fn):
    try:
        fn()
    except pysoem.SdoError as e:
        return e.abort_code
    return 0


def main():
    iface, phase, address = sys.argv[1], sys.argv[2], sys.argv[3]
    m = pysoem.Master()
    m.open(iface)
    try:
        n = m.config_init()
        check("one slave found", n == 1, str(n))
        s = m.slaves[0]
        check("PREOP", go(m, pysoem.PREOP_STATE))
        if phase == "store":
            check("0x2000:01 part number", text(s.sdo_read(0x2000, 1)) == "FI-CM0100-00",
                  text(s.sdo_read(0x2000, 1)))
            count = struct.unpack("<B", s.sdo_read(0x3000, 0))[0]
            idents = [struct.unpack("<I", s.sdo_read(0x3000, k))[0] for k in range(1, count + 1)]
            detected = [struct.unpack("<I", s.sdo_read(0xF050, k))[0] for k in range(1, count + 1)]
            check("0x3000 lists the modules and equals 0xF050", count > 0 and idents == detected,
                  f"{count} modules")
            for module in (1, 2, 15, 19):
                base = 0x3000 + (module - 1) * 0x10 + 1
                name = text(s.sdo_read(base, 1))
                rim = struct.unpack("<b", s.sdo_read(base, 4))[0]
                slot = struct.unpack("<b", s.sdo_read(base, 5))[0]
                check(f"0x{base:04X} module {module}", rim == 1 and slot == module,
                      f"{name} RIM {rim} slot {slot}")
            s.sdo_write(0x2000, 4, address.encode())
            check("0x2000:04 written in PREOP", text(s.sdo_read(0x2000, 4)) == address)
            s.sdo_write(0xFBF2, 1, b"save")
            status = 255
            deadline = time.monotonic() + 30  # 255 = executing (ETG.5003.1): fsync off the ESC thread
            while status == 255 and time.monotonic() < deadline:
                status = struct.unpack("<B", s.sdo_read(0xFBF2, 2))[0]
                time.sleep(0.01)
            check("0xFBF2 store completed (status 0)", status == 0, str(status))
        else:
            check("0x2000:04 survived the restart", text(s.sdo_read(0x2000, 4)) == address,
                  text(s.sdo_read(0x2000, 4)))
            rc = abort_of(lambda: s.sdo_write(0xF030, 1, struct.pack("<I", 0x0064A016)))
            check("0xF030 mismatch refused with 0x06090033", rc == 0x06090033, f"0x{rc:08X}")
            m.config_map()
            check("SAFEOP", go(m, pysoem.SAFEOP_STATE))
            m.send_processdata()
            m.receive_processdata(2000)
            check("OP", go(m, pysoem.OP_STATE))
            rc = abort_of(lambda: s.sdo_write(0x2000, 4, b"10.9.9.9"))
            check("0x2000:04 in OP refused with 0x08000022", rc == 0x08000022, f"0x{rc:08X}")
            go(m, pysoem.INIT_STATE)
    finally:
        m.close()
    return 1 if FAILED else 0


if __name__ == "__main__":
    sys.exit(main())
