"""What every Python driver shares: its command line, the expectations, and the parts of the
scenario that only need "read an SDO" / "exchange process data" callables from the master."""
import argparse
import struct
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from scenario import (NotOffered, Recorder, get_bits, load, run_isolated,  # noqa: E402,F401
                      set_bits, trigger)

# Working counter of one LRW over a slave with outputs and inputs (ETG.1000.4 LRW: +1 read,
# +2 write).
LRW_WKC_PER_SLAVE = 3


def parse_args():
    p = argparse.ArgumentParser()
    p.add_argument("--iface", required=True)
    p.add_argument("--expect", required=True, help="expectations JSON (scenario.py)")
    p.add_argument("--out", required=True, help="results JSON")
    a = p.parse_args()
    return a, load(a.expect)


def u32(data):
    return struct.unpack("<I", bytes(data)[:4])[0]


def check(cond, text):
    if not cond:
        raise AssertionError(text)


def run_sdo_steps(rec, read, write, read_ca, exp):
    """The SDO steps every SDO-capable driver runs in PREOP: expedited, normal and segmented
    transfers and complete access, through the master's read(index, sub),
    write(index, sub, data) and read_ca(index) (complete access of a whole object)."""
    pre = ("preop",)
    rec.run("sdo_upload_expedited", lambda: check_expedited_uploads(read, exp), pre)
    rec.run("sdo_download_expedited", lambda: check_expedited_download(read, write, exp), pre)
    rec.run("sdo_upload_normal", lambda: check_normal_upload(read, exp), pre)
    rec.run("sdo_download_normal", lambda: check_normal_download(read, write, exp), pre)
    rec.run("sdo_upload_segmented", lambda: check_segmented_upload(read_ca, exp), pre)
    rec.run("complete_access", lambda: check_complete_access(read_ca, exp), pre)


def check_sii_words(words_of, exp):
    """words_of(slave) -> the 64 words 0x00-0x3F as the master read them. Slave 0 compared
    whole; the others without the serial number (words 0x0E-0x0F)."""
    want = exp["sii_words"]
    for i in range(exp["slaves"]):
        got = words_of(i)
        skip = set() if i == 0 else {0x0E, 0x0F}
        bad = [k for k in range(64) if k not in skip and got[k] != want[k]]
        check(not bad, f"slave {i}: SII words differ at {[hex(k) for k in bad[:8]]}: "
                       f"{[hex(got[k]) for k in bad[:8]]} != {[hex(want[k]) for k in bad[:8]]}")
    return f"64 words x {exp['slaves']} slave(s)"


def scan(config_init, n, call="config_init"):
    """The scan step: config_init() up to 20 times, 0.1 s apart, until it finds the rack's n
    slaves (a master may start before every slave of a fresh rackcat answers); fails naming
    the master's call and what it found."""
    found = 0
    for _ in range(20):
        found = config_init()
        if found == n:
            break
        time.sleep(0.1)
    check(found == n, f"{call} found {found} slaves, expected {n}")
    return f"{found} slave(s)"


def check_identity(idents, exp):
    """idents: [(vendor, product, revision)] per slave as the master's scan read the SII."""
    want = tuple(exp["identity"][:3])
    check(len(idents) == exp["slaves"], f"{len(idents)} slaves")
    for i, got in enumerate(idents):
        check(tuple(got) == want, f"slave {i}: identity {[hex(v) for v in got]} != "
                                  f"{[hex(v) for v in want]}")
    return "vendor 0x%08X product 0x%08X revision 0x%08X" % want


def check_expedited_uploads(read, exp):
    """read(index, sub) -> bytes."""
    got = [u32(read(0x1018, k)) for k in (1, 2, 3, 4)]
    check(got == exp["identity"], f"0x1018:01-04 {[hex(v) for v in got]} != "
                                  f"{[hex(v) for v in exp['identity']]}")
    return "0x1018:01-04"


