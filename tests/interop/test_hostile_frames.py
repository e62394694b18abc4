"""[reliability] Hostile and faulty traffic against the real device, `rackcat run`, over a veth
pair: a raw AF_PACKET socket on the master end crafts frames a real master never sends
(truncated frames, lengths past the frame end, "more follows" running off the end, accesses
crossing the 64 KiB address space, LRW over unmapped logical space, writes to read-only
registers, SII writes without write enable, mailbox floods, repeated mailbox counters, SDO
segments out of order, abandoned SDO transfers). Each gets the answer docs/ESC.md and
docs/COE.md document (ETG.1000.4 §5/§6, ETG.1000.6 §5.6, ESC datasheet section II), and
afterwards the same rackcat process still reaches OP with pysoem and exchanges process data
through the rack's loopback wiring.

Needs root (network namespace, veth, raw sockets); skips with a message otherwise.
"""
import struct
import time

from raw_master import APRD, APWR, LRW, RawMaster, dgram, ecat_datagrams, phys
from rackcat_helpers import (go, loopback_entries, open_master, pysoem, rackcat, read_pdo_map,
                             to_op, wait_loopback)

assert rackcat  # the fixture, imported for pytest

# Registers (ESC datasheet section II; docs/ESC.md).
REG_TYPE, REG_STATION = 0x0000, 0x0010
REG_AL_STATUS, REG_AL_CODE = 0x0130, 0x0134
REG_RX_ERROR, REG_PU_ERROR = 0x0300, 0x030C
REG_SII_CONFIG, REG_SII_CONTROL, REG_SII_ADDRESS, REG_SII_DATA = 0x0500, 0x0502, 0x0504, 0x0508
REG_FMMU, REG_SM = 0x0600, 0x0800
SII_CMD_READ, SII_CMD_WRITE = 0x0100, 0x0200
SII_WRITE_ENABLE_ERROR = 0x4000  # 0x0502 bit 14: write command without write enable
SII_BUSY = 0x8000

# Mailbox / CoE (ETG.1000.4 §5.6, ETG.1000.6 §5.6.2).
MBX_TYPE_COE = 0x03
COE_SDO_REQUEST, COE_SDO_RESPONSE = 2, 3
ABORT_TOGGLE = 0x05030000
# An object larger than the 128-byte mailbox, read by complete access: module 24's AINx16
# (x8 samples) array (docs/MDP.md default rack), 258 bytes.
BIG = 0x6177


def error_counters(raw):
    """(port 0 RX error counter 0x0300, processing unit error counter 0x030C)."""
    wkc, data = raw.aprd(REG_RX_ERROR, 13)
    assert wkc == 1
    return data[0], data[12]


def op_and_process_data(master):
    """The slave still reaches OP with pysoem and exchanges process data: a DO card's output
    word comes back on the DI card wired to it (the rack's loopback wiring)."""
    s = master.slaves[0]
    do, di = loopback_entries(s)
    master.config_map()
    to_op(master)
    for value in (0x5AA5, 0x0001, 0xFFFF, 0x0000):
        assert wait_loopback(master, do, di, value) == value, f"output 0x{value:04X}"
    go(master, pysoem.INIT_STATE)


# --- frames and registers ----------------------------------------------------------------


