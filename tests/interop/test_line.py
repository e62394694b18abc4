"""A user's own line over veth under pysoem: coupler + 8-ch DI + 8-ch DO + CoE analog
terminal (all from tests/device/data/rackcat-test-devices.xml, written for these tests) + a
Fusion.IO rack, from one line file (`rackcat run --line`). The identities and names SOEM reads
equal the ESI's, config_map gives the sizes the ESI implies, the line reaches OP, a DO->DI
loopback wired in the line file is seen in the process image, and the SDO information of the
CoE terminal lists the ESI dictionary's objects."""
import concurrent.futures
import json
import shlex
import shutil
import struct
import subprocess
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


def assert_esi_identities(slaves, esi):
    """Positions 0-3 of the line (LINE, and the ENI of it) are the ESI devices: identity and
    name as their ESI says."""
    for pos, order in enumerate(["RC1100", "RC1008", "RC2008", "RC3102"]):
        code, rev, name, _ = esi[order]
        assert (slaves[pos].man, slaves[pos].id, slaves[pos].rev) == (0x0E1C, code, rev), pos
        assert slaves[pos].name == name, (pos, slaves[pos].name)


def open_line(ecat_segment, tmp_path, line_args, slaves):
    """`rackcat run` with `line_args` (--line FILE, or --eni FILE --esi-dir DIR) on a fresh
    segment, and pysoem opened on it, which has found the line's `slaves` slaves. Returns
    (master, slave process)."""
    q = shlex.quote  # the template is split like a shell line; paths may hold spaces
    cmd = (f"{q(str(BUILD / 'rackcat'))} run --iface {{iface}} {line_args} --no-control "
           f"--no-pty --state-dir {q(str(tmp_path / 'state'))}")
    iface, slave = ecat_segment(slaves=slaves, cmd=cmd, pcap=False)
    master = pysoem.Master()
    master.open(iface)
    try:
        assert master.config_init() == slaves
    except BaseException:
        master.close()
        raise
    return master, slave


def cycle(master, n=1):
    wkc = 0
    for _ in range(n):
        master.send_processdata()
        wkc = master.receive_processdata(2000)
    return wkc


def to_op(master):
    """SAFEOP, one cycle, then OP while cycling (10 s at most); every slave's state and AL
    status in the message when a step fails."""
    def where():
        return [(x.name, hex(x.state), hex(x.al_status)) for x in master.slaves]

    master.state = pysoem.SAFEOP_STATE
    master.write_state()
    assert master.state_check(pysoem.SAFEOP_STATE, 3_000_000) == pysoem.SAFEOP_STATE, where()
    cycle(master)
    master.state = pysoem.OP_STATE
    master.write_state()
    deadline = time.monotonic() + 10
    while master.state_check(pysoem.OP_STATE, 1000) != pysoem.OP_STATE:
        cycle(master)
        assert time.monotonic() < deadline, where()


def test_line_reaches_op_with_esi_identities_and_loopback(ecat_segment, tmp_path):
    work = tmp_path / "line"
    work.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", work)
    shutil.copy(REPO / "examples/tiny-rack.yaml", work)
    (work / "line.yaml").write_text(LINE)
    master, slave = open_line(ecat_segment, tmp_path,
                              f"--line {shlex.quote(str(work / 'line.yaml'))}", 5)
    esi = esi_devices()
    try:
        s = master.slaves
        assert_esi_identities(s, esi)
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
        to_op(master)
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


SOURCES_LINE = """\
devices:
  - esi: rackcat-test-devices.xml
    product_code: 0x3102
    name: ai
    inputs:
      - {bit: 16, bits: 16, source: ramp, from: 0, to: 30000, period_s: 1}
  - esi: rackcat-test-devices.xml
    device: RC1008
    inputs:
      - {bits: 8, source: constant, value: 165, signed: false}
  - esi: rackcat-test-devices.xml
    device: RC5001
    modules: [RM-DI4, RM-DO4]
    inputs:
      - {bits: 4, source: constant, value: 9, signed: false}
  - esi: rackcat-test-devices.xml
    device: RC5002
    modules: [RM-DI4, RM-DO4]
"""


