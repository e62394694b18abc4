"""ebpfcat 1.0.0: a normal SDO download carries complete size 0 (known_bugs.py)."""
import asyncio

from harness import main


def reproduce(iface):
    from ebpfcat.ethercat import EtherCat, EtherCatError, MachineState, Terminal

    async def run():
        ec = EtherCat(iface)
        await ec.connect()
        t = Terminal(ec)
        await t.initialize(0, 0x1001)
        await t.to_operational(MachineState.PRE_OPERATIONAL)
        try:
            await t.sdo_write(b"10.20.30.40\0\0\0\0\0", 0x2000, 4)
        except EtherCatError as e:
            print(f"ebpfcat: {e} (its request says complete size 0)")
            return True
        return False

    return asyncio.run(run())


main(reproduce)
