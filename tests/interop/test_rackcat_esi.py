"""[esi] One source for the SII, the ESI and the object dictionary, checked on the wire: the
EEPROM bytes SOEM reads from the running slave (pysoem eeprom_read over veth) equal `rackcat
sii -o FILE` byte for byte, and the ESI file describes the identity, mailbox and process-data
SyncManagers the master finds, for the default rack and for a rack file.
"""
import json
import struct
import time
import xml.etree.ElementTree as ET

import pytest

from rackcat_helpers import (check_capture, go, open_master, pysoem, rackcat, rackcat_tool,
                             sii_image, to_op)

assert rackcat  # the fixture, imported for pytest

TINY_RACK = """\
control_module:
  part_number: FI-CM0100-00
  serial_number: FI-CM0100-00-0042
  product_code: 0x00464E02
  revision: 0x00020001
  serial: 42
rims:
  - rim: 1
    type: 6-slot
    slots:
      - {slot: 1, card: CDO-10}
      - {slot: 2, card: CDI-10, loopback: {rim: 1, slot: 1}}
      - {slot: 4, card: CAI-11}
"""


def esi_hex(text):
    assert text.startswith("#x"), text
    return int(text[2:], 16)


@pytest.mark.parametrize("rack", ["default", "tiny"])
def test_sii_on_the_wire_equals_rackcat_sii_and_esi(rackcat, tmp_path, rack):
    config = None
    if rack == "tiny":
        config = tmp_path / "tiny-rack.yaml"
        config.write_text(TINY_RACK)
    image = sii_image(tmp_path, config)
    # ETG.2010: word 0x3E = EEPROM size in KiBit - 1; the image is the whole EEPROM.
    size_kbit = struct.unpack_from("<H", image, 0x3E * 2)[0] + 1
    assert len(image) == size_kbit * 1024 // 8
    vendor, product, revision, serial = struct.unpack_from("<IIII", image, 0x08 * 2)
    if rack == "tiny":
        assert (product, revision, serial) == (0x00464E02, 0x00020001, 42)

    esi_file = tmp_path / "rack.xml"
    rackcat_tool("esi", "-o", esi_file, *(["--config", config] if config else []))
    esi = ET.parse(esi_file).getroot()
    device = esi.find("./Descriptions/Devices/Device")
    dtype = device.find("Type")
    assert esi_hex(esi.find("./Vendor/Id").text) == vendor
    assert (esi_hex(dtype.get("ProductCode")), esi_hex(dtype.get("RevisionNo"))) == \
        (product, revision)
    # Eeprom ConfigData = SII words 0..7; ByteSize = the image size.
    assert bytes.fromhex(device.find("./Eeprom/ConfigData").text) == image[:16]
    assert int(device.find("./Eeprom/ByteSize").text) == len(image)
    sms = device.findall("Sm")

    rc = rackcat(config=config)
    master = open_master(rc.iface, 1)
    try:
        s = master.slaves[0]
        # Every SII word as SOEM reads it (4 bytes per read), byte for byte.
        read = b"".join(s.eeprom_read(w, 20_000) for w in range(0, len(image) // 2, 2))
        assert len(read) == len(image)
        diff = [i for i in range(len(image)) if read[i] != image[i]]
        assert diff == [], f"{len(diff)} bytes differ, first at 0x{diff[0]:04X}"
        # SII identity = 0x1018 = ESI Type.
        assert (s.man, s.id, s.rev) == (vendor, product, revision)
        assert struct.unpack("<IIII", s.sdo_read(0x1018, 0, ca=True)[2:]) == \
            (vendor, product, revision, serial)
        # SII standard mailbox (words 0x18..0x1B) = ESI Sm 0/1.
        rx_off, rx_size, tx_off, tx_size = struct.unpack_from("<HHHH", image, 0x18 * 2)
        assert (esi_hex(sms[0].get("StartAddress")), int(sms[0].get("DefaultSize"))) == \
            (rx_off, rx_size)
        assert (esi_hex(sms[1].get("StartAddress")), int(sms[1].get("DefaultSize"))) == \
            (tx_off, tx_size)
        # ESI Sm 2/3 default sizes = the process image SOEM maps from the default PDO
        # assignment, and the ESM accepts that mapping (SAFEOP, OP).
        master.config_map()
        assert (len(s.output), len(s.input)) == (int(sms[2].get("DefaultSize")),
                                                 int(sms[3].get("DefaultSize")))
        to_op(master)
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()
    check_capture(rc.pcap)


# SOEM keeps object and entry names in EC_MAXNAME = 40 characters.
SOEM_MAXNAME = 40
OBJECT_CODES = {7: "VAR", 8: "ARRAY", 9: "RECORD"}


def test_sdo_information_on_the_wire_equals_rackcat_od(rackcat):
    """What a master learns through SDO Information (object list, object and entry
    descriptions; SOEM's ecx_readODlist/ODdescription/OE as pysoem's slave.od) equals the
    dictionary `rackcat od --format json` prints: the same objects, names, object codes, data
    types, bit lengths and access bits, for every subindex up to the object's highest."""
    reference = json.loads(rackcat_tool("od", "--format", "json").stdout)["objects"]
    expected = {int(o["index"], 16): o for o in reference}
    rc = rackcat(extra=["--no-pty"])
    master = open_master(rc.iface, 1)
    problems = []
    try:
        od = master.slaves[0].od
        assert sorted(o.index for o in od) == sorted(expected), "object list (list type 1)"
        for o in od:
            ref = expected[o.index]
            name = o.name.decode(errors="replace")
            if (name, OBJECT_CODES.get(o.object_code)) != (ref["name"][:SOEM_MAXNAME],
                                                           ref["object_code"]):
                problems.append(f"0x{o.index:04X}: {name!r} {o.object_code} vs "
                                f"{ref['name']!r} {ref['object_code']}")
            if ref["object_code"] == "VAR":
                e = ref["entries"][0]
                if (o.data_type, o.bit_length) != (e["data_type"], e["bit_size"]):
                    problems.append(f"0x{o.index:04X}: type {o.data_type}/{o.bit_length} vs "
                                    f"{e['data_type']}/{e['bit_size']}")
                continue
            try:
                entries = o.entries
            except pysoem.SdoInfoError as err:
                problems.append(f"0x{o.index:04X}: entry descriptions failed ({err}); "
                                f"highest subindex {ref['entries'][-1]['subindex']}")
                continue
            for e in ref["entries"]:
                k = e["subindex"]
                want = (e["name"][:SOEM_MAXNAME], e["data_type"], e["bit_size"],
                        e["access_bits"])
                got = entries[k] if k < len(entries) else None
                got = got and (got.name.decode(errors="replace"), got.data_type,
                               got.bit_length, got.obj_access)
                if e["padding"] and got == ("", 0, 0, 0):
                    continue  # a gap inside the object: no description, as SOEM skips it
                if got != want:
                    problems.append(f"0x{o.index:04X}:{k:02X}: {got} vs {want}")
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()
    # Wireshark decodes the fragmented SDO Information answers.
    check_capture(rc.pcap)
    assert problems == [], f"{len(problems)} differences:\n" + "\n".join(problems[:20])


def raw_mailbox(slave, request, timeout_s=2.0):
    """One mailbox exchange written with the master's own FPWR/FPRD primitives (pysoem has no
    SDO Information call with value info): the request into SM0 (the whole SM, so its last byte
    hands it over), then SM1 once its status says full (ETG.1000.4 §6.7.2 register 0x0805+8n)."""
    sm0_start, sm0_len = struct.unpack("<HH", slave._fprd(0x0800, 4))
    sm1_start, sm1_len = struct.unpack("<HH", slave._fprd(0x0808, 4))
    slave._fpwr(sm0_start, request.ljust(sm0_len, b"\0"))
    deadline = time.monotonic() + timeout_s
    while not slave._fprd(0x080D, 1)[0] & 0x08:
        assert time.monotonic() < deadline, "no mailbox reply"
        time.sleep(0.002)
    reply = slave._fprd(sm1_start, sm1_len)
    length = struct.unpack_from("<H", reply, 0)[0]
    return reply[6:6 + length]


def test_units_in_esi_od_and_the_entry_description_layout(rackcat, tmp_path):
    """Issue 18 units: `rackcat esi` gives 0x2000:0F the ETG.1004 code for degree Celsius
    (0x002D0000) and declares notation index 0x2D in UnitTypes, `rackcat od` says the same, and an
    SDO Information entry description with value info 0x08 (ETG.1000.6 §5.6.3.6) carries the
    UNSIGNED16 unit type between the access word and the name, read by pysoem over veth. The
    16-bit value is 0: what it holds for a 32-bit ETG.1004 code is not in our references
    (docs/MDP.md "Units")."""
    esi_file = tmp_path / "rack.xml"
    rackcat_tool("esi", "-o", esi_file)
    device = ET.parse(esi_file).getroot().find("./Descriptions/Devices/Device")
    dictionary = device.find("./Profile/Dictionary")
    temp = [s for o in dictionary.findall("./Objects/Object") if o.findtext("Index") == "#x2000"
            for s in o.findall("./Info/SubItem") if s.findtext("Name") == "Temperature (CPU Zone)"]
    assert [s.findtext("./Info/Unit") for s in temp] == ["#x002D0000"]
    symbols = {ut.findtext("NotationIndex"): ut.findtext("Symbol")
               for ut in dictionary.findall("./UnitTypes/UnitType")}
    assert symbols.get("#x2D") == "\u00b0C", symbols
    od = json.loads(rackcat_tool("od", "--format", "json").stdout)["objects"]
    info = next(o for o in od if o["index"] == "0x2000")
    assert next(e for e in info["entries"] if e["subindex"] == 0x0F)["unit"] == "0x002D0000"

    rc = rackcat(extra=["--no-pty"])
    master = open_master(rc.iface, 1)
    try:
        s = master.slaves[0]
        # Mailbox header (length 10, address 0, priority 0, type 3 CoE, counter 5), CoE header
        # service 8 (SDO Information), Get Entry Description request 0x2000:0F value info 0x08.
        request = struct.pack("<HHBB", 10, 0, 0, 0x53) + bytes([0x00, 0x80, 0x05, 0x00, 0x00,
                                                                  0x00, 0x00, 0x20, 0x0F, 0x08])
        reply = raw_mailbox(s, request)
        name = b"Temperature (CPU Zone)"
        assert reply[:2] == b"\x00\x80" and reply[2] == 0x06, reply.hex()  # entry description
        # index, subindex, value info, REAL32, 32 bits, ro + TxPDO, unit type 0, the name.
        assert reply[6:] == bytes([0x00, 0x20, 0x0F, 0x08, 0x08, 0x00, 0x20, 0x00, 0x87, 0x00,
                                   0x00, 0x00]) + name, reply.hex()
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()
    check_capture(rc.pcap)
