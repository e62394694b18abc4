"""[modules] Slot-card behaviour seen by a real master (pysoem) on the wire: digital outputs
through the rack's loopback wiring, safe states when leaving OP, a RIM unplugged through the
control API (exception tree, CoE emergency, exception reset) and UART bytes from a
pseudo-terminal arriving in the Rx data object and the status word.
"""
import os
import struct
import time

from rackcat_helpers import (DI_LOOPBACK_MODULE, DO_MODULE, EXCEPTION_RESET, UART_MODULE,
                             check_capture, cycle, get_bits, go, open_master, pysoem, rackcat,
                             loopback_entries, rack_with_master, read_pdo_map, run_cycles,
                             set_bits, to_op, wait_loopback, wait_watchdog_safeop)

assert rackcat  # the fixture, imported for pytest


def u32(slave, index, sub):
    return struct.unpack("<I", slave.sdo_read(index, sub))[0]



def test_outputs_loop_back_and_take_safe_state_leaving_op(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        do, di = loopback_entries(s)
        master.config_map()
        to_op(master)
        for value in (0x0001, 0x8000, 0xA5C3, 0xFFFF, 0x0000, 0xF0F0):
            assert wait_loopback(master, do, di, value) == value, f"output 0x{value:04X}"
        # Safe state of the CDO-10 (0x4nn0, guide Table 7), set in OP: channels 0..3 take the
        # value 0b0101, channels 4..7 hold, channels 8..15 are not enabled (de-energised).
        safe = 0x4000 + (DO_MODULE - 1) * 0x10
        s.sdo_write(safe, 1, struct.pack("<H", 0x00FF))  # enable
        cycle(master)
        s.sdo_write(safe, 2, struct.pack("<H", 0x000F))  # action: 1 = set value, 0 = hold
        cycle(master)
        s.sdo_write(safe, 3, struct.pack("<H", 0x0005))  # value
        assert wait_loopback(master, do, di, 0xF0F0) == 0xF0F0
        # Leave OP: outputs (current 0xF0F0) -> 0b0101 | hold 0xF0 | 0 = 0x00F5.
        go(master, pysoem.SAFEOP_STATE)
        got = None
        for _ in range(100):
            cycle(master)  # inputs are still exchanged in SAFEOP
            got = get_bits(s.input, di)
            if got == 0x00F5:
                break
            time.sleep(0.001)
        assert got == 0x00F5, f"loopback input in SAFEOP 0x{got:04X}, expected 0x00F5"
        # What the master writes in SAFEOP does not reach the outputs.
        s.output = set_bits(s.output, do, 0x1234)
        run_cycles(master, 50)
        assert get_bits(s.input, di) == 0x00F5
        go(master, pysoem.INIT_STATE)


class Emergencies:
    def __init__(self):
        self.seen = []

    @classmethod
    def on(cls, slave):
        """A new record of the emergencies `slave` sends from now on."""
        emcy = cls()
        slave.add_emergency_callback(emcy)
        return emcy

    def __call__(self, emcy):
        self.seen.append((emcy.error_code, emcy.error_reg, emcy.b1, emcy.w1, emcy.w2))

    def wait(self, slave, code, timeout_s=3.0):
        """Polls the mailbox (SOEM picks emergencies up while it waits for mailbox replies)
        until an emergency with `code` arrived."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if any(e[0] == code for e in self.seen):
                return [e for e in self.seen if e[0] == code]
            slave.sdo_read(0x1018, 1)
            time.sleep(0.01)
        raise AssertionError(f"no emergency 0x{code:04X}; got {self.seen}")


def test_rim_unplug_exception_tree_emergency_and_reset(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        emcy = Emergencies.on(s)
        rim2 = 0x2021  # 0x2rr1, rr = 2
        # All online: RIM state bits 1..0 = 2 (ONLINE, guide Table 16), nothing active.
        assert u32(s, rim2, 8) == 0x00000002
        assert u32(s, 0xF388, 1) == 0 and s.sdo_read(0xF380, 0) == b"\x00"
        assert s.sdo_read(0xF390, 0) == b"\x00"

        rc.cli("unplug", "--rim", 2)
        # RIM 2 offline: state 0, the latched "state error" bit 3 (ONLINE -> OFFLINE).
        assert u32(s, rim2, 8) == 0x00000008
        # Global manufacturer error details: bit rr for RIM rr (guide Table 20).
        assert u32(s, 0xF388, 1) == 1 << 2
        # Summary: bit 3 manufacturer error, active and latched (guide Table 14).
        assert s.sdo_read(0xF380, 0) == b"\x08"
        assert s.sdo_read(0xF390, 0) == b"\x08"
        # RIM 1 is untouched.
        assert u32(s, 0x2011, 8) == 0x00000002
        got = emcy.wait(s, 0xA001)  # module missing (docs/MODULES.md, events.hpp)
        code, reg, b1, w1, w2 = got[0]
        assert reg & 0x01, f"error register 0x{reg:02X} without the generic error bit"
        assert b1 == 2, f"emergency names RIM {b1}, expected 2"

        rc.cli("replug", "--rim", 2)
        # Online again; the latched bits stay until the exception reset.
        assert u32(s, rim2, 8) == 0x0000000A
        assert u32(s, 0xF388, 1) == 0
        assert s.sdo_read(0xF380, 0) == b"\x00"
        assert s.sdo_read(0xF390, 0) == b"\x08"
        # 0xFBF1 Exception Reset, the guide's byte sequence: latched bits whose cause is gone
        # clear.
        s.sdo_write(0xFBF1, 1, EXCEPTION_RESET)
        assert u32(s, rim2, 8) == 0x00000002
        assert s.sdo_read(0xF390, 0) == b"\x00"
        # The control API sees the same tree.
        tree = rc.cli("exceptions")
        assert tree["F380"] == "0x00000000" and tree["F390"] == "0x00000000", tree
        go(master, pysoem.INIT_STATE)
    # Wireshark decodes the emergency mailbox messages like every other frame.
    check_capture(rc.pcap)


def test_uart_bytes_from_the_pty_arrive_in_rx_object_and_status(rackcat):
    rc = rackcat()
    info = rc.module(UART_MODULE)
    pty = info["uart"][0]["pty"]
    assert pty.startswith("/dev/pts/"), info["uart"][0]
    assert pty in rc.log(), "the pseudo-terminal path is printed at start"
    master = open_master(rc.iface, 1)
    fd = os.open(pty, os.O_RDWR | os.O_NOCTTY)
    try:
        s = master.slaves[0]
        nn = (UART_MODULE - 1) * 0x10
        status_obj, rx_obj = 0x5000 + nn + 6, 0x5000 + nn + 0xB
        pdo = read_pdo_map(s)
        status_pdo = pdo.find(0x6000 + nn + 0xA, 1, "in")  # 0x6nnA:01 status channel 0
        master.config_map()
        to_op(master)
        assert get_bits(s.input, status_pdo) & 0x0FFF == 0
        message = b"rackcat UART\r\n"
        os.write(fd, message)
        # 9600 baud, 8N1: 14 characters take about 15 ms on the line.
        want = len(message)

        def available(_):
            return get_bits(s.input, status_pdo) & 0x0FFF == want

        run_cycles(master, 1000, until=available)
        status = get_bits(s.input, status_pdo)
        assert status & 0x0FFF == want, f"status word 0x{status:04X} in the process data"
        assert struct.unpack("<H", s.sdo_read(status_obj, 5))[0] & 0x0FFF == want
        # Reading 0x5nnB:00 moves the received bytes into :01..n.
        n = s.sdo_read(rx_obj, 0)[0]
        assert n == want
        got = b""
        for k in range(1, n + 1):
            got += s.sdo_read(rx_obj, k)
            cycle(master)  # keep the SM2 watchdog fed between mailbox transfers
        assert got == message
        run_cycles(master, 50)
        assert get_bits(s.input, status_pdo) & 0x0FFF == 0, "the Rx FIFO was emptied"
        go(master, pysoem.SAFEOP_STATE)
        go(master, pysoem.INIT_STATE)
    finally:
        os.close(fd)
        master.close()
    rc.stop()


def ack_error_and_init(master, state):
    """Acknowledges the error flag (AL control bit 4) the way SOEM masters do, then INIT."""
    s = master.slaves[0]
    s.state = state | pysoem.STATE_ACK
    s.write_state()
    go(master, pysoem.INIT_STATE)


def driven_word(rc, master, module):
    """The levels a digital output card drives now, from the control API (bit n = channel n)."""
    m = rc.cli_while_cycling(master, "list", "--module", module, "--json")
    return sum(int(o["driven"]) << o["channel"] for o in m["outputs"])


def test_rim_lost_in_op_with_detect_modules_override_0_goes_to_safeop(rackcat):
    """Guide Table 23, Detect Modules Override 0: a RIM with mapped process data going offline
    in OP takes the device to SAFEOP (error flag, AL status code 0x0070) and every output to
    its safe state; the master also gets the module-missing emergency."""
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        emcy = Emergencies.on(s)
        s.sdo_write(0x2000, 0x0B, b"\x00")  # Detect Modules Override = 0 (PREOP)
        pdo = read_pdo_map(s)
        do = pdo.find(0x7000 + (DO_MODULE - 1) * 0x10, 1, "out")
        di = pdo.find(0x6000 + (DI_LOOPBACK_MODULE - 1) * 0x10, 1, "in")
        do_rim2 = pdo.find(0x7000 + (26 - 1) * 0x10, 1, "out")  # RIM 2 slot 7 CDO-10
        master.config_map()
        to_op(master)
        s.output = set_bits(set_bits(s.output, do, 0x0FF0), do_rim2, 0x00FF)
        assert wait_loopback(master, do, di, 0x0FF0) == 0x0FF0
        assert driven_word(rc, master, 26) == 0x00FF

        rc.cli_while_cycling(master, "unplug", "--rim", 2)
        run_cycles(master, 50)
        master.read_state()
        assert s.state == pysoem.SAFEOP_STATE | pysoem.STATE_ERROR, hex(s.state)
        assert s.al_status == 0x0070, hex(s.al_status)
        # Safe state (0x4nn0 defaults: not enabled -> de-energised) on both RIMs.
        assert get_bits(s.input, di) == 0, hex(get_bits(s.input, di))
        assert driven_word(rc, master, 26) == 0
        assert driven_word(rc, master, DO_MODULE) == 0
        missing = emcy.wait(s, 0xA001)
        assert missing[0][2] == 2, missing
        ack_error_and_init(master, pysoem.SAFEOP_STATE)


def test_sm_watchdog_in_op_drops_to_safeop_with_safe_outputs_and_emergency(rackcat):
    """The master stops sending process data in OP: after the SM2 watchdog (100 ms default)
    the device is in SAFEOP with the error flag and AL status code 0x001B, the outputs are in
    their safe state, and a 0x8110 emergency (process-data timeout) is queued."""
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        emcy = Emergencies.on(s)
        do, di = loopback_entries(s)
        master.config_map()
        to_op(master)
        assert wait_loopback(master, do, di, 0xFFFF) == 0xFFFF
        wait_watchdog_safeop(master)  # no frames: the SM2 watchdog (100 ms) expires
        assert s.state == pysoem.SAFEOP_STATE | pysoem.STATE_ERROR, hex(s.state)
        assert s.al_status == 0x001B, hex(s.al_status)
        run_cycles(master, 20)
        assert get_bits(s.input, di) == 0, "outputs not in their safe state after the watchdog"
        emcy.wait(s, 0x8110)
        ack_error_and_init(master, pysoem.SAFEOP_STATE)


def test_uart_bytes_written_by_the_master_leave_on_the_pty(rackcat):
    """0x5nn7 UART Tx data channel 0: a complete-access write (subindex 0 = count, then the
    bytes) transmits them; a serial program on the pseudo-terminal reads them."""
    rc = rackcat()
    pty = rc.module(UART_MODULE)["uart"][0]["pty"]
    fd = os.open(pty, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    master = open_master(rc.iface, 1)
    try:
        s = master.slaves[0]
        tx_obj = 0x5000 + (UART_MODULE - 1) * 0x10 + 7
        message = b"hello from the master\n"
        s.sdo_write(tx_obj, 0, bytes([len(message), 0]) + message, ca=True)
        got = b""
        deadline = time.monotonic() + 3.0
        while len(got) < len(message) and time.monotonic() < deadline:
            try:
                got += os.read(fd, 256)
            except BlockingIOError:
                time.sleep(0.01)
        assert got == message
        go(master, pysoem.INIT_STATE)
    finally:
        os.close(fd)
        master.close()
    rc.stop()


def test_analog_loopback_and_thermocouple_reading(rackcat):
    """Analog outputs written by the master come back through the loopback-wired analog
    input with the same 16-bit code (both cards -10..10 V, docs/MODULES.md scaling), and a
    thermocouple channel set through `rackcat ctl set` reads its temperature at 0.1 degC per
    bit (NIST ITS-90 round trip within 0.06 degC)."""
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        pdo = read_pdo_map(s)
        ao = [pdo.find(0x7000 + (11 - 1) * 0x10 + 2, k, "out") for k in range(1, 9)]  # CAO-15
        ai = [pdo.find(0x6000 + (12 - 1) * 0x10 + 2, k, "in") for k in range(1, 9)]  # CAI-11
        tc = pdo.find(0x6000 + (15 - 1) * 0x10 + 4, 1, "in")  # CTP-11 K-type, channel 0
        master.config_map()
        to_op(master)
        # code = round(V * 32767 / 10), two's complement in the UINT entry.
        codes = [0x4000, 0xE000, 0x0000, 0x7FFF, 0x8001, 0x0CCD, 0xF333, 0x0001]
        out = bytes(s.output)
        for entry, code in zip(ao, codes):
            out = set_bits(out, entry, code)
        s.output = out

        def analog_back(_):
            return [get_bits(s.input, e) for e in ai] == codes

        run_cycles(master, 500, until=analog_back)
        assert [hex(get_bits(s.input, e)) for e in ai] == [hex(c) for c in codes]

        rc.cli_while_cycling(master, "set", "--module", 15, "--channel", 0, "--value", 350.0)

        def tc_reads_350(_):
            return abs(get_bits(s.input, tc) - 3500) <= 1

        run_cycles(master, 500, until=tc_reads_350)
        assert abs(get_bits(s.input, tc) - 3500) <= 1, get_bits(s.input, tc)
        go(master, pysoem.SAFEOP_STATE)
        go(master, pysoem.INIT_STATE)
