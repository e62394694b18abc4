"""soemx 0.1.1 and Emergencies. In OP (the matrix) the callback's error_code carries SOEM's
32-bit error union (0x94210 for 0x4210, known_bugs.py); here, in PRE-OP, the SDO read that
picks the Emergency up crashes the process (SIGSEGV in the extension, seen 2026-11-23)."""
import subprocess
import time

from harness import main
from matrix import RACKCAT


def reproduce(iface):
    import faulthandler
    faulthandler.enable()
    import soemx
    m = soemx.Master()
    m.open(iface)
    m.config_init()
    m.state = soemx.PREOP_STATE
    m.write_state()
    m.state_check(soemx.PREOP_STATE, 0, 2_000_000)
    m.read_state()
    seen = []
    s = m.slaves[0]
    s.add_emergency_callback(lambda e: seen.append(e.error_code))
    subprocess.run([str(RACKCAT), "ctl", "cpu-temp", "--celsius", "95", "--now"], check=True)
    deadline = time.monotonic() + 3
    while not seen and time.monotonic() < deadline:
        s.sdo_read(0x1018, 1)
        m.errors()
    print(f"soemx {soemx.__version__}: Emergency error_code {[hex(c) for c in seen]} "
          "(rackcat sent 0x4210)")
    return seen != [0x4210]


main(reproduce)
