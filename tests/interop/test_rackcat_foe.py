"""Firmware update and parameter backup over FoE (ETG.1000.6 §5.8) with pysoem (SOEM 1.4),
as SOEM's firm_update does it: INIT, the bootstrap mailbox from SII words 0x14-0x17 put into
SM0/SM1 (amend_mbx), BOOT, foe_write, INIT; then a power cycle (restart of `rackcat run` with the
same state directory) and the new version read back over SDO and from the SII.

SOEM 1.4 does not return an FoE error code to the caller, so the codes are read from the frames
the slave sent (the pcap of the run): the FoE Error request carries code and standard text.
"""
import hashlib
import os
import random
import signal
import struct
import subprocess
import threading
import time
import zlib

from rackcat_helpers import (RACKCAT, device_reset, open_master, pysoem, rackcat, run_command,
                             store_parameters)

assert rackcat  # the fixture, imported for pytest

FOE_PASSWORD = 0x52434657  # "RCFW", the default (docs/FOE.md)
FW_NAME = "rackcat-update.rfw"
PRODUCT = 0x00464E01  # the built-in rack's identity (0x1018:02)
FOE_TIMEOUT_US = 10_000_000  # per mailbox step; generous: the machine is shared


def pack(tmp_path, version, revision, short="", payload=b"", config=None, name="fw"):
    src = tmp_path / f"{name}.payload"
    src.write_bytes(payload)
    out = tmp_path / f"{name}.rfw"
    args = [str(RACKCAT), "firmware", "pack", "--software-version", version, "--revision",
            hex(revision), "--payload", str(src), "-o", str(out)]
    if short:
        args += ["--short-version", short]
    if config:
        args += ["--config", str(config)]
    subprocess.run(args, check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=30)
    return out.read_bytes()


def enter_boot(slave):
    """INIT, then SM0/SM1 from the SII's bootstrap words, then BOOT (SOEM firm_update)."""
    slave.state = pysoem.INIT_STATE
    slave.write_state()
    assert slave.state_check(pysoem.INIT_STATE, 3_000_000) == pysoem.INIT_STATE
    rx_off, rx_len = struct.unpack("<HH", slave.eeprom_read(pysoem.SiiOffset.BOOT_RX_MBX))
    tx_off, tx_len = struct.unpack("<HH", slave.eeprom_read(pysoem.SiiOffset.BOOT_TX_MBX))
    assert rx_len and tx_len, "no bootstrap mailbox in the SII"
    slave.amend_mbx(mailbox="out", start_address=rx_off, size=rx_len)
    slave.amend_mbx(mailbox="in", start_address=tx_off, size=tx_len)
    slave.state = pysoem.BOOT_STATE
    slave.write_state()
    got = slave.state_check(pysoem.BOOT_STATE, 3_000_000)
    assert got == pysoem.BOOT_STATE, f"BOOT not reached: AL status 0x{slave.al_status:04X}"
    return rx_len


def leave_boot(slave):
    slave.state = pysoem.INIT_STATE
    slave.write_state()
    assert slave.state_check(pysoem.INIT_STATE, 3_000_000) == pysoem.INIT_STATE


def foe_write(slave, name, data, password=FOE_PASSWORD, release_gil=False):
    """True when the slave acknowledged the whole file; False when it refused (SOEM returns
    a non-positive working counter, or pysoem raises)."""
    try:
        return slave.foe_write(name, password, data, FOE_TIMEOUT_US, release_gil=release_gil) > 0
    except pysoem.WkcError:
        return False


def foe_error_sent(pcap, code, text):
    """The slave sent FoE Error `code` with its standard text (FoE header: OpCode 5, reserved,
    UINT32 code, text)."""
    needle = bytes([0x05, 0x00]) + struct.pack("<I", code) + text.encode()
    return needle in pcap.read_bytes()


def sdo_text(slave, index, sub):
    return slave.sdo_read(index, sub).rstrip(b"\0").decode()


def sdo_u32(slave, index, sub):
    return struct.unpack("<I", slave.sdo_read(index, sub))[0]


def checksum_md5(slave):
    """0xFBF3 Calculate Checksum, MD5 (bit 2): the 16 bytes after status and reserved."""
    assert run_command(slave, 0xFBF3, bytes([0x04, 0, 0, 0])) == 1
    return slave.sdo_read(0xFBF3, 3)[2:18]


