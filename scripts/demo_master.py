#!/usr/bin/env python3
"""What a real EtherCAT master (pysoem, which bundles SOEM) sees of rackcat.

Used by scripts/demo.sh (the README's run command): scans the segment, prints each slave's name
and identity, walks it INIT -> PREOP -> SAFEOP -> OP, prints the PDO map, shows a few seconds of
live process data while writing a pattern to the outputs, reads a few SDOs and goes back to
INIT.
"""
import argparse
import struct
import sys
import time

import pysoem

STATES = {
    pysoem.INIT_STATE: "INIT",
    pysoem.PREOP_STATE: "PREOP",
    pysoem.SAFEOP_STATE: "SAFEOP",
    pysoem.OP_STATE: "OP",
    pysoem.BOOT_STATE: "BOOT",
}


def state_name(s):
    base = STATES.get(s & 0x0F, hex(s))
    return base + (" + ERROR" if s & pysoem.STATE_ERROR else "")


def go(master, state, timeout_us=2_000_000):
    master.state = state
    master.write_state()
    reached = master.state_check(state, timeout_us)
    master.read_state()
    names = ", ".join(
        f"{s.name}: {state_name(s.state)}" + (f" (AL 0x{s.al_status:04X})" if s.al_status else "")
        for s in master.slaves[:4]
    )
    more = f" ... ({len(master.slaves)} slaves)" if len(master.slaves) > 4 else ""
    print(f"  -> {STATES[state]:6s} {'ok' if reached == state else 'FAILED'}   [{names}{more}]")
    if reached != state:
        raise SystemExit(f"master: could not reach {STATES[state]}")


def sdo_str(slave, index, sub):
    try:
        return slave.sdo_read(index, sub).rstrip(b"\0").decode(errors="replace")
    except pysoem.SdoError as e:
        return f"abort 0x{e.abort_code:08X}"


def sdo_u(slave, index, sub, fmt):
    return struct.unpack(fmt, slave.sdo_read(index, sub))[0]


def print_pdo_map(slave):
    for assign, kind in ((0x1C12, "RxPDO (outputs)"), (0x1C13, "TxPDO (inputs)")):
        count = sdo_u(slave, assign, 0, "<B")
        print(f"  0x{assign:04X} {kind}: {count} PDO(s)")
        for k in range(1, count + 1):
            pdo = sdo_u(slave, assign, k, "<H")
            n = sdo_u(slave, pdo, 0, "<B")
            entries = []
            for e in range(1, n + 1):
                m = sdo_u(slave, pdo, e, "<I")
                entries.append(f"{m >> 16:04X}:{(m >> 8) & 0xFF:02X}/{m & 0xFF}")
            shown = ", ".join(entries[:6]) + (f", ... ({n} entries)" if n > 6 else "")
            print(f"     0x{pdo:04X}: {shown}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("iface")
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--cycle-ms", type=float, default=1.0)
    args = ap.parse_args()

    master = pysoem.Master()
    master.open(args.iface)
    try:
        n = 0
        for _ in range(20):  # the slave may still be starting
            n = master.config_init()
            if n > 0:
                break
            time.sleep(0.1)
        if n <= 0:
            raise SystemExit("master: no slave found")
        print(f"master: found {n} slave(s)")
        for i, s in enumerate(master.slaves):
            print(f"  slave {i}: '{s.name}' vendor 0x{s.man:08X} product 0x{s.id:08X} "
                  f"revision 0x{s.rev:08X}, state {state_name(s.state)}")
        slave = master.slaves[0]
        print("state transitions:")
        master.read_state()
        print(f"  -> PREOP  (config_init)  [{slave.name}: {state_name(slave.state)}]")
        print("SDO reads (PREOP):")
        print(f"  0x1008 device name      : {sdo_str(slave, 0x1008, 0)}")
        print(f"  0x100A firmware version : {sdo_str(slave, 0x100A, 0)}")
        print(f"  0x1018:04 serial number : 0x{sdo_u(slave, 0x1018, 4, '<I'):08X}")
        try:
            print(f"  0x2000:01 part number   : {sdo_str(slave, 0x2000, 1)}")
            modules = slave.sdo_read(0xF050, 0)[0]
            print(f"  0xF050 detected modules : {modules}")
        except pysoem.SdoError as e:
            print(f"  (device objects: abort 0x{e.abort_code:08X})")
        print("PDO map:")
        print_pdo_map(slave)
        size = master.config_map()
        print(f"process image: {size} bytes; slave 0: {len(slave.output)} output bytes, "
              f"{len(slave.input)} input bytes")
        if master.config_dc():
            slave.dc_sync(True, int(args.cycle_ms * 1_000_000))
            print(f"distributed clocks: SYNC0 every {args.cycle_ms} ms")
        go(master, pysoem.SAFEOP_STATE)
        master.send_processdata()
        master.receive_processdata(2000)
        master.state = pysoem.OP_STATE
        master.write_state()
        for _ in range(200):
            master.send_processdata()
            master.receive_processdata(2000)
            if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
                break
        go(master, pysoem.OP_STATE)

        expected = master.expected_wkc
        cycles = bad = lost = 0
        end = time.monotonic() + args.seconds
        next_print = 0.0
        print(f"live process data (expected WKC {expected}):")
        while time.monotonic() < end:
            pattern = (cycles // 100) & 0xFF
            slave.output = bytes([pattern] * len(slave.output))
            master.send_processdata()
            wkc = master.receive_processdata(2000)
            cycles += 1
            if wkc < 0:
                lost += 1  # no reply within SOEM's 2 ms: timing (a busy machine), not an answer
            elif wkc != expected:
                bad += 1
            now = time.monotonic()
            if now >= next_print:
                print(f"  cycle {cycles:6d} wkc {wkc}  out {slave.output[:8].hex(' ')}  "
                      f"in {slave.input[:16].hex(' ')}")
                next_print = now + 0.5
            time.sleep(args.cycle_ms / 1000.0)
        print(f"  {cycles} cycles, {bad} with a wrong working counter, {lost} without a reply "
              f"within 2 ms")
        # A reply with a wrong working counter is a fault; a late reply is the machine's load
        # (the tests measure timing, docs/PERFORMANCE.md), unless it is more than 1 in 100.
        late = lost * 100 > cycles
        if lost and not late:
            print("  (late replies: the machine was busy; scripts/test.sh measures timing)")
        print("back to INIT:")
        go(master, pysoem.SAFEOP_STATE)
        go(master, pysoem.INIT_STATE)
        return 0 if bad == 0 and not late else 1
    finally:
        master.close()


if __name__ == "__main__":
    sys.exit(main())