def test_signal_sources_and_a_modular_device_with_its_modules(ecat_segment, tmp_path):
    """Signal sources of the line file drive ESI devices' inputs (a ramp on the analog
    terminal's channel 1 value, a constant on the DI), and the ETG.5001 device RC5001 runs with
    the modules the line file chose (RM-DI4 in slot 1, RM-DO4 in slot 2): pysoem maps 1 byte
    each way, reads 0xF030/0xF050 and the module objects at their slot indices, reaches OP and
    sees the sources in the process image."""
    work = tmp_path / "line"
    work.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", work)
    (work / "line.yaml").write_text(SOURCES_LINE)
    master, slave = open_line(ecat_segment, tmp_path,
                              f"--line {shlex.quote(str(work / 'line.yaml'))}", 4)
    try:
        s = master.slaves
        # RC5002 (slot groups, ModuleClass): RM-DI4 in group 0, RM-DO4 in group 1 at
        # 0x7000 + 1 x 0x100 with its PDO 0x1600 + 1 x 0x20; its device-level lists follow.
        grp = s[3]
        u32 = lambda index, sub: int.from_bytes(grp.sdo_read(index, sub), "little")
        for index, want in ((0xF030, [1, 2]), (0xF050, [1, 2]), (0x3000, [1, 2]),
                            (0xF010, [1101, 1102]), (0x1C12, [0x1620]), (0x1C13, [0x1A00])):
            assert grp.sdo_read(index, 0)[0] == len(want), hex(index)
            assert [u32(index, k + 1) for k in range(len(want))] == want, hex(index)
        assert u32(0x1620, 1) == 0x71000101 and u32(0x1A00, 1) == 0x60000101
        od = {obj.index: obj.name for obj in grp.od}
        assert od[0x7100] == b"DO4 outputs" and 0x7000 not in od, od
        mod = s[2]
        assert mod.id == 0x5001
        for index in (0xF030, 0xF050):
            assert mod.sdo_read(index, 0)[0] == 2
            assert int.from_bytes(mod.sdo_read(index, 1), "little") == 1  # RM-DI4
            assert int.from_bytes(mod.sdo_read(index, 2), "little") == 2  # RM-DO4
        od = {obj.index: obj.name for obj in mod.od}
        assert od[0x6000] == b"DI4 inputs" and od[0x7010] == b"DO4 outputs", od
        assert 0x7000 not in od and 0x6010 not in od
        master.config_map()
        sizes = [(len(x.output), len(x.input)) for x in s]
        assert sizes == [(0, 8), (0, 1), (1, 1), (1, 1)], sizes
        to_op(master)
        values = set()
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline and len(values) < 5:
            cycle(master)
            values.add(int.from_bytes(s[0].input[2:4], "little", signed=True))
            assert s[1].input[0] == 165
            assert s[2].input[0] & 0x0F == 9
            time.sleep(0.01)
        assert len(values) >= 5 and all(0 <= v <= 30000 for v in values), values
        master.state = pysoem.INIT_STATE
        master.write_state()
    finally:
        master.close()
    assert slave.stop() == 0, slave.log()


def test_eni_builds_the_same_line(ecat_segment, tmp_path):
    """The hand-written ENI of this line (tests/apps/data/test-line.eni.xml), with the ESI and
    the rack file looked up by identity in --esi-dir, gives the same slaves: identities, names,
    config_map sizes, OP."""
    esi_dir = tmp_path / "esi"
    esi_dir.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", esi_dir)
    shutil.copy(REPO / "examples/tiny-rack.yaml", esi_dir)
    eni = REPO / "tests/apps/data/test-line.eni.xml"
    q = shlex.quote
    master, slave = open_line(ecat_segment, tmp_path,
                              f"--eni {q(str(eni))} --esi-dir {q(str(esi_dir))}", 5)
    try:
        s = master.slaves
        assert_esi_identities(s, esi_devices())
        assert (s[4].id, s[4].rev) == (0x00464E01, 0x00010009)
        master.config_map()
        sizes = [(len(x.output), len(x.input)) for x in s[:4]]
        assert sizes == [(0, 0), (0, 1), (1, 0), (0, 8)], sizes
        to_op(master)
        master.state = pysoem.INIT_STATE
        master.write_state()
    finally:
        master.close()
    assert slave.stop() == 0, slave.log()


