"""ebpfcat 1.0.0: a segmented upload raises TypeError after the first segment
(known_bugs.py)."""
import asyncio

from harness import main


def reproduce(iface):
    from ebpfcat.ethercat import EtherCat, MachineState, Terminal

    async def run():
        ec = EtherCat(iface)
        await ec.connect()
        t = Terminal(ec)
        await t.initialize(0, 0x1001)
        await t.to_operational(MachineState.PRE_OPERATIONAL)
        try:
            data = await t.sdo_read(0x2000)  # complete access, 227 bytes from subindex 1
        except TypeError as e:
            print(f"ebpfcat: TypeError: {e}")
            return True
        print(f"read {len(data)} bytes")
        return False

    return asyncio.run(run())


main(reproduce)
