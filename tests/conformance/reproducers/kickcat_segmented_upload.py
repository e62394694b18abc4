"""KickCAT 2.5: a segmented upload (complete access of 0x2000, 229 bytes) crashes the
process (known_bugs.py)."""
import datetime

from harness import main


def reproduce(iface):
    import kickcat
    bus = kickcat.Bus(kickcat.create_link(iface, ""))
    bus.init(1.0)
    data = bus.read_sdo(bus.slaves()[0], 0x2000, 0, kickcat.Access.COMPLETE, 1024,
                        datetime.timedelta(milliseconds=500))
    print(f"read {len(data)} bytes")
    return len(data) != 229


main(reproduce)
