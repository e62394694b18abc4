"""[line] A user's own line over veth under pysoem: coupler + 8-ch DI + 8-ch DO + CoE analog
terminal (all from tests/device/data/rackcat-test-devices.xml, written for these tests) + a
Fusion.IO rack, from one line file (`rackcat run --line`). The identities and names SOEM reads
equal the ESI's, config_map gives the sizes the ESI implies, the line reaches OP, a DO->DI
loopback wired in the line file is seen in the process image, and the SDO information of the
CoE terminal lists the ESI dictionary's objects."""
import shlex
import shutil
import time
import xml.etree.ElementTree as ET

import pytest

from conftest import BUILD, REPO

pysoem = pytest.importorskip("pysoem", reason="pysoem not installed (scripts/setup.sh)")

DATA = REPO / "tests/device/data"
LINE = """\
devices:
  - {esi: rackcat-test-devices.xml, device: RC1100, alias: 0x100}
  - {esi: rackcat-test-devices.xml, device: RC1008, name: di}
  - {esi: rackcat-test-devices.xml, device: RC2008, name: do}
  - {esi: rackcat-test-devices.xml, product_code: 0x3102, name: ai}
  - {rack: tiny-rack.yaml}
wiring:
  - {from: do, to: di, bits: 8}
"""


def esi_devices():
    root = ET.parse(DATA / "rackcat-test-devices.xml").getroot()
    out = {}
    for d in root.findall("./Descriptions/Devices/Device"):
        t = d.find("Type")
        out[t.text] = (int(t.get("ProductCode")[2:], 16), int(t.get("RevisionNo")[2:], 16),
                       d.find("Name").text, d)
    return out


def cycle(master, n=1):
    wkc = 0
    for _ in range(n):
        master.send_processdata()
        wkc = master.receive_processdata(2000)
    return wkc


def test_line_reaches_op_with_esi_identities_and_loopback(ecat_segment, tmp_path):
    work = tmp_path / "line"
    work.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", work)
    shutil.copy(REPO / "examples/tiny-rack.yaml", work)
    (work / "line.yaml").write_text(LINE)
    q = shlex.quote  # the template is split like a shell line; paths may hold spaces
    cmd = (f"{q(str(BUILD / 'rackcat'))} run --iface {{iface}} --line {q(str(work / 'line.yaml'))} "
           f"--no-control --no-pty --state-dir {q(str(tmp_path / 'state'))}")
    iface, slave = ecat_segment(slaves=5, cmd=cmd, pcap=False)
    esi = esi_devices()
    master = pysoem.Master()
    master.open(iface)
    try:
        assert master.config_init() == 5
        s = master.slaves
        for pos, order in enumerate(["RC1100", "RC1008", "RC2008", "RC3102"]):
            code, rev, name, _ = esi[order]
            assert (s[pos].man, s[pos].id, s[pos].rev) == (0x0E1C, code, rev), pos
            assert s[pos].name == name, (pos, s[pos].name)
        # CoE terminal: SDO information lists every object the ESI dictionary declares.
        ai = s[3]
        od_indices = {obj.index for obj in ai.od}
        declared = {int(o.find("Index").text[2:], 16)
                    for o in esi["RC3102"][3].findall("./Profile/Dictionary/Objects/Object")}
        assert declared <= od_indices, (declared, od_indices)
        names = {obj.index: obj.name for obj in ai.od}
        assert names[0x8000] == b"AI Filter"
        assert int.from_bytes(ai.sdo_read(0x1C13, 1), "little") == 0x1A00
        master.config_map()
        sizes = [(len(x.output), len(x.input)) for x in s[:4]]
        assert sizes == [(0, 0), (0, 1), (1, 0), (0, 8)], sizes
        master.state = pysoem.SAFEOP_STATE
        master.write_state()
        assert master.state_check(pysoem.SAFEOP_STATE, 3_000_000) == pysoem.SAFEOP_STATE, \
            [(x.name, hex(x.state), hex(x.al_status)) for x in s]
        cycle(master)
        master.state = pysoem.OP_STATE
        master.write_state()
        deadline = time.monotonic() + 10
        while master.state_check(pysoem.OP_STATE, 1000) != pysoem.OP_STATE:
            cycle(master)
            assert time.monotonic() < deadline, \
                [(x.name, hex(x.state), hex(x.al_status)) for x in s]
        # DO -> DI loopback across devices (line file wiring).
        for pattern in (0xA5, 0x3C, 0x00):
            s[2].output = bytes([pattern])
            seen = None
            for _ in range(50):
                cycle(master)
                seen = s[1].input[0]
                if seen == pattern:
                    break
                time.sleep(0.002)
            assert seen == pattern, f"DI shows {seen:#x}, DO wrote {pattern:#x}"
        master.state = pysoem.INIT_STATE
        master.write_state()
    finally:
        master.close()
    assert slave.stop() == 0, slave.log()
