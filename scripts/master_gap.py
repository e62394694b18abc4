#!/usr/bin/env python3
"""Where a round trip's time goes, from a capture on the master's end of the veth pair.

Each EtherCAT frame the master sends is followed by the slave's reply (the slave sets bit 1 of
the first source-MAC byte on every frame it processed, docs/ESC.md). From the capture's
timestamps (taken by the kernel as the frames pass the master's interface):

  turnaround   request -> reply: the slave, its kernel paths and the veth in between
  master gap   reply -> next request: the master waking up and building the next frame

    dumpcap -q -P -i MASTER_IFACE -w cap.pcap   (in the master's namespace, during the run)
    scripts/master_gap.py cap.pcap [--skip 100]

libpcap's TPACKET_V3 ring wakes the capture once per block, not once per frame, so it hardly
disturbs what it measures. Prints the percentiles in microseconds.
"""
import argparse
import statistics
import struct
import sys


def frames(path):
    data = open(path, "rb").read()
    magic = struct.unpack("<I", data[:4])[0]
    if magic not in (0xA1B2C3D4, 0xA1B23C4D):
        sys.exit(f"{path}: not a little-endian pcap file (pcapng: capture with dumpcap -P)")
    nano = magic == 0xA1B23C4D
    pos = 24
    while pos + 16 <= len(data):
        sec, frac, incl, _ = struct.unpack("<IIII", data[pos:pos + 16])
        frame = data[pos + 16:pos + 16 + incl]
        pos += 16 + incl
        if len(frame) >= 14 and frame[12:14] == b"\x88\xa4":
            yield sec * 1e6 + (frac / 1000 if nano else frac), bool(frame[6] & 0x02)


def pct(values, p):
    s = sorted(values)
    return s[min(len(s) - 1, int(len(s) * p / 100))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pcap")
    ap.add_argument("--skip", type=int, default=100, help="round trips left out at each end")
    args = ap.parse_args()
    turnaround, gap = [], []
    prev = None
    for t, reply in frames(args.pcap):
        if prev is not None and reply and not prev[1]:
            turnaround.append(t - prev[0])
        if prev is not None and not reply and prev[1]:
            gap.append(t - prev[0])
        prev = (t, reply)
    turnaround = turnaround[args.skip:len(turnaround) - args.skip]
    gap = gap[args.skip:len(gap) - args.skip]
    if not turnaround or not gap:
        sys.exit("no request/reply pairs in the capture")
    for name, v in (("turnaround", turnaround), ("master gap", gap)):
        print(f"{name:10s} n {len(v):6d}  p50 {pct(v, 50):7.2f}  p90 {pct(v, 90):7.2f}  "
              f"mean {statistics.mean(v):7.2f} us")


if __name__ == "__main__":
    main()
