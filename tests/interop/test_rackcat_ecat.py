"""[ecat] A real master (pysoem, bundling SOEM) drives the real device, `rackcat run` on the
built-in default rack, over a veth pair: scan, identity, SDO (expedited, complete access,
aborts), PDO mapping, distributed clocks, OP, cyclic process data through the rack's
loopback wiring, a 16-slave segment, back to INIT, and a capture that Wireshark decodes.
"""
import os
import struct
import time

from rackcat_helpers import (CYCLE_S, DI_LOOPBACK_MODULE, DO_MODULE, abort_code,
                             check_capture, cycle, get_bits, go, open_master, pysoem, rackcat,
                             rack_with_master, read_pdo_map, set_bits, sii_image, to_op)

assert rackcat  # the fixture, imported for pytest

CYCLES_1 = int(os.environ.get("RACKCAT_INTEROP_CYCLES", "10000"))
CYCLES_16 = int(os.environ.get("RACKCAT_INTEROP_CYCLES_16", "2000"))

# Identity of the default rack (examples/default-rack.yaml control_module).
VENDOR, PRODUCT, REVISION, SERIAL = 0x00000000, 0x00464E01, 0x00010009, 1
# Modules of the default rack with outputs / inputs (docs/MDP.md card catalogue), in module
# order: the default 0x1C12/0x1C13 assign their mapping objects 0x1600/0x1A00 + n - 1.
OUTPUT_MODULES = [1, 3, 4, 5, 6, 8, 9, 11, 13, 26]
INPUT_MODULES = [2, 3, 4, 7, 10, 12, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 27]


def assign_bytes(base, modules):
    """Complete-access image of a PDO assignment object: subindex 0 in 16 bits (value + 8
    padding bits, ETG.1000.6 §5.6.2.1.2), then one UINT per assigned PDO."""
    return struct.pack("<BB", len(modules), 0) + b"".join(
        struct.pack("<H", base + n - 1) for n in modules)


def test_identity_sdo_complete_access_and_aborts(rackcat, tmp_path):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        assert s.state == pysoem.PREOP_STATE
        # The identity SOEM read from the SII equals 0x1018 read over SDO and the rack file.
        sdo_identity = tuple(struct.unpack("<I", s.sdo_read(0x1018, k))[0] for k in (1, 2, 3))
        assert (s.man, s.id, s.rev) == sdo_identity == (VENDOR, PRODUCT, REVISION)
        image = sii_image(tmp_path)
        assert struct.unpack_from("<IIII", image, 0x08 * 2) == (VENDOR, PRODUCT, REVISION,
                                                                 SERIAL)
        assert struct.unpack("<I", s.sdo_read(0x1018, 4))[0] == SERIAL

        # Expedited write then read back (0x2000:09 Event Mask, rw, UDINT), then restore.
        old = s.sdo_read(0x2000, 9)
        s.sdo_write(0x2000, 9, struct.pack("<I", 0x0000FF0F))
        assert s.sdo_read(0x2000, 9) == struct.pack("<I", 0x0000FF0F)
        s.sdo_write(0x2000, 9, old)
        assert s.sdo_read(0x2000, 9) == old
        # A segmented upload: the 64-character part number string.
        assert s.sdo_read(0x2000, 1).rstrip(b"\0") == b"FI-CM0100-00"

        # Complete access reads with golden bytes from the rack file and ETG.1000.6.
        assert s.sdo_read(0x1C12, 0, 1024, ca=True) == assign_bytes(0x1600, OUTPUT_MODULES)
        assert s.sdo_read(0x1C13, 0, 1024, ca=True) == assign_bytes(0x1A00, INPUT_MODULES)
        assert s.sdo_read(0x1018, 0, ca=True) == struct.pack("<BBIIII", 4, 0, VENDOR, PRODUCT,
                                                             REVISION, SERIAL)

        # Aborts arrive as pysoem.SdoError with the ETG.1000.6 Table 41 code.
        assert abort_code(s.sdo_read, 0x1234, 0) == 0x06020000  # object does not exist
        assert abort_code(s.sdo_write, 0x1018, 1, b"\x01\0\0\0") == 0x06010002  # read only
        assert abort_code(s.sdo_read, 0x1018, 9) == 0x06090011  # subindex does not exist
        # The server is still answering normally after the aborts.
        assert struct.unpack("<I", s.sdo_read(0x1018, 2))[0] == PRODUCT
        go(master, pysoem.INIT_STATE)
    check_capture(rc.pcap)


def assign(slave, index, pdos):
    """PDO assignment the way masters write it in PREOP (ETG.1000.6 §5.6.7.4): subindex 0 to
    0, the entries, then subindex 0 to the count."""
    slave.sdo_write(index, 0, b"\0")
    for k, pdo in enumerate(pdos, start=1):
        slave.sdo_write(index, k, struct.pack("<H", pdo))
    slave.sdo_write(index, 0, bytes([len(pdos)]))


