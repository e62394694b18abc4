"""The conformance scenario through ebpfcat (a Python master, asyncio; its fast path runs the
cyclic exchange in an XDP/eBPF program, its plain path - used here - in Python over an
AF_PACKET socket).

Offered: scan (APRD count), addressing, the whole SII (its EEPROM reader), SM setup from the
SII, states, SDO upload/download (expedited, normal, segmented; complete access starting at
subindex 1), SDO information (OD list, object and entry descriptions), the PDO assignment
read over SDO, FMMU mapping and raw datagrams (LRW). Not offered: distributed clocks,
Emergencies (a message it did not ask for is logged and dropped), abort codes (an abort is an
EtherCatError with the CoE service, without the code).
"""
import asyncio
import struct
import time

from ebpfcat.ethercat import ECCmd, EtherCat, EtherCatError, MachineState, Packet, Terminal

from common import (LoopbackRun, NotOffered, Recorder, check, check_descriptions,
                    check_expedited_uploads, check_identity, check_normal_upload,
                    check_od_list, check_sii_words, check_sizes, parse_args)

LOGICAL_BASE = 0x10000


def version():
    from importlib.metadata import version as v
    return f"ebpfcat {v('ebpfcat')}"


def main():
    args, exp = parse_args()
    rec = Recorder(args.out, "ebpfcat", version())
    asyncio.run(scenario(args.iface, rec, exp))


async def arun(rec, step, coro_fn, requires=()):
    """rec.run for a coroutine function (asyncio)."""
    box = {}

    async def body():
        box["detail"] = await coro_fn()

    missing = [r for r in requires if not rec.passed(r)]
    if missing:
        return rec.run(step, lambda: None, requires)
    t0 = time.monotonic()
    try:
        await asyncio.wait_for(body(), 120)
    except Exception as e:  # noqa: BLE001 - handed to the recorder below
        err = e

        def fail():
            raise err
        return rec.run(step, fail)
    took = time.monotonic() - t0
    return rec.run(step, lambda: (box["detail"] or "") + f" [{took:.1f} s]")


