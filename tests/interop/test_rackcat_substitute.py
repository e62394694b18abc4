"""[diagnostics] Substitute values (docs/MODULES.md "Substitute values", INTERBUS Basic profile
§7.3.2 and its objects 0x0020 PDTimeoutCode / 0x0030 PF_Code / 0x0031 PDIN_Subst) seen by a real
master (pysoem) on the wire: every output reaction after an SM watchdog expiry and after a RIM
unplug (Detect Modules Override 0: OP -> SAFEOP), read back through the rack's loopback wiring;
every input reaction of a module whose RIM is unplugged, in the process data, with the status
bits of 0x4nnC.

Objects per module n (nn = n - 1): 0x4nn8 output reaction, 0x4nnA input reaction, 0x4nnB input
substitute value, 0x4nnC input substitute status. Reaction codes: 0 zeros, 1 ones, 2 hold last,
3 substitute (outputs: the guide's 0x4nnX Value; inputs: 0x4nnB), 4 minimum, 5 maximum,
0x8000 the guide's own rule (default).
"""
import struct

from rackcat_helpers import (DI_LOOPBACK_MODULE, DO_MODULE, abort_code, cycle, get_bits, go,
                             pysoem, rack_with_master, rackcat, read_pdo_map,
                             ride_through_rim_loss, run_cycles, set_bits, to_op, wait_loopback,
                             wait_watchdog_safeop)

assert rackcat  # the fixture, imported for pytest

ZEROS, ONES, HOLD, SUBST, MIN, MAX, GUIDE = 0, 1, 2, 3, 4, 5, 0x8000
AO_MODULE, AI_MODULE = 11, 12  # RIM 1 slot 11 CAO-15 -> slot 12 CAI-11 (loopback, -10..10 V)
RIM2_DI_MODULE = 20            # RIM 2 slot 1 CDI-13, 8x DI
RIM2_AI_MODULE = 23            # RIM 2 slot 4 CAI-11/X8, 8 samples per channel


def obj(module, nibble, base=0x4000):
    return base + (module - 1) * 0x10 + nibble


def u16(v):
    return struct.pack("<H", v)


def set_output_reactions(s):
    """DO module channels 0..6 and AO module channels 0..6: one reaction each (0x4nn8 is
    writable in every state)."""
    codes = [ZEROS, ONES, HOLD, SUBST, MIN, MAX, GUIDE]
    for module in (DO_MODULE, AO_MODULE):
        for ch, code in enumerate(codes):
            s.sdo_write(obj(module, 0x8), ch + 1, u16(code))


def set_guide_values(master):
    """The guide's safe-state Values the SUBST reaction takes; 0x4nnX is "ro,wr_op" (guide
    Appendix A), so written in OP with process data flowing between the transfers."""
    s = master.slaves[0]
    s.sdo_write(obj(DO_MODULE, 0x0), 3, u16(0x0008))  # guide Table 7 Value: channel 3 = 1
    cycle(master)
    s.sdo_write(obj(AO_MODULE, 0x2), 3 + 3, u16(0xE000))  # guide Table 9 Value[3] = -2.5 V
    cycle(master)


# DO: commanded 0x0055 -> 0 zeros, 1 ones, 1 hold, 1 Value, 0 min, 1 max, 0 guide (not enabled)
DO_COMMAND, DO_SUBSTITUTED = 0x0055, 0x002E
AO_COMMAND = 0x4CCD  # +6 V
AO_SUBSTITUTED = [0x0000, 0xFFFF, AO_COMMAND, 0xE000, 0x8001, 0x7FFF, 0x0000, 0x0000]


def map_loopbacks(s):
    pdo = read_pdo_map(s)
    do = pdo.find(obj(DO_MODULE, 0, 0x7000), 1, "out")
    di = pdo.find(obj(DI_LOOPBACK_MODULE, 0, 0x6000), 1, "in")
    ao = [pdo.find(obj(AO_MODULE, 2, 0x7000), k, "out") for k in range(1, 9)]
    ai = [pdo.find(obj(AI_MODULE, 2, 0x6000), k, "in") for k in range(1, 9)]
    return pdo, do, di, ao, ai


def drive(master, do, di, ao, ai):
    s = master.slaves[0]
    out = bytes(s.output)
    for e in ao:
        out = set_bits(out, e, AO_COMMAND)
    s.output = out
    assert wait_loopback(master, do, di, DO_COMMAND) == DO_COMMAND
    run_cycles(master, 300, until=lambda _: [get_bits(s.input, e) for e in ai] == [AO_COMMAND] * 8)
    assert [get_bits(s.input, e) for e in ai] == [AO_COMMAND] * 8


def check_substituted(master, di, ai):
    s = master.slaves[0]

    def done(_):
        return get_bits(s.input, di) == DO_SUBSTITUTED and \
            [get_bits(s.input, e) for e in ai] == AO_SUBSTITUTED

    run_cycles(master, 300, until=done)
    assert hex(get_bits(s.input, di)) == hex(DO_SUBSTITUTED)
    assert [hex(get_bits(s.input, e)) for e in ai] == [hex(c) for c in AO_SUBSTITUTED]


def ack_error_and_init(master, state):
    s = master.slaves[0]
    s.state = state | pysoem.STATE_ACK
    s.write_state()
    go(master, pysoem.INIT_STATE)