def check_expedited_download(read, write, exp):
    old = read(0x2000, 9)
    check(u32(old) == exp["event_mask"], f"0x2000:09 {old.hex()} before the download")
    write(0x2000, 9, struct.pack("<I", 0x0000FF0F))
    got = read(0x2000, 9)
    write(0x2000, 9, bytes(old))
    check(u32(got) == 0x0000FF0F,
          f"0x2000:09 read back {bytes(got).hex()} after writing 0f ff 00 00")
    check(bytes(read(0x2000, 9)) == bytes(old), "0x2000:09 not restored")
    return "0x2000:09 written, read back, restored"


def check_normal_upload(read, exp):
    got = bytes(read(0x2000, 1)).rstrip(b"\0")
    check(got == exp["part_number"].encode(), f"0x2000:01 {got!r} != {exp['part_number']!r}")
    return f"0x2000:01 = {got.decode()!r}"


def check_normal_download(read, write, exp):
    """0x2000:04 IPv4 address, STRING(16), writable in PRE-OP."""
    old = bytes(read(0x2000, 4))
    new = b"10.20.30.40\0\0\0\0\0"
    write(0x2000, 4, new)
    got = bytes(read(0x2000, 4))
    write(0x2000, 4, old.ljust(16, b"\0"))
    check(got.rstrip(b"\0") == new.rstrip(b"\0"), f"0x2000:04 read back {got!r}")
    restored = bytes(read(0x2000, 4)).rstrip(b"\0")
    check(restored == exp["ipv4_address"].encode(), f"0x2000:04 not restored: {restored!r}")
    return "0x2000:04 (16 bytes) written, read back, restored"


def check_segmented_upload(read_ca, exp):
    """read_ca(index) -> the complete-access image of the object."""
    got = bytes(read_ca(0x2000))
    # subindex 0 in 16 bits (ETG.1000.6 §5.6.2.1.2), then the entries packed: the object's
    # bit size as `rackcat od` gives it
    want_len = exp["ca_2000_bytes"]
    check(len(got) == want_len, f"{len(got)} bytes, expected {want_len}")
    check(got[0] == 15, f"subindex 0 = {got[0]}")
    check(exp["part_number"].encode() in got, "part number not in the image")
    return f"{len(got)} bytes"


def check_complete_access(read_ca, exp):
    for index, key in ((0x1C12, "ca_1c12"), (0x1C13, "ca_1c13"), (0x1018, "ca_1018")):
        got = bytes(read_ca(index)).hex()
        check(got == exp[key], f"0x{index:04X}: {got} != {exp[key]}")
    return "0x1C12, 0x1C13, 0x1018"


def check_od_list(indices, exp):
    got = sorted(indices)
    want = exp["od_indices"]
    missing = sorted(set(want) - set(got))
    extra = sorted(set(got) - set(want))
    check(not missing and not extra and len(got) == len(want),
          f"{len(got)} indices, expected {len(want)}; missing {[hex(i) for i in missing[:6]]}"
          f" extra {[hex(i) for i in extra[:6]]}")
    return f"{len(got)} objects"


def check_descriptions(objects, exp, name_limit=None):
    """objects: {index: (name, {sub: (name, data_type, bit_size)})} as the master read them
    (entries may be given for a subset of objects). name_limit: the master keeps only that
    many characters of a name (SOEM: EC_MAXNAME = 40); longer names must match up to it."""
    bad = []
    cut = 0
    n_entries = 0

    def same(got, want):
        nonlocal cut
        if name_limit and len(want) > name_limit and got == want[:name_limit]:
            cut += 1
            return True
        return got == want

    for key, want in exp["objects"].items():
        index = int(key, 16)
        if index not in objects:
            bad.append(f"{key} missing")
            continue
        name, entries = objects[index]
        if not same(name, want["name"]):
            bad.append(f"{key} name {name!r} != {want['name']!r}")
        for sub, (ename, dtype, bits) in (entries or {}).items():
            w = want["entries"].get(str(sub))
            n_entries += 1
            if w is None:
                # A gap below MaxSubindex (0x1C32/0x1C33 0x0D..0x1F) is described as a reserved
                # entry with no data type and no bits, so a master listing every subindex up to
                # MaxSubindex gets no error; `rackcat od` lists only the entries that exist.
                if (dtype, bits) != (0, 0):
                    bad.append(f"{key}:{sub} not in rackcat od")
            elif not same(ename, w["name"]) or (dtype, bits) != (w["data_type"], w["bit_size"]):
                bad.append(f"{key}:{sub} {(ename, dtype, bits)} != "
                           f"{(w['name'], w['data_type'], w['bit_size'])}")
    check(not bad, f"{len(bad)} differences: {bad[:4]}")
    text = f"{len(objects)} object names, {n_entries} entry descriptions"
    if cut:
        text += f"; {cut} names longer than {name_limit} characters cut by the master"
    return text


