#!/usr/bin/env python3
"""FoE write throughput of a firmware file with pysoem (SOEM 1.4) over veth, in BOOT, at a given
bootstrap mailbox size (docs/FOE.md, docs/PERFORMANCE.md).

For each mailbox size: `rackcat run --boot-mailbox-size N` in a private namespace, pysoem
enters BOOT as SOEM's firm_update does (SII words 0x14-0x17 into SM0/SM1) and writes a packed
firmware file of --size bytes; the time of foe_write gives KiB/s. A second run records a pcap
and counts the frames the master sent during the transfer: frames per FoE data packet
(a packet carries mailbox size - 12 bytes; every packet is a mailbox write, status polls and
the read of the Ack).

    sudo scripts/foe_throughput.py [--build-dir build] [--size 1048576] [--sizes 512,1486]

With --esi: the same for a device emulated from its ESI (test device RC6001 of
tests/device/data/rackcat-test-devices.xml on a line, BOOT, its 256-byte bootstrap mailbox):
foe_write of a --size file (at most 1 MiB, device/foe_files.hpp) and foe_read of it back; the
device's file work runs on the background worker (the write's commit answers Busy, the read's
first Data is deferred until the file is read).
"""
import argparse
import os
import random
import shlex
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests" / "interop"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build-dir", default=str(REPO / "build"))
    ap.add_argument("--size", type=int, default=1 << 20)
    ap.add_argument("--sizes", default="512,1486")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--esi", action="store_true", help="an ESI device's FoE files (RC6001)")
    args = ap.parse_args()
    os.environ["RACKCAT_BUILD_DIR"] = args.build_dir
    import pysoem
    from conftest import SlaveProcess, VethNamespace
    from rackcat_helpers import realtime_master, rt_prefix

    rackcat = Path(args.build_dir) / "rackcat"
    tmp = Path(tempfile.mkdtemp(prefix="rackcat-foe-bench-"))
    payload = random.Random(5).randbytes(args.size - 128)
    (tmp / "payload").write_bytes(payload)
    fw = tmp / "fw.rfw"
    subprocess.run([str(rackcat), "firmware", "pack", "--software-version", "9.9.9", "--revision",
                    "0x00090909", "--payload", str(tmp / "payload"), "-o", str(fw)], check=True)
    data = fw.read_bytes()
    password = 0x52434657

    def one(mbx, pcap):
        with VethNamespace() as ns:
            state = tempfile.mkdtemp(dir=tmp)
            cap = tmp / f"foe-{mbx}.pcap" if pcap else None
            proc = SlaveProcess(ns, f"{shlex.quote(str(rackcat))} run --iface {{iface}} --slaves {{slaves}}", 1,
                                ["--state-dir", state, "--no-control", "--no-pty",
                                 "--boot-mailbox-size", str(mbx)], cap, tmp / f"log-{mbx}-{time.monotonic_ns()}.txt",
                                rt_prefix())
            try:
                m, s, size = open_in_boot(pysoem, proc, ns)
                assert size == mbx
                t0 = time.time()
                wkc = s.foe_write("rackcat-bench.rfw", password, data, 10_000_000)
                t1 = time.time()
                assert wkc > 0, "foe_write refused"
                s.state = pysoem.INIT_STATE
                s.write_state()
                m.close()
            finally:
                proc.stop()
            return t0, t1, cap

    def frames_of_transfer(pcap, last_packet):
        """Master frames from the write request (FoE OpCode 2 in a datagram to SM0) until the
        master first sends the last Data packet (the data phase), and the Busy answers of the
        commit after it; counted in the capture (its own clock)."""
        raw = pcap.read_bytes()
        pos, n, counting, busy = 24, 0, False, 0
        while pos + 16 <= len(raw):
            incl = struct.unpack_from("<I", raw, pos + 8)[0]
            frame = raw[pos + 16:pos + 16 + incl]
            pos += 16 + incl
            from_master = not (frame[6] & 0x02)  # the slave sets bit 1 of its source MAC
            p = 16  # Ethernet header and EtherCAT frame header
            while p + 12 <= len(frame):
                ado = struct.unpack_from("<H", frame, p + 4)[0]
                length = struct.unpack_from("<H", frame, p + 6)[0]
                data = frame[p + 10:p + 10 + (length & 0x7FF)]
                if len(data) >= 12 and data[5] & 0x0F == 4:  # mailbox type FoE
                    op, value = data[6], struct.unpack_from("<I", data, 8)[0]
                    if from_master and op == 2:
                        counting, n = True, 0
                    if from_master and op == 3 and value == last_packet and counting:
                        counting = False
                    if not from_master and op == 6:
                        busy += 1
                    if not from_master and op == 4 and value == last_packet:
                        return n, busy
                p += 12 + (length & 0x7FF)
                if not length & 0x8000:
                    break
            if counting and from_master:
                n += 1
        return None, busy

    if args.esi:
        with realtime_master():
            measure_esi(args, rackcat, tmp, pysoem, VethNamespace, SlaveProcess,
                        frames_of_transfer)
        return
    print(f"FoE write of {len(data)} bytes (pysoem {pysoem.__version__}, BOOT; slave and master "
          "SCHED_FIFO as in tests/interop)")
    with realtime_master():
        measure(args, data, one, frames_of_transfer)


