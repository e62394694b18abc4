"""KickCAT 2.5: an SDO abort reaches Python as 'Error while reading SDO - Timeout', without
its code (known_bugs.py)."""
import datetime

from harness import main


def reproduce(iface):
    import kickcat
    bus = kickcat.Bus(kickcat.create_link(iface, ""))
    bus.init(1.0)
    try:
        bus.read_sdo(bus.slaves()[0], 0x1234, 0, kickcat.Access.PARTIAL, 4,
                     datetime.timedelta(milliseconds=500))
    except RuntimeError as e:
        print(f"KickCAT: {e} (rackcat sent abort 0x06020000)")
        return "6020000" not in str(e).lower()  # the abort code never reaches the caller
    return True


main(reproduce)