def test_malformed_frames_and_register_abuse_then_op(rackcat):
    rc = rackcat(pcap=False)
    raw = RawMaster(rc.iface)
    try:
        esc_type = raw.aprd(REG_TYPE, 2)[1]
        assert esc_type[0] == 0x11, esc_type.hex()  # ET1100-class type byte
        # Writing 0x0300 clears every error counter, 0x030C clears on write (docs/ESC.md).
        assert raw.apwr(REG_RX_ERROR, bytes(14)) == 1
        assert error_counters(raw) == (0, 0)
        expected_errors = 0

        def malformed(payload, ecat_len=None, processed=()):
            """Sends a malformed frame: it comes back at its full length with the datagrams
            before the defect processed (`processed`: their working counters), and every
            slave counts it once in 0x0300 and 0x030C."""
            nonlocal expected_errors
            frame = raw.frame(payload, ecat_len)
            reply = raw.exchange(frame)
            assert reply is not None, f"malformed frame not returned: {frame.hex()}"
            assert reply[6] & 0x02, "returned frame lacks the processed mark in the source MAC"
            got = [wkc for _c, _i, wkc, _d in ecat_datagrams(reply)][:len(processed)]
            assert got == list(processed), f"working counters {got}, expected {processed}"
            expected_errors += 1
            assert error_counters(raw) == (expected_errors, expected_errors)
            return reply

        # Cut inside the EtherCAT header: no EtherCAT frame at all, not answered, not counted.
        assert raw.exchange(raw.frame(b"")[:15], timeout_s=0.3) is None
        assert error_counters(raw) == (0, 0)
        # Truncated frame: the datagram header ends after 6 bytes; nothing is processed and the
        # bytes come back as they were.
        full = dgram(APRD, raw.next_idx(), phys(0, REG_TYPE), b"\0\0")
        reply = malformed(full[:6], ecat_len=len(full))
        assert reply[16:] == full[:6]
        # EtherCAT header length (1000) larger than the frame: the complete datagram is still
        # processed (WKC 1, the type register read), the frame counts as an error.
        reply = malformed(dgram(APRD, raw.next_idx(), phys(0, REG_TYPE), b"\0\0"), ecat_len=1000)
        assert ecat_datagrams(reply)[0][3] == esc_type
        # "More follows" set on the last datagram, 3 stray bytes after it: the first datagram
        # is processed, the chain running off the end is an error.
        malformed(dgram(APRD, raw.next_idx(), phys(0, REG_TYPE), b"\0\0", more=True) + b"\1\2\3",
                  processed=(1,))
        # A datagram whose length field (2047) runs past the frame: not processed.
        d = dgram(APWR, raw.next_idx(), phys(0, 0x1000), b"\xEE" * 8, length=2047)
        malformed(d)
        assert raw.aprd(0x1000, 8)[1] != b"\xEE" * 8, "a datagram past the frame end was written"
        # Two good datagrams, then one running past the end: the first two are processed.
        chain = dgram(APRD, raw.next_idx(), phys(0, REG_TYPE), b"\0\0", more=True) + \
            dgram(APRD, raw.next_idx(), phys(0, REG_STATION), b"\0\0", more=True) + \
            dgram(APRD, raw.next_idx(), phys(0, REG_TYPE), b"\0" * 64)[:20]
        malformed(chain, processed=(1, 1))

        # Accesses crossing the end of the 64 KiB address space are ignored: no WKC, data
        # unchanged, memory unchanged. They are not frame errors.
        wkc_before, tail_before = raw.aprd(0xFFF0, 16)
        assert wkc_before == 1
        wkc, data = raw.aprd(0xFFF8, 16, pattern=0x5C)
        assert (wkc, data) == (0, b"\x5C" * 16)
        assert raw.apwr(0xFFFC, b"\xA5" * 8) == 0
        assert raw.aprd(0xFFF0, 16) == (1, tail_before)
        assert raw.datagram(APRD, phys(0, 0xFFFF), b"\0\0")[0] == 0
        assert error_counters(raw) == (expected_errors, expected_errors)

        # Writes to read-only registers count (WKC 1, as on an ESC) and change nothing.
        wkc, ident = raw.aprd(REG_TYPE, 10)
        assert wkc == 1
        assert raw.apwr(REG_TYPE, b"\xFF" * 10) == 1
        assert raw.aprd(REG_TYPE, 10) == (1, ident)
        al = raw.aprd(REG_AL_STATUS, 6)[1]
        assert al[0] & 0x0F == 0x01, f"AL status 0x{al[0]:02X}, expected INIT"
        assert raw.apwr(REG_AL_STATUS, b"\x08\x00") == 1  # AL status is read-only: not OP
        assert raw.apwr(REG_AL_CODE, b"\x1B\x00") == 1
        assert raw.aprd(REG_AL_STATUS, 6) == (1, al)

        # SII write without write enable (0x0502 bit 0): error bit 14, EEPROM unchanged.
        assert raw.apwr(REG_SII_CONFIG, b"\0\0") == 1  # EEPROM owned by EtherCAT

        def sii_read(word):
            assert raw.apwr(REG_SII_CONTROL, struct.pack("<HI", SII_CMD_READ, word)) == 1
            status = raw.reg16(REG_SII_CONTROL)
            assert status & (SII_BUSY | 0x6000) == 0, f"SII read status 0x{status:04X}"
            return raw.aprd(REG_SII_DATA, 4)[1][:2]

        vendor_lo = sii_read(0x0008)
        assert raw.apwr(REG_SII_DATA, b"\x55\xAA") == 1
        assert raw.apwr(REG_SII_CONTROL, struct.pack("<HI", SII_CMD_WRITE, 0x0008)) == 1
        status = raw.reg16(REG_SII_CONTROL)
        assert status & SII_WRITE_ENABLE_ERROR, f"SII status 0x{status:04X}: no write-enable error"
        assert sii_read(0x0008) == vendor_lo

        # LRW over logical space no FMMU maps (INIT: none): no WKC, data unchanged.
        idx = raw.next_idx()
        reply = raw.exchange(raw.frame(dgram(LRW, idx, 0x40000000, b"\x77" * 32)))
        assert ecat_datagrams(reply)[0][2:] == (0, b"\x77" * 32)
    finally:
        raw.close()

    master = open_master(rc.iface, 1)
    try:
        # In SAFEOP, with pysoem's FMMUs: an LRW far from them gets no WKC; one spanning the
        # whole mapped range plus unmapped margins gets WKC 3 (read + write FMMU) and leaves
        # the margins as they were.
        s = master.slaves[0]
        pdo = read_pdo_map(s)
        master.config_map()
        go(master, pysoem.SAFEOP_STATE)
        raw = RawMaster(rc.iface)
        try:
            station = raw.reg16(REG_STATION)
            wkc, fmmus = raw.fprd(station, REG_FMMU, 16 * 4)
            assert wkc == 1
            spans = []
            for k in range(4):
                start, length, _sb, _eb, _phys, _pb, typ, act = struct.unpack_from(
                    "<IHBBHBBB", fmmus, 16 * k)
                if act & 1 and typ in (1, 2, 3):
                    spans.append((start, start + length, typ))
            assert {t for _s, _e, t in spans} >= {1, 2}, f"FMMUs {spans}"
            lo, hi = min(s_ for s_, _e, _t in spans), max(e for _s, e, _t in spans)
            front = min(8, lo)  # unmapped bytes before the first FMMU (if there is room)
            data = bytes([0xC3]) * (front + hi - lo + 16)
            reply = raw.exchange(raw.frame(dgram(LRW, raw.next_idx(), lo - front, data)))
            [(_c, _i, wkc, back)] = ecat_datagrams(reply)
            assert wkc == 3, f"LRW over the mapped range: WKC {wkc}"
            assert back[:front] == data[:front]
            assert back[front + hi - lo:] == data[front + hi - lo:], "unmapped bytes changed"
            reply = raw.exchange(raw.frame(dgram(LRW, raw.next_idx(), hi + 0x1000, data)))
            assert ecat_datagrams(reply)[0][2:] == (0, data)
        finally:
            raw.close()
        assert pdo.output_bits and pdo.input_bits
        go(master, pysoem.PREOP_STATE)
        go(master, pysoem.INIT_STATE)
        master.config_init()
        op_and_process_data(master)
    finally:
        master.close()
    rc.stop()