def test_output_reactions_after_the_sm_watchdog(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        # A reaction outside the profile's table is refused and changes nothing.
        assert abort_code(s.sdo_write, obj(DO_MODULE, 0x8), 8, u16(0x0006)) == 0x06090030
        assert struct.unpack("<H", s.sdo_read(obj(DO_MODULE, 0x8), 8))[0] == GUIDE
        set_output_reactions(s)
        _, do, di, ao, ai = map_loopbacks(s)
        master.config_map()
        to_op(master)
        set_guide_values(master)
        drive(master, do, di, ao, ai)
        wait_watchdog_safeop(master)  # no frames: the SM2 watchdog (100 ms) expires
        assert s.state == pysoem.SAFEOP_STATE | pysoem.STATE_ERROR, hex(s.state)
        assert s.al_status == 0x001B, hex(s.al_status)
        check_substituted(master, di, ai)
        ack_error_and_init(master, pysoem.SAFEOP_STATE)


def test_output_and_input_reactions_after_a_rim_unplug(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        ride_through_rim_loss(s)
        set_output_reactions(s)
        # RIM 2's CDI-13: channel 0 substitute 1, 1 hold last, 2 zeros, 3..7 the guide (0).
        s.sdo_write(obj(RIM2_DI_MODULE, 0xA), 1, u16(SUBST))
        s.sdo_write(obj(RIM2_DI_MODULE, 0xB), 1, u16(1))
        s.sdo_write(obj(RIM2_DI_MODULE, 0xA), 2, u16(HOLD))
        s.sdo_write(obj(RIM2_DI_MODULE, 0xA), 3, u16(ZEROS))
        assert abort_code(s.sdo_write, obj(RIM2_DI_MODULE, 0xA), 4, u16(ONES)) == 0x06090030
        assert abort_code(s.sdo_write, obj(RIM2_DI_MODULE, 0xB), 2, u16(2)) == 0x06090031
        # RIM 2's CAI-11/X8: channel 0 substitute 0x1234 in all 8 samples.
        s.sdo_write(obj(RIM2_AI_MODULE, 0xA), 1, u16(SUBST))
        s.sdo_write(obj(RIM2_AI_MODULE, 0xB), 1, u16(0x1234))
        # The status 0x4nnC in the user TxPDO 0x1B00, appended to the assignment (PREOP).
        status_obj = obj(RIM2_DI_MODULE, 0xC)
        s.sdo_write(0x1B00, 0, b"\x00")
        s.sdo_write(0x1B00, 1, struct.pack("<I", status_obj << 16 | 16))
        s.sdo_write(0x1B00, 0, b"\x01")
        n = s.sdo_read(0x1C13, 0)[0]
        s.sdo_write(0x1C13, 0, b"\x00")
        s.sdo_write(0x1C13, n + 1, struct.pack("<H", 0x1B00))
        s.sdo_write(0x1C13, 0, bytes([n + 1]))
        pdo, do, di, ao, ai = map_loopbacks(s)
        status_pdo = pdo.find(status_obj, 0, "in")
        rim2_di = pdo.find(obj(RIM2_DI_MODULE, 1, 0x6000), 1, "in")  # DINx8 0x6nn1
        rim2_ai = [pdo.find(obj(RIM2_AI_MODULE, 8, 0x6000), 1, "in")]  # 8 samples of channel 0
        master.config_map()
        to_op(master)
        set_guide_values(master)
        for ch in (1, 2):
            rc.cli_while_cycling(master, "set", "--module", RIM2_DI_MODULE, "--channel", ch,
                                 "--value", 1)
        run_cycles(master, 300, until=lambda _: get_bits(s.input, rim2_di) == 0x06)
        assert get_bits(s.input, rim2_di) == 0x06
        drive(master, do, di, ao, ai)
        assert struct.unpack("<H", s.sdo_read(obj(RIM2_DI_MODULE, 0xC), 0))[0] == 0

        rc.cli_while_cycling(master, "unplug", "--rim", 2)
        run_cycles(master, 50)
        master.read_state()
        assert s.state == pysoem.SAFEOP_STATE | pysoem.STATE_ERROR, hex(s.state)
        assert s.al_status == 0x0070, hex(s.al_status)
        check_substituted(master, di, ai)
        # Inputs of the unplugged RIM: 1 (substitute), 1 (last valid), 0 (zeros), 0 (guide).
        assert hex(get_bits(s.input, rim2_di)) == hex(0x03)
        samples = get_bits(s.input, rim2_ai[0])
        assert samples == int.from_bytes(bytes.fromhex("3412" * 8), "little"), hex(samples)
        status = struct.unpack("<H", s.sdo_read(obj(RIM2_DI_MODULE, 0xC), 0))[0]
        assert status == 0xFF, hex(status)
        assert get_bits(s.input, status_pdo) == 0xFF  # the same in the process data
        rc.cli_while_cycling(master, "replug", "--rim", 2)
        run_cycles(master, 300, until=lambda _: get_bits(s.input, rim2_di) == 0x06)
        assert get_bits(s.input, rim2_di) == 0x06
        assert struct.unpack("<H", s.sdo_read(obj(RIM2_DI_MODULE, 0xC), 0))[0] == 0
        assert get_bits(s.input, status_pdo) == 0
        ack_error_and_init(master, pysoem.SAFEOP_STATE)

