#!/usr/bin/env python3
"""The soak master: pysoem at 1 kHz in OP, SDO traffic on a second thread, fault injection.

Phase 1 (first half): no faults; every reply must carry the expected working counter.
Phase 2 (second half): RIM 2 unplugged and replugged, fan speeds and CPU temperature changed
through rackcat's control API (127.0.0.1:8765 in the same namespace) every few seconds. With
Detect Modules Override at its default (1) the slave stays in OP, so the working counter must
stay right here too; errors are reported per phase. A frame whose reply did not come back
within SOEM's 2 ms is a lost frame, reported apart from WKC errors (a reply with a wrong
working counter): on a loaded 2-core VM the veth's soft interrupts are sometimes late. In the
same way an SDO read that got no reply in time (pysoem.WkcError) is a timeout, and an
"unexpected frame" within three requests after one, or within a second of a lost process-data
frame, is a late or repeated reply to an earlier request (stale), both reported; any other
wrong answer (abort, mailbox error) is a failure.
"""
import argparse
import json
import os
import sys
import threading
import time
import urllib.request

import pysoem

API = "http://127.0.0.1:8765"


def rss_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return -1


TOKEN = ""  # the control API's per-run secret, read from the state directory in main()


def api(path, body):
    req = urllib.request.Request(API + path, data=json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json",
                                          "Authorization": f"Bearer {TOKEN}"}, method="POST")
    with urllib.request.urlopen(req, timeout=3) as r:
        return r.status


