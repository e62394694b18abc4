#!/usr/bin/env python3
"""Checks a capture of the RIM CAN bus (dumpcap on vcan1 in the EtherCAT stage of the CAN VM
test, docs/CAN.md): Wireshark's CANopen dissector must decode every frame without a malformed
or error-level expert item, and the capture must hold what a RIM start-up puts on the bus
(CiA 301): NMT start, boot-up and operational heartbeats, SDO requests and responses, TPDOs
and RPDOs. Prints one line:
    CAN_VM_CAPTURE PASS|FAIL|SKIP key=value ...
Usage: check_can_capture.py CAPTURE_FILE
"""
import collections
import shutil
import subprocess
import sys
from pathlib import Path

DECODE = ["-d", "can.subdissector,canopen"]  # CAN carries no protocol id: tell tshark

# CiA 301 pre-defined connection set: function code (COB-ID bits 10..7, as the dissector's
# canopen.function_code gives it) -> what it carries.
FUNCTIONS = {0x0: "nmt", 0x1: "emcy", 0x2: "time", 0x3: "tpdo", 0x4: "rpdo", 0x5: "tpdo",
             0x6: "rpdo", 0x7: "tpdo", 0x8: "rpdo", 0x9: "tpdo", 0xA: "rpdo",
             0xB: "sdo_response", 0xC: "sdo_request", 0xE: "heartbeat"}
REQUIRED = ("nmt", "heartbeat", "sdo_request", "sdo_response", "tpdo", "rpdo")


def tshark(pcap, *args):
    out = subprocess.run(["tshark", "-n", "-r", str(pcap), *DECODE, *args],
                         stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                         timeout=120).stdout
    return [line for line in out.splitlines() if line.strip()]


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        sys.exit(2)
    pcap = Path(sys.argv[1])
    if shutil.which("tshark") is None:
        print("CAN_VM_CAPTURE SKIP reason=no_tshark")
        return 0
    if not pcap.exists() or pcap.stat().st_size == 0:
        print("CAN_VM_CAPTURE FAIL reason=no_capture")
        return 1
    total = len(tshark(pcap, "-T", "fields", "-e", "frame.number"))
    rows = tshark(pcap, "-Y", "canopen", "-T", "fields", "-e", "canopen.function_code")
    bad = tshark(pcap, "-Y", "_ws.malformed || _ws.expert.severity >= error")
    kinds = collections.Counter(FUNCTIONS.get(int(r.split(",")[0], 16), "other") for r in rows)
    missing = [k for k in REQUIRED if kinds[k] == 0]
    ok = total > 0 and len(rows) == total and not bad and not missing
    counts = " ".join(f"{k}={kinds[k]}" for k in (*REQUIRED, "emcy", "other"))
    print(f"CAN_VM_CAPTURE {'PASS' if ok else 'FAIL'} frames={total} canopen={len(rows)} "
          f"malformed_or_error={len(bad)} {counts}"
          + (f" missing={','.join(missing)}" if missing else ""))
    for line in bad[:5]:
        print("  " + line)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
