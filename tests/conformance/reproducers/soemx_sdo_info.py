"""soemx 0.1.1: Slave.sdo_info() lists one object of the default rack's 163 (known_bugs.py)."""
from harness import main


def reproduce(iface):
    import soemx
    m = soemx.Master()
    m.open(iface)
    m.config_init()
    m.state = soemx.PREOP_STATE
    m.write_state()
    m.state_check(soemx.PREOP_STATE, 0, 2_000_000)
    m.read_state()
    n = len(m.slaves[0].sdo_info())
    print(f"soemx {soemx.__version__}: sdo_info() returned {n} object(s); rackcat has 163")
    return n != 163


main(reproduce)