def check_sizes(sizes, exp):
    """sizes: [(output_bytes, input_bytes)] per slave."""
    want = ((exp["output_bits"] + 7) // 8, (exp["input_bits"] + 7) // 8)
    for i, got in enumerate(sizes):
        check(tuple(got) == want, f"slave {i}: {got} bytes (out, in), expected {want}")
    return f"{want[0]} output / {want[1]} input bytes per slave"


class LoopbackRun:
    """N cycles with a new output pattern every `hold` cycles on each wired output; the wired
    inputs must show it by the end of the hold. exchange() sends and receives one cycle and
    returns the working counter; outputs(i)/set_outputs(i, bytes)/inputs(i) access the image."""

    def __init__(self, exp, hold=20):
        self.exp = exp
        self.hold = hold
        self.bad_wkc = []
        self.stale = []
        self.seen = 0

    def pattern(self, block, slave, loop, bits):
        return ((block * 0x3B1D + slave * 0x0101 + loop * 0x55) & 0xFFFF) & ((1 << bits) - 1)

    def run(self, exchange, outputs, set_outputs, inputs, expected_wkc, cycles):
        n = self.exp["slaves"]
        period = self.exp["cycle_us"] / 1e6
        next_t = time.monotonic()
        for c in range(cycles):
            block = c // self.hold
            for i in range(n):
                out = outputs(i)
                for k, lp in enumerate(self.exp["loops"]):
                    out = set_bits(out, lp["out_bit"], lp["bits"],
                                   self.pattern(block, i, k, lp["bits"]))
                set_outputs(i, out)
            wkc = exchange()
            if wkc != expected_wkc:
                self.bad_wkc.append((c, wkc))
            elif c % self.hold == self.hold - 1:
                for i in range(n):
                    for k, lp in enumerate(self.exp["loops"]):
                        want = self.pattern(block, i, k, lp["bits"])
                        got = get_bits(inputs(i), lp["in_bit"], lp["bits"])
                        if got != want:
                            self.stale.append((c, i, k, hex(got), hex(want)))
                        else:
                            self.seen += 1
            next_t += period
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)

    def wkc_result(self, expected, cycles):
        check(not self.bad_wkc, f"{len(self.bad_wkc)} of {cycles} cycles with WKC != "
                                f"{expected}: {self.bad_wkc[:6]}")
        return f"{cycles} cycles, WKC {expected}"

    def loopback_result(self):
        check(self.exp["loops"], "no loopback wired in this rack")
        check(not self.stale, f"{len(self.stale)} patterns not seen: {self.stale[:4]}")
        check(self.seen > 0, "no pattern checked")
        return f"{self.seen} patterns seen on {len(self.exp['loops'])} loop(s) per slave"


def while_cycling(cycle, work, period_s=0.001):
    """Runs work() in a thread while the caller keeps the process data flowing (the SM
    watchdog in OP is 100 ms); returns work's result or raises its exception."""
    box = {}

    def target():
        try:
            box["value"] = work()
        except BaseException as e:  # noqa: BLE001
            box["error"] = e

    t = threading.Thread(target=target, daemon=True)
    t.start()
    while t.is_alive():
        cycle()
        time.sleep(period_s)
    if "error" in box:
        raise box["error"]
    return box.get("value")