def measure_esi(args, rackcat, tmp, pysoem, VethNamespace, SlaveProcess, frames_of_transfer):
    """--esi: RC6001 (FoE, bootstrap mailbox 256 B) on a line; foe_write then foe_read."""
    from rackcat_helpers import rt_prefix
    shutil.copy(REPO / "tests/device/data/rackcat-test-devices.xml", tmp)
    line = tmp / "line.yaml"
    line.write_text("devices:\n  - {esi: rackcat-test-devices.xml, device: RC6001}\n")
    data = random.Random(6).randbytes(args.size)
    password = 0x52434657

    def one(pcap):
        with VethNamespace() as ns:
            state = tempfile.mkdtemp(dir=tmp)
            cap = tmp / f"foe-esi-{time.monotonic_ns()}.pcap" if pcap else None
            proc = SlaveProcess(ns, f"{shlex.quote(str(rackcat))} run --iface {{iface}}", 1,
                                ["--line", str(line), "--state-dir", state, "--no-control",
                                 "--no-pty"], cap, tmp / f"log-esi-{time.monotonic_ns()}.txt",
                                rt_prefix())
            try:
                m, s, size = open_in_boot(pysoem, proc, ns)
                t0 = time.time()
                assert s.foe_write("bench.bin", password, data, 10_000_000) > 0, proc.log()
                t1 = time.time()
                back = s.foe_read("bench.bin", password, len(data), 10_000_000)
                t2 = time.time()
                assert back == data, "foe_read gave other bytes"
                s.state = pysoem.INIT_STATE
                s.write_state()
                m.close()
            finally:
                proc.stop()
            return size, t1 - t0, t2 - t1, cap

    writes, reads = [], []
    for _ in range(args.runs):
        mbx, w, r, _ = one(False)
        writes.append(len(data) / 1024 / w)
        reads.append(len(data) / 1024 / r)
    mbx, _, _, cap = one(True)
    packets = len(data) // (mbx - 12) + 1
    frames, busy = frames_of_transfer(cap, packets)
    writes.sort()
    reads.sort()
    print(f"FoE of {len(data)} bytes to/from an ESI device (RC6001, pysoem {pysoem.__version__}, "
          f"BOOT, mailbox {mbx} B: {mbx - 12} data bytes/packet, {packets} packets)")
    print(f"write: median {writes[len(writes) // 2]:.0f} KiB/s (runs: "
          f"{', '.join(f'{r:.0f}' for r in writes)}), "
          + (f"{frames / (packets - 1):.2f} master frames per data packet, " if frames else "")
          + f"{busy} Busy answers while committing")
    print(f"read:  median {reads[len(reads) // 2]:.0f} KiB/s (runs: "
          f"{', '.join(f'{r:.0f}' for r in reads)})")


def open_in_boot(pysoem, proc, ns):
    """The one slave of `proc`, scanned by pysoem and taken to BOOT as SOEM's firm_update does
    (INIT, SII bootstrap mailbox words 0x14-0x17 into SM0/SM1, BOOT). Returns (master, slave,
    bootstrap mailbox size)."""
    proc.wait_ready(1)
    m = pysoem.Master()
    m.open(ns.master_iface)
    assert m.config_init() == 1
    s = m.slaves[0]
    s.state = pysoem.INIT_STATE
    s.write_state()
    assert s.state_check(pysoem.INIT_STATE, 3_000_000) == pysoem.INIT_STATE
    rx = struct.unpack("<HH", s.eeprom_read(pysoem.SiiOffset.BOOT_RX_MBX))
    tx = struct.unpack("<HH", s.eeprom_read(pysoem.SiiOffset.BOOT_TX_MBX))
    s.amend_mbx(mailbox="out", start_address=rx[0], size=rx[1])
    s.amend_mbx(mailbox="in", start_address=tx[0], size=tx[1])
    s.state = pysoem.BOOT_STATE
    s.write_state()
    assert s.state_check(pysoem.BOOT_STATE, 3_000_000) == pysoem.BOOT_STATE
    return m, s, rx[1]


def measure(args, data, one, frames_of_transfer):
    for mbx in [int(x) for x in args.sizes.split(",")]:
        rates = []
        for _ in range(args.runs):
            t0, t1, _ = one(mbx, False)
            rates.append(len(data) / 1024 / (t1 - t0))
        t0, t1, cap = one(mbx, True)
        packets = len(data) // (mbx - 12) + 1
        frames, busy = frames_of_transfer(cap, packets)
        rates.sort()
        if not rates:
            rates = [len(data) / 1024 / (t1 - t0)]
        print(f"mailbox {mbx:5d} B: {mbx - 12:5d} data bytes/packet, {packets} packets, "
              f"median {rates[len(rates) // 2]:.0f} KiB/s (runs: "
              f"{', '.join(f'{r:.0f}' for r in rates)}), "
              + (f"{frames / (packets - 1):.2f} master frames per data packet, {busy} Busy "
                 "answers while committing" if frames else "frames: n/a"))


if __name__ == "__main__":
    main()
