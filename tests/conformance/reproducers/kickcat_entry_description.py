"""KickCAT 2.5: an entry description's name starts with the entry's default value
(known_bugs.py)."""
from harness import main


def reproduce(iface):
    import kickcat
    bus = kickcat.Bus(kickcat.create_link(iface, ""))
    bus.init(1.0)
    name, _ = bus.read_entry_description(bus.slaves()[0], 0x1018, 4)
    print(f"0x1018:04 name {name!r} (rackcat: 'Serial number' after the 4-byte default)")
    return name != "Serial number"


main(reproduce)