# --- mailbox ------------------------------------------------------------------------------


class Mailbox:
    """SM0 (master -> slave) and SM1 (slave -> master) of the slave at `station`, written and
    read with FPWR/FPRD the way a master does (ETG.1000.4 §5.6)."""

    def __init__(self, raw, station):
        self.raw, self.station = raw, station
        wkc, sms = raw.fprd(station, REG_SM, 16)
        assert wkc == 1
        self.out_start, self.out_len = struct.unpack_from("<HH", sms, 0)
        self.in_start, self.in_len = struct.unpack_from("<HH", sms, 8)
        assert sms[6] & 1 and sms[14] & 1, "mailbox SyncManagers not active in PREOP"

    def request(self, counter, coe_service, body):
        """Mailbox header (length, address 0, channel/priority 0, type CoE | counter), CoE
        header (number 0, service), body; padded to the SM0 length."""
        payload = struct.pack("<H", coe_service << 12) + body
        msg = struct.pack("<HHBB", len(payload), 0, 0, MBX_TYPE_COE | (counter << 4)) + payload
        return msg.ljust(self.out_len, b"\0")

    def write(self, msg):
        return self.raw.fpwr(self.station, self.out_start, msg)

    def sm_status(self, sm):
        wkc, data = self.raw.fprd(self.station, REG_SM + 8 * sm + 5, 1)
        assert wkc == 1
        return data[0]

    def wait_full(self, sm, timeout_s=2.0):
        deadline = time.monotonic() + timeout_s
        while not self.sm_status(sm) & 0x08:
            assert time.monotonic() < deadline, f"SM{sm} never became full"
            time.sleep(0.002)

    def read(self):
        """(WKC, bytes) of one read of the whole SM1 (WKC 0 while it is empty)."""
        return self.raw.fprd(self.station, self.in_start, self.in_len)

    def reply(self, timeout_s=2.0):
        deadline = time.monotonic() + timeout_s
        while True:
            wkc, data = self.read()
            if wkc == 1:
                return data
            assert time.monotonic() < deadline, "no mailbox reply"
            time.sleep(0.002)

    def drain(self):
        """Reads pending messages (emergencies) until SM1 stays empty for 50 ms."""
        quiet = time.monotonic() + 0.05
        while time.monotonic() < quiet:
            if self.read()[0] == 1:
                quiet = time.monotonic() + 0.05

    def sdo(self, counter, command, index, sub, data=b"\0\0\0\0"):
        """Sends one SDO request (command, index, subindex, 4 data bytes) and returns the SDO
        part of the answer: (command, index, sub, 4 data bytes, mailbox counter, reply)."""
        return self.sdo_raw(counter, struct.pack("<BHB", command, index, sub) + data)

    def segment(self, counter, command, seven=bytes(7)):
        """A segment request: command byte, then 7 bytes of data (ETG.1000.6 §5.6.2.3)."""
        return self.sdo_raw(counter, bytes([command]) + seven)

    def sdo_raw(self, counter, sdo):
        assert self.write(self.request(counter, COE_SDO_REQUEST, sdo)) == 1
        rep = self.reply()
        assert rep[5] & 0x0F == MBX_TYPE_COE, f"not a CoE reply: {rep[:16].hex()}"
        cmd, idx, sb = struct.unpack_from("<BHB", rep, 8)
        # Answers are SDO responses; an abort travels as an SDO request (ETG.1000.6 §5.6.2.7).
        service = COE_SDO_REQUEST if cmd == 0x80 else COE_SDO_RESPONSE
        assert struct.unpack_from("<H", rep, 6)[0] >> 12 == service, rep[:16].hex()
        return cmd, idx, sb, rep[12:16], (rep[5] >> 4) & 7, rep


