#!/usr/bin/env python3
"""Seed corpora for the fuzz targets, cut from real traffic.

    python3 fuzz/seed_corpora.py capture OUT.pcap [--build-dir build]   # root: netns + veth
    python3 fuzz/seed_corpora.py split OUT.pcap [--out fuzz/corpus]

`capture` runs `rackcat run --pcap` on the default rack in a private network namespace and
drives it with pysoem the way the interop tests do: scan (SII reads), SDO expedited and
segmented uploads, complete access, an SDO write, aborts, SDO information (the whole OD),
PDO mapping, distributed clocks, OP with cyclic process data, back to INIT.

`split` cuts that capture into small seed files, one directory per fuzz target
(fuzz_X reads fuzz/corpus/X, scripts/fuzz.sh):
  ecat_segment        byte 0 = clock advance (x 50 us), then one master frame, one per
                      distinct datagram layout (commands, addresses, lengths)
  coe_sdo             byte 0 = ESM state (0 = PREOP), byte 1 = mailbox size - 16, then the
                      SDO requests of one transfer as [length][mailbox message]
  coe_sdo_info        byte 0 = mailbox size - 16, then the SDO Information request body
  sii_parser          the EEPROM image the master read word by word (0x0502/0x0508)
The rack-file and control-API seeds (mdp_config, modules_control_api) are written by hand
from examples/ and the interop tests' requests; `split` leaves them alone.
"""
import argparse
import os
import struct
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SM0_START, SM0_SIZE = 0x1000, 128  # mdp/sync_manager_layout.hpp
FPWR, FPRD, APWR, APRD, BWR = 0x05, 0x04, 0x02, 0x01, 0x08