def test_firmware_update_in_boot_reports_the_new_version_after_a_power_cycle(rackcat, tmp_path):
    payload = random.Random(1).randbytes(64 * 1024)
    fw = pack(tmp_path, "2.00.1", 0x00020001, "7a", payload)
    rc = rackcat()
    master = open_master(rc.iface)
    s = master.slaves[0]
    assert s.rev == 0x00010009
    assert sdo_text(s, 0x100A, 0) == "1.09.6"
    enter_boot(s)
    # The running firmware is the built-in one until the device restarts.
    running = s.foe_read(FW_NAME, FOE_PASSWORD, 4096, FOE_TIMEOUT_US)
    assert running[:8] == b"RCATFW\r\n" and b"1.09.6" in running
    assert foe_write(s, FW_NAME, fw), rc.log()
    assert s.foe_read(FW_NAME, FOE_PASSWORD, 4096, FOE_TIMEOUT_US) == running
    leave_boot(s)
    master.close()

    rc.restart()  # power cycle, same state directory
    master = open_master(rc.iface)
    s = master.slaves[0]
    assert s.rev == 0x00020001  # SII word 0x0C
    assert sdo_text(s, 0x100A, 0) == "2.00.1"
    assert sdo_u32(s, 0x1018, 3) == 0x00020001
    assert sdo_text(s, 0x2000, 2) == "7a"
    enter_boot(s)
    assert s.foe_read(FW_NAME, FOE_PASSWORD, len(fw) + 1, FOE_TIMEOUT_US) == fw
    leave_boot(s)
    master.close()


def test_device_reset_after_a_firmware_update_runs_the_new_version(rackcat, tmp_path):
    """The device reset 0xFBF0 (ETG.5003.1) restarts the firmware like a power cycle: after a
    foe_write in BOOT, back to PREOP still reports the old version; once the reset has run and
    the master has scanned again, 0x100A, 0x1018:03, 0x2000:02 and the SII revision (word 0x0C,
    pysoem's slave.rev) report the new one (a version text of another length than the old one:
    0x100A is re-created)."""
    fw = pack(tmp_path, "2.10.0-rc1", 0x00020100, "8c", b"new firmware")
    rc = rackcat()
    master = open_master(rc.iface)
    s = master.slaves[0]
    enter_boot(s)
    assert foe_write(s, FW_NAME, fw), rc.log()
    leave_boot(s)
    master.close()
    master = open_master(rc.iface)  # a new scan: the standard mailbox, PREOP
    s = master.slaves[0]
    assert sdo_text(s, 0x100A, 0) == "1.09.6"  # the old firmware runs until the reset
    assert sdo_u32(s, 0x1018, 3) == 0x00010009
    assert s.rev == 0x00010009  # SII words 0x0C-0x0D as SOEM's scan read them
    device_reset(master, s)
    assert s.al_status == 0, hex(s.al_status)
    master.close()
    master = open_master(rc.iface)
    s = master.slaves[0]
    assert sdo_text(s, 0x100A, 0) == "2.10.0-rc1"
    assert sdo_u32(s, 0x1018, 3) == 0x00020100
    # The restarted firmware stored its SII image in the ESC's EEPROM through the PDI side of
    # the EEPROM interface (ecat/slave/eeprom_store.cpp): config_init's SII read sees it.
    assert s.rev == 0x00020100, hex(s.rev)
    assert sdo_text(s, 0x2000, 2) == "8c"
    enter_boot(s)
    assert s.foe_read(FW_NAME, FOE_PASSWORD, len(fw) + 1, FOE_TIMEOUT_US) == fw
    leave_boot(s)
    master.close()
    rc.stop()


def test_bad_firmware_files_are_refused_with_their_foe_error_and_change_nothing(rackcat, tmp_path):
    good = pack(tmp_path, "3.0.0", 0x00030000, "", b"x" * 5000, name="good")
    corrupt = bytearray(good)
    corrupt[-100] ^= 0x01
    wrong_product = bytearray(good)
    wrong_product[20:24] = struct.pack("<I", PRODUCT + 1)
    # Keep the header CRC right so the product check is the one that refuses it.
    wrong_product[124:128] = struct.pack("<I", zlib.crc32(bytes(wrong_product[:124])))
    rc = rackcat()
    master = open_master(rc.iface)
    s = master.slaves[0]
    # In PREOP, firmware is refused: Bootstrap only.
    assert not foe_write(s, FW_NAME, good)
    enter_boot(s)
    cases = [
        (FW_NAME, bytes(corrupt), FOE_PASSWORD, 0x800C, "Wrong checksum"),
        (FW_NAME, good[:-700], FOE_PASSWORD, 0x800C, "Wrong checksum"),  # truncated
        (FW_NAME, bytes(wrong_product), FOE_PASSWORD, 0x800D, "Firmware does not fit for hardware"),
        (FW_NAME, b"not a firmware file at all", FOE_PASSWORD, 0x8010, "File header does not exist"),
        (FW_NAME, good, FOE_PASSWORD ^ 1, 0x800A, "No rights"),
        ("../escape.rfw", good, FOE_PASSWORD, 0x8001, "Not found"),
        ("parameters.bin", good, FOE_PASSWORD, 0x8009, "Not Bootstrap"),
        ("rackcat-" + "a" * 60 + ".rfw", good, FOE_PASSWORD, 0x8004, "Illegal"),
    ]
    for name, data, password, _, _ in cases:
        assert not foe_write(s, name, data, password), name
    leave_boot(s)
    master.close()
    rc.stop()
    pcap = rc.pcap
    assert foe_error_sent(pcap, 0x8008, "Bootstrap only")
    for name, _, _, code, text in cases:
        assert foe_error_sent(pcap, code, text), f"{name}: no FoE error 0x{code:04X} ({text})"
    assert not (rc.state_dir / "firmware.rfw").exists()
    assert not (tmp_path / "escape.rfw").exists()
    rc.start()
    master = open_master(rc.iface)
    assert sdo_text(master.slaves[0], 0x100A, 0) == "1.09.6"
    master.close()