def test_check_validates_line_and_eni_like_run(tmp_path):
    """`rackcat check --line` / `--eni` use run's loading: a good file lists its slaves (exit
    0), a bad one is one FILE:LINE line (exit 2) and run refuses it the same way before
    opening any interface."""
    work = tmp_path / "line"
    work.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", work)
    shutil.copy(REPO / "examples/tiny-rack.yaml", work)
    (work / "line.yaml").write_text(LINE)
    rackcat = str(BUILD / "rackcat")
    ok = subprocess.run([rackcat, "check", "--line", str(work / "line.yaml")],
                        capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert "ok, 5 slave(s)" in ok.stdout
    assert "wire: slave 2 outputs bits 0..7 -> slave 1 inputs bits 0..7" in ok.stdout
    eni = REPO / "tests/apps/data/test-line.eni.xml"
    ok = subprocess.run([rackcat, "check", "--eni", str(eni), "--esi-dir", str(work)],
                        capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert "slave 3: RC3102" in ok.stdout and "8 input byte(s)" in ok.stdout
    bad = LINE.replace("{from: do, to: di, bits: 8}", "{from: do, to: di, bits: 9}")
    (work / "line.yaml").write_text(bad)
    for args in (["check", "--line", str(work / "line.yaml")],
                 ["run", "--iface", "no-such-iface", "--line", str(work / "line.yaml")]):
        res = subprocess.run([rackcat, *args], capture_output=True, text=True, timeout=60)
        assert res.returncode == 2, res
        assert res.stderr.strip() == (f"{work / 'line.yaml'}:8: wire reads output bits 0..8 but "
                                      "the device has 8 output bits"), res.stderr
    # An ENI whose CoE init commands the device would refuse (TxPDO 0x1A05 assigned, which
    # RC3102 lacks): the SDO abort the master would meet, at that init command's line.
    text = eni.read_text()
    bad_eni = work / "bad.eni.xml"
    bad_eni.write_text(text.replace("<SubIndex>1</SubIndex><Data>001a</Data>",
                                    "<SubIndex>1</SubIndex><Data>051a</Data>"))
    line_no = text[:text.index("download pdo 0x1C13:01")].count("\n") + 1
    res = subprocess.run([rackcat, "check", "--eni", str(bad_eni), "--esi-dir", str(work)],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2, res
    assert res.stderr.strip() == (
        f"{bad_eni}:{line_no}: InitCmd writes 0x1C13:1 but RC3102 "
        f"({work / 'rackcat-test-devices.xml'}) answers SDO abort 0x06020000 (The object does "
        "not exist in the object dictionary)"), res.stderr


def test_every_device_of_the_line_is_reachable_through_the_control_api(ecat_segment, tmp_path):
    """`rackcat ctl --slave N` reaches every device of the line by its line position: a DO
    terminal's outputs read back what pysoem wrote, a DI terminal's and the CoE terminal's
    inputs set through the API show up in pysoem's process image, the rack keeps its own
    endpoints; the API still wants the bearer token."""
    work = tmp_path / "line"
    work.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", work)
    shutil.copy(REPO / "examples/tiny-rack.yaml", work)
    (work / "line.yaml").write_text(LINE.split("wiring:")[0])  # no loopback: inputs from ctl
    state = tmp_path / "state"
    q = shlex.quote
    cmd = (f"{q(str(BUILD / 'rackcat'))} run --iface {{iface}} --line {q(str(work / 'line.yaml'))} "
           f"--no-pty --control-port 8765 --state-dir {q(str(state))}")
    iface, slave = ecat_segment(slaves=5, cmd=cmd, pcap=False)

    def ctl(*args, expect=0):
        r = subprocess.run(slave.ns.exec_prefix() + [str(BUILD / "rackcat"), "ctl", "--json",
                                                     "--state-dir", str(state), *map(str, args)],
                           capture_output=True, text=True, timeout=20)
        assert r.returncode == expect, (args, r.returncode, r.stdout, r.stderr)
        return json.loads(r.stdout) if expect == 0 else r.stderr

    deadline = time.monotonic() + 10
    while not (state / "control-token").exists():
        assert time.monotonic() < deadline, slave.log()
        time.sleep(0.05)
    master = pysoem.Master()
    master.open(iface)
    try:
        assert master.config_init() == 5
        s = master.slaves
        master.config_map()
        master.state = pysoem.SAFEOP_STATE
        master.write_state()
        assert master.state_check(pysoem.SAFEOP_STATE, 3_000_000) == pysoem.SAFEOP_STATE
        cycle(master)
        master.state = pysoem.OP_STATE
        master.write_state()
        deadline = time.monotonic() + 10
        while master.state_check(pysoem.OP_STATE, 1000) != pysoem.OP_STATE:
            cycle(master)
            assert time.monotonic() < deadline

        def while_cycling(fn, *args, **kw):
            with concurrent.futures.ThreadPoolExecutor(1) as pool:
                future = pool.submit(fn, *args, **kw)
                while not future.done():
                    cycle(master)
                    time.sleep(0.002)
                return future.result()

        listing = while_cycling(ctl, "--slave", 0, "io")
        assert listing["device"] == "RC1100 'RC1100 EtherCAT coupler'", listing
        # DO terminal (slave 2): outputs read back.
        s[2].output = bytes([0x3C])
        cycle(master, 5)
        io = while_cycling(ctl, "--slave", 2, "io")
        assert (io["outputs"], io["output_bits"]) == ("3C", 8), io
        # DI terminal (slave 1): inputs set from outside reach the master.
        io = while_cycling(ctl, "--slave", 1, "set-inputs", "A5")
        assert io["inputs"] == "A5", io
        cycle(master, 5)
        assert s[1].input[0] == 0xA5
        # CoE analog terminal (slave 3): channel 2's value (input bits 48..63) = 0x1234.
        io = while_cycling(ctl, "--slave", 3, "set-inputs", "3412", "--bit", 48)
        cycle(master, 5)
        assert s[3].input[6:8] == bytes([0x34, 0x12]), s[3].input.hex()
        # Beyond the inputs, rack endpoints on an ESI device: one precise refusal each.
        err = while_cycling(ctl, "--slave", 1, "set-inputs", "FF", "--bit", 4, expect=2)
        assert "input bits 4..11 are beyond the 8 input bit(s) of slave 1" in err, err
        err = while_cycling(ctl, "--slave", 1, "esm", expect=2)
        assert "slave 1 is RC1008" in err and "GET /api/io" in err, err
        # The rack (slave 4) keeps its own endpoints.
        esm = while_cycling(ctl, "--slave", 4, "esm")
        assert esm, esm
        # Without the token: 401.
        r = while_cycling(subprocess.run, slave.ns.exec_prefix() + [
            "curl", "-s", "-o", "/dev/null", "-w", "%{http_code}",
            "http://127.0.0.1:8765/api/slaves/1/io"], capture_output=True, text=True, timeout=20)
        assert r.stdout == "401", r
        master.state = pysoem.INIT_STATE
        master.write_state()
    finally:
        master.close()
    assert slave.stop() == 0, slave.log()


FOE_PASSWORD = 0x52434657  # rackcat's default FoE password ("RCFW", docs/FOE.md)
FOE_TIMEOUT_US = 10_000_000  # per mailbox step; generous: the machine is shared


def test_foe_on_an_esi_device(ecat_segment, tmp_path):
    """ESI devices whose ESI says <Mailbox><FoE/> (RC5002 with CoE, RC6001 without) serve FoE
    from their own directory beneath the state directory (esi-<position>): pysoem's foe_write of
    a file over several
    mailbox packets, foe_read gives it back byte for byte, and it is on disk there; a wrong
    password, a bad name and a link planted in the directory are refused, and the link's target
    is never read."""
    work = tmp_path / "line"
    work.mkdir()
    shutil.copy(DATA / "rackcat-test-devices.xml", work)
    (work / "line.yaml").write_text(
        "devices:\n  - {esi: rackcat-test-devices.xml, device: RC5002, modules: [RM-DI4]}\n"
        "  - {esi: rackcat-test-devices.xml, device: RC6001}\n")
    state = tmp_path / "state"
    secret = tmp_path / "secret.txt"
    secret.write_bytes(b"not for the master")
    master, slave = open_line(ecat_segment, tmp_path,
                              f"--line {shlex.quote(str(work / 'line.yaml'))}", 2)
    try:
        # RC6001 has FoE and no CoE: its SII announces FoE only (word 0x1C bit 3).
        assert int.from_bytes(master.slaves[1].eeprom_read(0x1C)[:2], "little") == 0x0008
        for pos, dev in enumerate(master.slaves):
            data = bytes(range(256)) * 3 + bytes([pos])  # several packets, 128-byte mailboxes
            assert dev.foe_write("params.bin", FOE_PASSWORD, data, FOE_TIMEOUT_US) > 0, slave.log()
            assert dev.foe_read("params.bin", FOE_PASSWORD, 4096, FOE_TIMEOUT_US) == data
            assert (state / f"esi-{pos}" / "params.bin").read_bytes() == data
        dev = master.slaves[0]
        data = bytes(range(256)) * 3 + bytes([0])
        # Refusals: each an FoE error, nothing written.
        for name, password in (("other.bin", FOE_PASSWORD + 1), ("../escape", FOE_PASSWORD)):
            try:
                ok = dev.foe_write(name, password, b"x", FOE_TIMEOUT_US) > 0
            except (pysoem.WkcError, pysoem.MailboxError):
                ok = False
            assert not ok, name
        assert sorted(p.name for p in (state / "esi-0").iterdir()) == ["params.bin"]
        (state / "esi-0" / "link.bin").symlink_to(secret)
        try:
            got = dev.foe_read("link.bin", FOE_PASSWORD, 4096, FOE_TIMEOUT_US)
        except (pysoem.WkcError, pysoem.MailboxError):
            got = None
        assert got != secret.read_bytes()
        assert dev.foe_read("params.bin", FOE_PASSWORD, 4096, FOE_TIMEOUT_US) == data
        # RC6001 has a bootstrap mailbox (Eeprom/BootStrap): FoE in BOOT too, as SOEM's
        # firm_update does it (INIT, SM0/SM1 from SII words 0x14-0x17, BOOT, foe_write, INIT).
        boot = master.slaves[1]
        boot.state = pysoem.INIT_STATE
        boot.write_state()
        assert boot.state_check(pysoem.INIT_STATE, 3_000_000) == pysoem.INIT_STATE
        rx_off, rx_len = struct.unpack("<HH", boot.eeprom_read(pysoem.SiiOffset.BOOT_RX_MBX))
        tx_off, tx_len = struct.unpack("<HH", boot.eeprom_read(pysoem.SiiOffset.BOOT_TX_MBX))
        assert (rx_off, rx_len, tx_off, tx_len) == (0x1000, 256, 0x1200, 256)
        boot.amend_mbx(mailbox="out", start_address=rx_off, size=rx_len)
        boot.amend_mbx(mailbox="in", start_address=tx_off, size=tx_len)
        boot.state = pysoem.BOOT_STATE
        boot.write_state()
        assert boot.state_check(pysoem.BOOT_STATE, 3_000_000) == pysoem.BOOT_STATE, \
            f"AL status 0x{boot.al_status:04X}"
        image = bytes(range(251, -1, -1)) * 4  # 1008 bytes through 256-byte mailboxes
        assert boot.foe_write("image.bin", FOE_PASSWORD, image, FOE_TIMEOUT_US) > 0, slave.log()
        assert boot.foe_read("image.bin", FOE_PASSWORD, 4096, FOE_TIMEOUT_US) == image
        assert (state / "esi-1" / "image.bin").read_bytes() == image
        boot.state = pysoem.INIT_STATE
        boot.write_state()
        assert boot.state_check(pysoem.INIT_STATE, 3_000_000) == pysoem.INIT_STATE
    finally:
        master.close()
    assert slave.stop() == 0, slave.log()