def to_op(master):
    master.config_map()
    master.state = pysoem.SAFEOP_STATE
    master.write_state()
    if master.state_check(pysoem.SAFEOP_STATE, 3_000_000) != pysoem.SAFEOP_STATE:
        raise SystemExit("soak: SAFEOP not reached")
    master.state = pysoem.OP_STATE
    master.write_state()
    for _ in range(500):
        master.send_processdata()
        master.receive_processdata(2000)
        if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
            return
    raise SystemExit("soak: OP not reached")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("iface")
    ap.add_argument("--pid", type=int, required=True)
    ap.add_argument("--minutes", type=float, default=1.0)
    ap.add_argument("--slaves", type=int, default=1)
    ap.add_argument("--state-dir", required=True, help="rackcat run's --state-dir (control token)")
    args = ap.parse_args()
    global TOKEN
    token_file = os.path.join(args.state_dir, "control-token")
    for _ in range(50):  # rackcat run writes it at start
        if os.path.exists(token_file):
            break
        time.sleep(0.1)
    with open(token_file) as f:
        TOKEN = f.readline().strip()

    master = pysoem.Master()
    master.open(args.iface)
    for _ in range(50):
        if master.config_init() == args.slaves:
            break
        time.sleep(0.1)
    else:
        raise SystemExit("soak: slaves not found")
    to_op(master)
    expected = master.expected_wkc
    stop = threading.Event()
    phase = [1]
    wkc_errors = {1: 0, 2: 0}
    lost = {1: 0, 2: 0}
    cycles = {1: 0, 2: 0}
    sdo = {"ok": 0, "failed": 0, "emergencies": 0}
    late = [0]
    sdo_timeouts = {1: 0, 2: 0}
    sdo_stale = {1: 0, 2: 0}
    since_timeout = [1000]
    last_lost = [-1e9]  # monotonic time of the last process-data frame lost (late reply)
    sdo_errors = []

    def cyclic():
        period = 0.001
        nxt = time.perf_counter()
        n = 0
        while not stop.is_set():
            for s in master.slaves:
                s.output = bytes([n & 0xFF]) * len(s.output)
            master.send_processdata()
            wkc = master.receive_processdata(2000)
            p = phase[0]
            cycles[p] += 1
            if wkc < 0:  # EC_NOFRAME: no reply within SOEM's 2 ms
                lost[p] += 1
                last_lost[0] = time.monotonic()
            elif wkc != expected:
                wkc_errors[p] += 1
            n += 1
            nxt += period
            delay = nxt - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            elif delay < -0.05:
                late[0] += 1
                nxt = time.perf_counter()

    def sdo_traffic():
        slave = master.slaves[0]

        def emergency(_msg):
            sdo["emergencies"] += 1  # phase 2's faults raise them (0xA001 module missing ...)

        # SOEM meets Emergencies while it waits for SDO replies; pysoem hands them here.
        slave.add_emergency_callback(emergency)
        while not stop.is_set():
            try:
                slave.sdo_read(0x1018, 4)
                slave.sdo_read(0x1008, 0)
                slave.sdo_read(0xF050, 0)
                sdo["ok"] += 3
                since_timeout[0] += 1
            except pysoem.WkcError:
                # No reply within SOEM's mailbox timeout: a lost mailbox frame, the same
                # scheduling effect as a lost process-data frame, reported with them.
                sdo_timeouts[phase[0]] += 1
                since_timeout[0] = 0
            except pysoem.PacketError as e:
                # "Unexpected frame returned" right after a timeout or a late frame: a reply
                # SOEM gave up on, or a second copy of one (SOEM retransmits a mailbox write
                # whose reply was late; the slave answers that repeat with the same reply),
                # arrived in place of the next one (SOEM drains one message with a zero
                # timeout before each request). Stale, not wrong. Without such a disturbance
                # in the last second it is a wrong answer.
                if since_timeout[0] < 3 or time.monotonic() - last_lost[0] < 1.0:
                    sdo_stale[phase[0]] += 1
                else:
                    sdo["failed"] += 1
                    sdo_errors.append(f"phase {phase[0]}: {type(e).__name__}: {e}")
                since_timeout[0] += 1
            except (pysoem.SdoError, pysoem.MailboxError) as e:
                # A reply that is wrong (abort, mailbox error): a failure.
                sdo["failed"] += 1
                sdo_errors.append(f"phase {phase[0]}: {type(e).__name__}: {e}")
                since_timeout[0] += 1
            time.sleep(0.005)

    master.always_release_gil = True
    threads = [threading.Thread(target=cyclic), threading.Thread(target=sdo_traffic)]
    for t in threads:
        t.start()
    time.sleep(2.0)  # warm-up: caches, first SDO buffers
    rss_start = rss_kib(args.pid)
    total = args.minutes * 60.0
    t_end = time.monotonic() + total
    t_phase2 = time.monotonic() + total / 2
    faults = 0
    rss_series = [rss_start]  # every 30 s: tells warm-up growth from a slow creep
    next_rss = time.monotonic() + 30.0
    try:
        while time.monotonic() < t_end:
            if time.monotonic() >= next_rss:
                rss_series.append(rss_kib(args.pid))
                next_rss += 30.0
            if phase[0] == 1 and time.monotonic() >= t_phase2:
                phase[0] = 2
            if phase[0] == 2:
                k = faults % 4
                if k == 0:
                    api("/api/rim/unplug", {"rim": 2})
                elif k == 1:
                    api("/api/rim/replug", {"rim": 2})
                elif k == 2:
                    api("/api/fan", {"rim": 1, "zone": "slot_card", "rpm": 900 + 100 * (faults % 7)})
                else:
                    api("/api/cpu_temperature", {"celsius": 40 + faults % 30, "immediate": True})
                faults += 1
            time.sleep(1.0)
        api("/api/rim/replug", {"rim": 2})
    finally:
        stop.set()
        for t in threads:
            t.join()
    rss_end = rss_kib(args.pid)
    master.state = pysoem.INIT_STATE
    master.write_state()
    master.close()

    print(f"soak: {args.minutes} min, {args.slaves} slave(s), expected WKC {expected}")
    for p, name in ((1, "no faults"), (2, f"{faults} faults injected")):
        print(f"  phase {p} ({name}): {cycles[p]} cycles, {wkc_errors[p]} WKC errors, "
              f"{lost[p]} lost frames")
    print(f"  SDO reads: {sdo['ok']} ok, {sdo['failed']} failed, {sdo['emergencies']} "
          f"emergencies received; cycles late by >50 ms: {late[0]}")
    for p in (1, 2):
        print(f"  SDO phase {p}: {sdo_timeouts[p]} timeouts (no reply), {sdo_stale[p]} stale "
              f"replies right after a timeout")
    for line in sdo_errors[:10]:
        print(f"    {line}")
    print(f"  rackcat resident memory: {rss_start} KiB at start, {rss_end} KiB at end")
    rss_series.append(rss_end)
    print("  resident memory every 30 s (KiB): " + " ".join(map(str, rss_series)))
    # The control-API and Emergency paths warm up when phase 2 starts; a leak would keep
    # growing after that, so the last third of the run is the number to watch.
    tail = rss_series[(2 * len(rss_series)) // 3:]
    print(f"  growth over the last third of the run: {tail[-1] - tail[0]} KiB")
    ok = (wkc_errors[1] == 0 and wkc_errors[2] == 0 and sdo["failed"] == 0
          and rss_end <= rss_start + 512)
    print("soak: " + ("ok" if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