async def scenario(iface, rec, exp):
    n = exp["slaves"]
    ec = EtherCat(iface)
    await ec.connect()
    terms = []

    async def scan():
        count = await ec.count()
        check(count == n, f"APRD 0x0010 counted {count} slaves, expected {n}")
        for i in range(count):
            t = Terminal(ec)
            await t.initialize(-i, 0x1001 + i)  # addresses, SII read, SMs from the SII, INIT
            terms.append(t)
        return f"{count} slave(s), SII read and SMs set by Terminal.initialize"

    if not await arun(rec, "scan", scan):
        return
    rec.run("identity", lambda: check_identity(
        [(t.vendorId, t.productCode, t.revisionNo) for t in terms], exp))

    words = {}

    async def sii():
        for i in range(n):
            w = []
            for addr in range(0, 64, 2):
                v = await ec.eeprom_read(-i, addr)
                w += [v & 0xFFFF, v >> 16]
            words[i] = w
        return check_sii_words(lambda i: words[i], exp)

    await arun(rec, "sii", sii)

    async def go(state):
        for t in terms:
            await t.to_operational(state)
        for t in terms:
            got, error, status = await t.get_state()
            check(got is state and not error, f"{t.position:#06x}: {got} error {error} "
                                              f"code 0x{status:04X}")

    await arun(rec, "preop", lambda: go(MachineState.PRE_OPERATIONAL))
    t0 = terms[0]
    pre = ("preop",)
    # the check_* helpers are synchronous: read/write everything they need first
    cache = {}

    async def fetch(keys):
        for index, sub in keys:
            cache[(index, sub)] = await t0.sdo_read(index, sub)

    def read(index, sub):
        return cache[(index, sub)]

    async def uploads():
        await fetch([(0x1018, k) for k in (1, 2, 3, 4)])
        return check_expedited_uploads(read, exp)

    await arun(rec, "sdo_upload_expedited", uploads, pre)

    async def download_expedited():
        old = await t0.sdo_read(0x2000, 9)
        await t0.sdo_write(struct.pack("<I", 0x0000FF0F), 0x2000, 9)
        got = await t0.sdo_read(0x2000, 9)
        await t0.sdo_write(old, 0x2000, 9)
        back = await t0.sdo_read(0x2000, 9)
        check(got == struct.pack("<I", 0x0000FF0F), f"read back {got.hex()}")
        check(back == old, "not restored")
        return "0x2000:09 written, read back, restored"

    await arun(rec, "sdo_download_expedited", download_expedited, pre)

    async def normal_upload():
        await fetch([(0x2000, 1)])
        return check_normal_upload(read, exp)

    await arun(rec, "sdo_upload_normal", normal_upload, pre)

    async def normal_download():
        old = await t0.sdo_read(0x2000, 4)
        new = b"10.20.30.40\0\0\0\0\0"
        await t0.sdo_write(new, 0x2000, 4)
        got = await t0.sdo_read(0x2000, 4)
        await t0.sdo_write(old.ljust(16, b"\0"), 0x2000, 4)
        back = (await t0.sdo_read(0x2000, 4)).rstrip(b"\0")
        check(got.rstrip(b"\0") == new.rstrip(b"\0"), f"read back {got!r}")
        check(back == exp["ipv4_address"].encode(), f"not restored: {back!r}")
        return "0x2000:04 (16 bytes) written, read back, restored"

    await arun(rec, "sdo_download_normal", normal_download, pre)

    async def segmented():
        # complete access from subindex 1 (ebpfcat's only form): subindex 0 and its padding
        # are not in the image (ETG.1000.6 §5.6.2.1.2)
        got = await t0.sdo_read(0x2000)
        want = exp["ca_2000_bytes"] - 2
        check(len(got) == want, f"{len(got)} bytes, expected {want}")
        check(got.startswith(exp["part_number"].encode()), f"starts {got[:16]!r}")
        return f"{len(got)} bytes from subindex 1"

    await arun(rec, "sdo_upload_segmented", segmented, pre)

    async def complete():
        for index, key in ((0x1C12, "ca_1c12"), (0x1C13, "ca_1c13"), (0x1018, "ca_1018")):
            got = (await t0.sdo_read(index)).hex()
            want = exp[key][4:]  # without subindex 0 (16 bits)
            check(got == want, f"0x{index:04X} from subindex 1: {got} != {want}")
        return "0x1C12, 0x1C13, 0x1018 from subindex 1"

    await arun(rec, "complete_access", complete, pre)

    async def aborts():
        try:
            await t0.sdo_read(0x1234, 0)
        except EtherCatError as e:
            raise NotOffered(f"an abort arrives as EtherCatError without its code: {e}")
        raise AssertionError("0x1234:00 read without an abort")

    await arun(rec, "sdo_abort", aborts, pre)
    od = {}

    async def od_list():
        got = await t0.read_ODlist()  # list, then every object and entry description
        for index, o in got.items():
            entries = {}
            entries = {k: (e.name, e.dataTypeOriginal, e.bitLength)
                       for k, e in o.entries.items()}  # read_ODlist reads them all
            od[index] = (o.name, entries)
        return check_od_list(list(od), exp)

    await arun(rec, "sdo_info_list", od_list, pre)
    rec.run("sdo_info_desc", lambda: check_descriptions(od, exp), ("sdo_info_list",))

    async def mapping():
        got = []
        for t in terms:
            out_bits, in_bits = await t.parse_pdos()  # 0x1C12/0x1C13 and the mapping objects
            got.append(((out_bits + 7) // 8, (in_bits + 7) // 8))
        return check_sizes(got, exp)

    await arun(rec, "pdo_sizes", mapping, pre)
    # ebpfcat maps its FMMUs with the SyncM lengths of the SII, not with parse_pdos
    sizes = [(t.pdo_out_sz, t.pdo_in_sz) for t in terms]
    rec.not_offered("dc_sync0", "no distributed clocks in ebpfcat")
    fmmus = []
    layout = []  # (logical address of the outputs, out bytes, in bytes) per slave

    async def safeop():
        addr = LOGICAL_BASE
        for t, (out_b, in_b) in zip(terms, sizes):
            await t.write_pdo_sm()
            for write, size in ((True, out_b), (False, in_b)):
                cm = t.map_fmmu(addr, write)
                await cm.__aenter__()
                fmmus.append(cm)
                addr += size
            layout.append((addr - out_b - in_b, out_b, in_b))
        await go(MachineState.SAFE_OPERATIONAL)
        check(sizes == [((exp["output_bits"] + 7) // 8, (exp["input_bits"] + 7) // 8)] * n,
              f"SII SyncM lengths {sizes[:2]} differ from the mapping")
        return "FMMUs mapped with Terminal.map_fmmu, SM lengths from the SII = the mapping"

    await arun(rec, "safeop", safeop, pre)
    image = bytearray(sum(o + i for _, o, i in layout))
    # ebpfcat's packets are at most 1500 bytes: the image goes in LRW datagrams of CHUNK bytes
    CHUNK = 1400

    def expected_wkc():
        """Per datagram, per slave: +2 when it covers the slave's outputs (FMMU write), +1
        when it covers its inputs (FMMU read) - ETG.1000.4 LRW working counter."""
        total = 0
        for start in range(0, len(image), CHUNK):
            end = min(start + CHUNK, len(image))
            for base, out_b, in_b in layout:
                o0 = base - LOGICAL_BASE
                if out_b and o0 < end and o0 + out_b > start:
                    total += 2
                if in_b and o0 + out_b < end and o0 + out_b + in_b > start:
                    total += 1
        return total

    async def exchange():
        wkc = 0
        for start in range(0, len(image), CHUNK):
            chunk = bytes(image[start:start + CHUNK])
            p = Packet()
            s0_, s1_ = p.append(ECCmd.LRW, chunk, 0, LOGICAL_BASE + start)
            data = await ec.roundtrip_packet(p)
            image[start:start + len(chunk)] = data[s0_:s1_]
            wkc += struct.unpack_from("<H", data, s1_)[0]
        return wkc

    async def op():
        await exchange()
        for t in terms:
            await t.ec.roundtrip(ECCmd.FPWR, t.position, 0x0120, "H", 8)
        for _ in range(300):
            await exchange()
            states = [(await t.get_state())[0] for t in terms]
            if all(s is MachineState.OPERATIONAL for s in states):
                return "OP with LRW cycles while waiting"
        raise AssertionError(f"states {states}")

    await arun(rec, "op", op, ("safeop",))
    run = LoopbackRun(exp)

    async def cycles():
        expected = expected_wkc()
        # LoopbackRun is synchronous: one exchange per call through the running loop
        bad, stale, seen = [], [], 0
        hold = run.hold
        for c in range(exp["cycles"]):
            block = c // hold
            for i, (base, out_b, in_b) in enumerate(layout):
                off = base - LOGICAL_BASE
                out = bytes(image[off:off + out_b])
                for k, lp in enumerate(exp["loops"]):
                    out = _set(out, lp, run.pattern(block, i, k, lp["bits"]))
                image[off:off + out_b] = out
            wkc = await exchange()
            if wkc != expected:
                bad.append((c, wkc))
            elif c % hold == hold - 1:
                for i, (base, out_b, in_b) in enumerate(layout):
                    first = base - LOGICAL_BASE + out_b
                    ins = bytes(image[first:first + in_b])
                    for k, lp in enumerate(exp["loops"]):
                        want = run.pattern(block, i, k, lp["bits"])
                        got = _get(ins, lp)
                        if got != want:
                            stale.append((c, i, k, hex(got), hex(want)))
                        else:
                            seen += 1
            await asyncio.sleep(exp["cycle_us"] / 1e6)
        run.bad_wkc, run.stale, run.seen = bad, stale, seen
        return run.wkc_result(expected, exp["cycles"])

    await arun(rec, "cycles", cycles, ("op",))
    rec.run("loopback", run.loopback_result, ("cycles",))
    rec.not_offered("emergency", "ebpfcat logs and drops mailbox messages it did not ask for")

    async def back_to_init():
        for state in (4, 2, 1):
            for t in terms:
                await t.ec.roundtrip(ECCmd.FPWR, t.position, 0x0120, "H", state)
            for _ in range(200):
                await exchange()
                states = [(await t.get_state()) for t in terms]
                if all(s[0].value == state and not s[1] for s in states):
                    break
            else:
                raise AssertionError(f"state {state} not reached: {states[:3]}")
        return "OP -> SAFE-OP -> PRE-OP -> INIT"

    await arun(rec, "init", back_to_init, ("scan",))


def _set(data, lp, value):
    from common import set_bits
    return set_bits(data, lp["out_bit"], lp["bits"], value)


def _get(data, lp):
    from common import get_bits
    return get_bits(data, lp["in_bit"], lp["bits"])


if __name__ == "__main__":
    main()