def test_mailbox_flood_counters_toggle_and_abandoned_transfers_then_op(rackcat):
    rc = rackcat(pcap=False)
    master = open_master(rc.iface, 1)  # PREOP: SM0/SM1 configured by SOEM
    try:
        s = master.slaves[0]
        product = struct.unpack("<I", s.sdo_read(0x1018, 2))[0]
        assign_count = s.sdo_read(0x1C12, 0)
        raw = RawMaster(rc.iface)
        try:
            station = raw.reg16(REG_STATION)
            mbx = Mailbox(raw, station)
            mbx.drain()

            # Flood: request 1 is answered into SM1 (left unread); request 2 fills SM0 and
            # waits there, since SM1 is full; request 3, written while SM0 is full, gets WKC 0
            # and is never executed (docs/ESC.md "Mailbox mode").
            def up(counter, sub):
                return mbx.request(counter, COE_SDO_REQUEST,
                                   struct.pack("<BHB", 0x40, 0x1018, sub) + bytes(4))
            assert mbx.write(up(1, 1)) == 1
            mbx.wait_full(1)
            assert mbx.write(up(2, 2)) == 1
            assert mbx.sm_status(0) & 0x08, "SM0 not full while SM1 holds a reply"
            assert mbx.write(up(3, 4)) == 0, "write into a full mailbox was accepted"
            assert mbx.write(up(4, 3)) == 0
            first = mbx.reply()
            second = mbx.reply()
            assert struct.unpack_from("<BHB", first, 8) == (0x43, 0x1018, 1)
            assert struct.unpack_from("<BHB", second, 8) == (0x43, 0x1018, 2)
            assert struct.unpack_from("<I", second, 12)[0] == product
            time.sleep(0.05)
            assert mbx.read()[0] == 0, "a request written into a full mailbox was executed"

            # Repeated mailbox counter: the same non-zero counter and bytes again is the master
            # retransmitting a write (ETG.1000.4 §5.6 "double write"): dropped, no second
            # reply, nothing executes twice (docs/COE.md "Mailbox counter").
            a = mbx.sdo(5, 0x40, 0x1018, 2)
            body = struct.pack("<BHB", 0x40, 0x1018, 2) + bytes(4)
            again = mbx.request(5, COE_SDO_REQUEST, body)
            assert mbx.write(again) == 1
            time.sleep(0.05)
            assert mbx.read()[0] == 0, "a repeated mailbox write was answered a second time"
            c = mbx.sdo(6, 0x40, 0x1018, 2)
            assert c[4] != a[4], "a new request got the previous reply's mailbox counter"
            assert struct.unpack("<I", c[3])[0] == product

            # SDO segments out of order: a segmented upload (complete access of 0x6177, the
            # 258-byte AINx16 x8-samples array of module 24, larger than the mailbox), then an
            # upload segment request with toggle 1 where 0 is due -> abort 0x05030000.
            cmd, _i, _s, size, *_ = mbx.sdo(7, 0x50, BIG, 0)
            assert cmd == 0x51, f"0x{BIG:04X} complete-access upload answered 0x{cmd:02X}"
            assert struct.unpack("<I", size)[0] > mbx.in_len - 16, "upload not segmented"
            cmd, index, sub, data, *_ = mbx.segment(1, 0x70)
            assert cmd == 0x80, f"toggle error answered with 0x{cmd:02X}, not an abort"
            assert (index, sub) == (BIG, 0)
            assert struct.unpack("<I", data)[0] == ABORT_TOGGLE

            # A segmented download with its segments out of order: initiate (complete access
            # 0x1C12, 12 bytes), then a segment with toggle 1 first -> abort 0x05030000, the
            # object unchanged.
            cmd, *_ = mbx.sdo(2, 0x31, 0x1C12, 0, struct.pack("<I", 12))
            assert cmd == 0x70, f"download initiate answered 0x{cmd:02X}"  # 0x60 | CA
            cmd, index, sub, data, *_ = mbx.segment(3, 0x10, b"\x05\0\0\x16\x01\x16\x02")
            assert (cmd, index, sub) == (0x80, 0x1C12, 0)
            assert struct.unpack("<I", data)[0] == ABORT_TOGGLE

            # Abandoned half way: an upload after its first segment, a download after its
            # first segment. A new initiate drops them; a download is committed only at its
            # last segment, so the object is unchanged.
            assert mbx.sdo(4, 0x50, BIG, 0)[0] == 0x51
            assert mbx.segment(5, 0x60)[0] & 0xE0 == 0x00  # upload segment response
            assert mbx.sdo(6, 0x31, 0x1C12, 0, struct.pack("<I", 12))[0] == 0x70
            assert mbx.segment(7, 0x00, b"\x05\0\0\x16\x01\x16\x02")[0] == 0x20
            got = mbx.sdo(1, 0x40, 0x1018, 2)
            assert (got[0], struct.unpack("<I", got[3])[0]) == (0x43, product)
        finally:
            raw.close()
        # pysoem continues on the same slave: the mapping is untouched, OP and process data.
        assert s.sdo_read(0x1C12, 0) == assign_count
        assert struct.unpack("<I", s.sdo_read(0x1018, 2))[0] == product
        op_and_process_data(master)
    finally:
        master.close()
    rc.stop()