def test_parameter_backup_from_one_rack_restores_a_second(rackcat):
    rc = rackcat(slaves=2)
    master = open_master(rc.iface, 2)
    a, b = master.slaves[0], master.slaves[1]
    a.sdo_write(0x2000, 4, b"10.20.30.40")
    assert store_parameters(a) == 0
    assert checksum_md5(a) != checksum_md5(b)
    backup = a.foe_read("parameters.bin", FOE_PASSWORD, 65536, FOE_TIMEOUT_US)
    assert backup[:8] == b"RACKCATP"
    assert foe_write(b, "parameters.bin", backup)
    assert sdo_text(b, 0x2000, 4) == "10.20.30.40"
    assert checksum_md5(a) == checksum_md5(b)
    # A damaged backup is refused and changes nothing.
    damaged = bytearray(backup)
    damaged[-5] ^= 0xFF
    assert not foe_write(a, "parameters.bin", bytes(damaged))
    assert not foe_write(a, "nothing-here.bin", backup)
    assert sdo_text(a, 0x2000, 4) == "10.20.30.40"
    master.close()
    rc.stop()
    assert foe_error_sent(rc.pcap, 0x800C, "Wrong checksum")
    assert foe_error_sent(rc.pcap, 0x8001, "Not found")
    rc.start()  # the restore was stored: it survives the power cycle
    master = open_master(rc.iface, 2)
    assert sdo_text(master.slaves[1], 0x2000, 4) == "10.20.30.40"
    master.close()


def installed_version(state_dir):
    """The version string of the installed firmware file, None without one; raises when the
    file is not a whole container (a mixed state)."""
    path = state_dir / "firmware.rfw"
    if not path.exists():
        return None
    data = path.read_bytes()
    length = struct.unpack("<I", data[28:32])[0]
    assert len(data) == 128 + length, f"mixed state: {len(data)} bytes, header says {128 + length}"
    assert hashlib.sha256(data[128:]).digest() == data[64:96], "mixed state: payload hash"
    return data[36:60].rstrip(b"\0").decode()


VERSIONS = ["4.0.0", "4.0.1", "4.0.2"]


def test_kill_during_firmware_commits_leaves_old_or_new_never_a_mix(rackcat, tmp_path):
    """Bounded trial loop: kill -9 the device at a random moment of a firmware write (most
    near its end, where the commit runs), restart, and check file and 0x100A agree."""
    trials = int(os.environ.get("RACKCAT_FOE_KILL_TRIALS", "8"))
    rng = random.Random(17)
    payload = rng.randbytes(256 * 1024)
    images = {v: pack(tmp_path, v, 0x00040000 + i, "", payload + v.encode(), name=f"k{i}")
              for i, v in enumerate(VERSIONS)}
    rc = rackcat(pcap=False)
    mixed = 0
    outcomes = []
    duration = None
    for trial in range(trials):
        before = installed_version(rc.state_dir) or "1.09.6"
        version = next(v for v in VERSIONS[trial % 3:] + VERSIONS if v != before)
        master = open_master(rc.iface)
        s = master.slaves[0]
        enter_boot(s)
        killer = None
        if duration is not None:
            delay = duration * rng.uniform(0.3, 1.6)
            killer = threading.Timer(delay, lambda: rc.proc.stop(sig=signal.SIGKILL))
            killer.start()
        t0 = time.monotonic()
        ok = foe_write(s, FW_NAME, images[version], release_gil=True)
        if killer is None:
            assert ok, rc.log()
            duration = time.monotonic() - t0
            leave_boot(s)
            master.close()
            rc.proc.stop(sig=signal.SIGKILL)
        else:
            killer.join()
            master.close()
        rc.start()
        try:
            on_disk = installed_version(rc.state_dir) or "1.09.6"
        except AssertionError:
            mixed += 1
            continue
        master = open_master(rc.iface)
        reported = sdo_text(master.slaves[0], 0x100A, 0)
        master.close()
        if reported != on_disk or on_disk not in (before, version):
            mixed += 1
        outcomes.append((before, version, on_disk))
    print(f"kill trials (before, written, after), transfer {duration:.3f} s:", outcomes)
    assert mixed == 0, outcomes
    assert len(outcomes) == trials