def _cyclic(rc, slaves, cycles, reduced_map=False):
    master = open_master(rc.iface, slaves)
    try:
        if reduced_map:
            # pysoem's process image is EC_IOMAPSIZE = 4096 bytes: 16 default racks (608
            # bytes each) do not fit. The master assigns only the loopback pair and the
            # analog input card, as a real application selects the PDOs it uses.
            for s in master.slaves:
                assign(s, 0x1C12, [0x1600 + DO_MODULE - 1])
                assign(s, 0x1C13, [0x1A00 + DI_LOOPBACK_MODULE - 1, 0x1A00 + 14 - 1])
        pdo = read_pdo_map(master.slaves[0])  # every slave runs the same default rack
        do = pdo.find(0x7000 + (DO_MODULE - 1) * 0x10, 1, "out")
        di = pdo.find(0x6000 + (DI_LOOPBACK_MODULE - 1) * 0x10, 1, "in")
        ai = pdo.find(0x6000 + (14 - 1) * 0x10 + 3, 3, "in")
        assert (do.bits, di.bits, ai.bits) == (16, 16, 16)
        master.config_map()
        for i, s in enumerate(master.slaves):
            assert len(s.output) * 8 == pdo.output_bits, f"slave {i} output size"
            assert len(s.input) * 8 == pdo.input_bits, f"slave {i} input size"
        assert master.config_dc(), "the slaves report no distributed clock"
        for s in master.slaves:
            s.dc_sync(True, 1_000_000)  # SYNC0 every 1 ms
        to_op(master)
        expected = master.expected_wkc
        assert expected == 3 * slaves  # LRW: outputs (+1) and inputs (+2) on every slave

        # Output patterns change every BLOCK cycles; each slave gets its own pattern. The
        # loopback-wired input must show the previous or the current pattern in every cycle
        # (never anything else) and the current one by the end of each block.
        block = 20
        bad_wkc, bad_data, stale = [], [], []
        previous = [None] * slaves
        next_t = time.monotonic()
        for c in range(cycles):
            next_t += CYCLE_S  # paced at the SYNC0 period, as a master's cyclic task
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            pattern = [((c // block) * 0x3B1D + i * 0x0101) & 0xFFFF for i in range(slaves)]
            for i, s in enumerate(master.slaves):
                s.output = set_bits(s.output, do, pattern[i])
            wkc = cycle(master)
            if wkc != expected:
                bad_wkc.append((c, wkc))
                continue
            for i, s in enumerate(master.slaves):
                got = get_bits(s.input, di)
                if got not in (pattern[i], previous[i]) and c >= block:
                    bad_data.append((c, i, hex(got), hex(pattern[i])))
                if c % block == block - 1 and got != pattern[i]:
                    stale.append((c, i, hex(got), hex(pattern[i])))
            if c % block == block - 1:
                previous = pattern
        # The slave's application (slot card driver) holds what the master wrote last.
        module = rc.cli_while_cycling(master, "list", "--module", DO_MODULE, "--json")
        commanded = sum(int(o["commanded"]) << o["channel"] for o in module["outputs"])
        assert bad_wkc == [], f"{len(bad_wkc)} cycles with WKC != {expected}: {bad_wkc[:10]}"
        assert bad_data == [], f"{len(bad_data)} wrong loopback inputs: {bad_data[:10]}"
        assert stale == [], f"{len(stale)} blocks whose outputs never came back: {stale[:10]}"
        assert commanded == pattern[0], (hex(commanded), hex(pattern[0]), module["outputs"])
        # Inputs generated by the slave reach the master: RIM 1 slot 14 (module 14, CAI-15)
        # channel 2 has a constant 2.5 V source in the rack file; code = round(2.5 * 32767 /
        # 10) = 8192 (docs/MODULES.md analog scaling).
        for i, s in enumerate(master.slaves):
            assert get_bits(s.input, ai) == 8192, f"slave {i}: AI code {get_bits(s.input, ai)}"
        master.read_state()
        for i, s in enumerate(master.slaves):
            assert s.state == pysoem.OP_STATE, f"slave {i} left OP: {hex(s.state)}"
            assert s.al_status == 0, f"slave {i} AL status {hex(s.al_status)}"
        go(master, pysoem.SAFEOP_STATE)
        go(master, pysoem.PREOP_STATE)
        go(master, pysoem.INIT_STATE)
        for i, s in enumerate(master.slaves):
            assert s.al_status == 0, f"slave {i} AL status {hex(s.al_status)} in INIT"
    finally:
        master.close()
    rc.stop()
    check_capture(rc.pcap)


def test_op_with_dc_and_loopback_1_slave(rackcat):
    _cyclic(rackcat(slaves=1), 1, CYCLES_1)


def test_op_with_dc_and_loopback_through_lan9252_access(rackcat):
    # The same firmware reaching its ESC through the LAN9252 host-bus protocol (CSR command /
    # data registers, process RAM through the PRAM FIFOs) instead of the chip model's PDI.
    _cyclic(rackcat(slaves=1, extra=["--pdi", "lan9252-emulated"]), 1, CYCLES_16)


def test_op_with_dc_and_loopback_16_slaves(rackcat):
    _cyclic(rackcat(slaves=16, extra=["--no-pty"]), 16, CYCLES_16, reduced_map=True)