def read_pcap(path):
    data = Path(path).read_bytes()
    magic = struct.unpack_from("<I", data, 0)[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    pos, frames = 24, []
    while pos + 16 <= len(data):
        _ts, _tu, incl, _orig = struct.unpack_from(endian + "IIII", data, pos)
        frames.append(data[pos + 16:pos + 16 + incl])
        pos += 16 + incl
    return frames


def datagrams(frame):
    """(cmd, adp, ado, data, wkc) of every datagram of an EtherCAT frame."""
    if len(frame) < 16 or frame[12:14] != b"\x88\xa4":
        return []
    out, pos = [], 16
    while pos + 12 <= len(frame):
        cmd, _idx, adp, ado, ln, _irq = struct.unpack_from("<BBHHHH", frame, pos)
        n = ln & 0x7FF
        if pos + 12 + n > len(frame):
            break
        out.append((cmd, adp, ado, frame[pos + 10:pos + 10 + n],
                    struct.unpack_from("<H", frame, pos + 10 + n)[0]))
        pos += 12 + n
        if not ln & 0x8000:
            break
    return out


def is_request(frame):
    return len(frame) > 12 and not frame[6] & 0x02  # the ESC marks returned frames (docs/ESC.md)


def write_seed(directory, name, payload):
    directory.mkdir(parents=True, exist_ok=True)
    (directory / name).write_bytes(payload)


def split(pcap, out):
    frames = read_pcap(pcap)
    requests = [f for f in frames if is_request(f)]
    replies = [f for f in frames if not is_request(f)]

    # ecat_segment: one frame per distinct layout, at most 24.
    seen, chosen = set(), []
    for f in requests:
        layout = tuple((c, a if c not in (0x0A, 0x0B, 0x0C) else 0, len(d))
                       for c, _p, a, d, _w in datagrams(f))
        if layout and layout not in seen:
            seen.add(layout)
            chosen.append(f)
    step = max(1, len(chosen) // 24)
    for k, f in enumerate(chosen[::step][:24]):
        write_seed(out / "ecat_segment", f"frame-{k:02d}", bytes([20]) + f)

    # Mailbox requests: the SM0 writes (whole SM0, trimmed to the mailbox header's length).
    mails = []
    for f in requests:
        for c, _p, ado, d, _w in datagrams(f):
            if c == FPWR and ado == SM0_START and len(d) == SM0_SIZE:
                n = struct.unpack_from("<H", d, 0)[0]
                mails.append(d[:6 + n])
    sdo = [m for m in mails if m[5] & 0x0F == 3 and len(m) >= 8 and m[7] >> 4 == 2]
    info = [m for m in mails if m[5] & 0x0F == 3 and len(m) >= 8 and m[7] >> 4 == 8]

    # coe_sdo: transfers (an initiate and the segment requests after it), one per distinct
    # (command, index) at most 16.
    transfers, current = [], []
    for m in sdo:
        ccs = m[8] >> 5
        if ccs in (1, 2) and current:  # download / upload initiate starts a new transfer
            transfers.append(current)
            current = []
        current.append(m)
    if current:
        transfers.append(current)
    seen = set()
    k = 0
    for t in transfers:
        key = (t[0][8], t[0][9:11], len(t) > 1)
        if key in seen:
            continue
        seen.add(key)
        body = bytes([0, SM0_SIZE - 16]) + b"".join(bytes([len(m)]) + m for m in t[:8])
        write_seed(out / "coe_sdo", f"transfer-{k:02d}", body)
        k += 1
        if k == 16:
            break

    # coe_sdo_info: one request per opcode and (for descriptions) a few different indices.
    seen, k = set(), 0
    for m in info:
        key = (m[8] & 0x7F, m[12:14])
        opcode_count = sum(1 for s in seen if s[0] == key[0])
        if key in seen or opcode_count >= 4:
            continue
        seen.add(key)
        write_seed(out / "coe_sdo_info", f"request-{k:02d}", bytes([SM0_SIZE - 16]) + m[8:])
        k += 1

    # sii_parser: the words the master read. A read command (0x0502 = 0x0100, address in
    # 0x0504) followed by the read of 0x0508 in the returned frame.
    eeprom = {}
    address = None
    for f in replies:
        for c, _p, ado, d, w in datagrams(f):
            if c in (APWR, FPWR, BWR) and ado == 0x0502 and len(d) >= 6 and d[1] & 0x01:
                address = struct.unpack_from("<I", d, 2)[0] * 2
            elif c in (APRD, FPRD) and ado == 0x0502 and len(d) >= 10 and w and address is not None:
                for i, b in enumerate(d[6:10]):  # 0x0508.. within a 0x0502 read
                    eeprom.setdefault(address + i, b)
            elif c in (APRD, FPRD) and ado == 0x0508 and w and address is not None:
                for i, b in enumerate(d[:8]):
                    eeprom.setdefault(address + i, b)
    if eeprom:
        size = max(eeprom) + 1
        image = bytes(eeprom.get(i, 0xFF) for i in range(size))
        write_seed(out / "sii_parser", "from-capture.bin", image)

    for target in ("ecat_segment", "coe_sdo", "coe_sdo_info", "sii_parser"):
        files = list((out / target).glob("*")) if (out / target).exists() else []
        print(f"{target}: {len(files)} seeds, {sum(p.stat().st_size for p in files)} bytes")


def capture(pcap, build_dir):
    sys.path.insert(0, str(REPO / "tests" / "interop"))
    import pysoem
    from conftest import VethNamespace, probe_brd

    rackcat = Path(build_dir).resolve() / "rackcat"
    state = Path(pcap).resolve().parent / "seed-capture-state"
    with VethNamespace() as ns:
        proc = subprocess.Popen(ns.exec_prefix() + [
            str(rackcat), "run", "--iface", ns.slave_iface, "--state-dir", str(state),
            "--pcap", str(Path(pcap).resolve()), "--no-pty"])
        try:
            assert probe_brd(ns.master_iface) == 1, "rackcat does not answer"
            m = pysoem.Master()
            m.open(ns.master_iface)
            assert m.config_init() == 1
            s = m.slaves[0]
            s.sdo_read(0x1018, 2)                       # expedited upload
            s.sdo_read(0x2000, 1)                       # normal upload (string)
            s.sdo_read(0x1018, 0, ca=True)              # complete access
            s.sdo_read(0x1C12, 0, 1024, ca=True)
            s.sdo_read(0x6177, 0, 1024, ca=True)        # segmented upload (258 bytes)
            old = s.sdo_read(0x2000, 9)
            s.sdo_write(0x2000, 9, struct.pack("<I", 0x0000FF0F))  # expedited download
            s.sdo_write(0x2000, 9, old)
            s.sdo_write(0x2000, 4, b"192.168.9.51")     # normal download (string)
            m.config_map()
            m.config_dc()
            m.state = pysoem.SAFEOP_STATE
            m.write_state()
            m.state_check(pysoem.SAFEOP_STATE, 2_000_000)
            m.state = pysoem.OP_STATE
            m.write_state()
            for k in range(500):
                s.output = bytes([k & 0xFF]) * len(s.output)
                m.send_processdata()
                m.receive_processdata(20_000)
                time.sleep(0.001)
            m.state = pysoem.INIT_STATE
            m.write_state()
            m.state_check(pysoem.INIT_STATE, 2_000_000)
            m.config_init()
            for index, sub in ((0x1234, 0), (0x1018, 9)):
                try:
                    s.sdo_read(index, sub)              # aborts (SOEM then refuses config_map)
                except pysoem.SdoError:
                    pass
            try:
                _ = s.od                                # SDO information, the whole OD
            except Exception as e:  # noqa: BLE001 - the seeds only need the traffic
                print(f"SDO information: {e}")
            m.close()
        finally:
            time.sleep(1.5)  # the capture is flushed once a second
            proc.terminate()
            proc.wait(10)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("capture")
    c.add_argument("pcap")
    c.add_argument("--build-dir", default=os.environ.get("RACKCAT_BUILD_DIR", REPO / "build"))
    s = sub.add_parser("split")
    s.add_argument("pcap")
    s.add_argument("--out", default=REPO / "fuzz" / "corpus", type=Path)
    a = ap.parse_args()
    if a.cmd == "capture":
        capture(a.pcap, a.build_dir)
    else:
        split(a.pcap, a.out)


if __name__ == "__main__":
    main()
