"""The process image layout as a master computes it from the slave's dictionary over SDO, and
bit access into pysoem's input/output images. No pytest here: the CAN VM test
(tests/can_vm/ecat_over_can.py) runs it without pytest inside the VM."""
import struct
from dataclasses import dataclass, field


def sdo_u(slave, index, sub, fmt):
    return struct.unpack(fmt, slave.sdo_read(index, sub))[0]


@dataclass
class PdoEntry:
    index: int
    sub: int
    bits: int
    bit_offset: int  # from the start of the slave's output (RxPDO) or input (TxPDO) image


@dataclass
class PdoMap:
    outputs: list = field(default_factory=list)
    inputs: list = field(default_factory=list)
    output_bits: int = 0
    input_bits: int = 0

    def find(self, index, sub, direction):
        for e in self.outputs if direction == "out" else self.inputs:
            if (e.index, e.sub) == (index, sub):
                return e
        raise AssertionError(f"0x{index:04X}:{sub:02X} not mapped ({direction})")


def read_pdo_map(slave):
    """The process image layout as a master computes it: 0x1C12/0x1C13 assignments, then each
    PDO's entries in order (ETG.1000.6 §5.6.7.4), over SDO."""
    pm = PdoMap()
    for assign, entries, attr in ((0x1C12, pm.outputs, "output_bits"),
                                  (0x1C13, pm.inputs, "input_bits")):
        bit = 0
        for k in range(1, sdo_u(slave, assign, 0, "<B") + 1):
            pdo = sdo_u(slave, assign, k, "<H")
            for e in range(1, sdo_u(slave, pdo, 0, "<B") + 1):
                m = sdo_u(slave, pdo, e, "<I")
                entries.append(PdoEntry(m >> 16, (m >> 8) & 0xFF, m & 0xFF, bit))
                bit += m & 0xFF
        setattr(pm, attr, bit)
    return pm


def get_bits(image, entry):
    value = int.from_bytes(bytes(image), "little")
    return (value >> entry.bit_offset) & ((1 << entry.bits) - 1)


def set_bits(image, entry, v):
    value = int.from_bytes(bytes(image), "little")
    mask = ((1 << entry.bits) - 1) << entry.bit_offset
    value = (value & ~mask) | ((v << entry.bit_offset) & mask)
    return value.to_bytes(len(image), "little")
