"""The modular device's objects as a real master (pysoem) reads and writes them over the
wire: device and module information, module lists, and a stored parameter (0x2000:04 IPv4)
that survives a restart of `rackcat run` with the same --state-dir.
"""
import struct

from rackcat_helpers import (DEFAULT_MODULES, abort_code, device_reset, go, open_master, pysoem,
                             rack_with_master, run_command, rackcat, run_cycles,
                             store_parameters, to_op)

assert rackcat  # the fixture, imported for pytest

# Module idents of the default rack (examples/default-rack.yaml), module by module, from the
# guide's Table 5 (docs/MDP.md card catalogue; the /X8 cards use the oversampled idents).
DEFAULT_IDENTS = [
    0x0064D016, 0x0064D116, 0x0064D004, 0x0064DD08, 0x0064D016, 0x0064D008, 0x0064D116,
    0x0064D016, 0x0064D008, 0x0064D116, 0x0064A008, 0x0064A108, 0x0064A016, 0x0064A116,
    0x0064C108, 0x0064C108, 0x0064C108, 0x0064C104, 0x0064C004,  # RIM 1 slots 1..19
    0x0064D108, 0x0064D808, 0x0064D816, 0x0064A808, 0x0064A816, 0x0064D816, 0x0064D016,
    0x0064D116,  # RIM 2 slots 1..8
]
assert len(DEFAULT_IDENTS) == DEFAULT_MODULES


def text(slave, index, sub):
    return slave.sdo_read(index, sub).rstrip(b"\0").decode()


def module_list(slave, index):
    n = slave.sdo_read(index, 0)[0]
    return [struct.unpack("<I", slave.sdo_read(index, k))[0] for k in range(1, n + 1)]


def test_device_and_module_information(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        assert text(s, 0x2000, 1) == "FI-CM0100-00"  # part number, rack file
        assert text(s, 0x2000, 3) == "FI-CM0100-00-0001"
        assert text(s, 0x2011, 4) == "24-slot (integrated)"  # RIM 1 type
        assert text(s, 0x2021, 4) == "12-slot"  # RIM 2 type
        # 0x3000 module ident map and 0xF050 detected module list: every card of the rack.
        assert module_list(s, 0x3000) == DEFAULT_IDENTS
        assert module_list(s, 0xF050) == DEFAULT_IDENTS
        # Both as complete access, the way configuration tools read module lists.
        ca = struct.pack("<BB", DEFAULT_MODULES, 0) + b"".join(
            struct.pack("<I", v) for v in DEFAULT_IDENTS)
        assert s.sdo_read(0xF050, 0, 1024, ca=True) == ca
        # 0x3nn1 module information (nn = module number - 1): card type, description,
        # channels, RIM, slot, voltage range (guide Table 3/6, docs/MDP.md).
        expected = {
            1: ("CDO-10", "16xDout Source", 16, 1, 1, 24.0, 0.0),
            2: ("CDI-10", "16xDin 24V", 16, 1, 2, 24.0, 0.0),
            11: ("CAO-15", "8xAout 16 bit -10 to 10", 8, 1, 11, 10.0, -10.0),
            19: ("CUR-12", "4xUART RS232/RS485", 4, 1, 19, 12.0, -12.0),
            27: ("CDI-10", "16xDin 24V", 16, 2, 8, 24.0, 0.0),
        }
        for n, (card, desc, ch, rim, slot, vmax, vmin) in expected.items():
            idx = 0x3000 + (n - 1) * 0x10 + 1
            got = (text(s, idx, 1), text(s, idx, 2),
                   struct.unpack("<h", s.sdo_read(idx, 3))[0],
                   struct.unpack("<b", s.sdo_read(idx, 4))[0],
                   struct.unpack("<b", s.sdo_read(idx, 5))[0],
                   struct.unpack("<f", s.sdo_read(idx, 8))[0],
                   struct.unpack("<f", s.sdo_read(idx, 9))[0])
            assert got == (card, desc, ch, rim, slot, vmax, vmin), f"0x{idx:04X}"
        # A module number beyond the rack has no information object.
        assert abort_code(s.sdo_read, 0x3000 + DEFAULT_MODULES * 0x10 + 1, 1) == 0x06020000
        go(master, pysoem.INIT_STATE)



def test_ipv4_stored_survives_restart_and_is_read_only_in_op(rackcat, tmp_path):
    rc = rackcat(state_dir=tmp_path / "state")
    new_ip = b"10.20.30.40"
    master = open_master(rc.iface, 1)
    try:
        s = master.slaves[0]
        assert text(s, 0x2000, 4) == "192.168.9.50"  # rack file default
        s.sdo_write(0x2000, 4, new_ip)  # PREOP: writable
        assert text(s, 0x2000, 4) == new_ip.decode()
        assert store_parameters(s) in (0, 1)
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()

    rc.restart()  # same namespace, same --state-dir
    assert "loaded stored parameters" in rc.log()
    master = open_master(rc.iface, 1)
    try:
        s = master.slaves[0]
        assert text(s, 0x2000, 4) == new_ip.decode(), rc.log()
        # In OP the address is read-only: abort 0x08000022 "cannot be transferred or stored
        # because of the present device state", and the value is unchanged.
        master.config_map()
        to_op(master)
        run_cycles(master, 20)
        assert abort_code(s.sdo_write, 0x2000, 4, b"10.0.0.1") == 0x08000022
        run_cycles(master, 20)
        assert text(s, 0x2000, 4) == new_ip.decode()
        master.read_state()
        assert s.state == pysoem.OP_STATE
        go(master, pysoem.SAFEOP_STATE)
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()


def detect_modules(slave, timeout_s=5.0):
    """0xF002 Detect Modules Command: "scan" (0x73 0x63 0x61 0x6E)."""
    return run_command(slave, 0xF002, b"scan", timeout_s)


def request_safeop(master):
    master.state = pysoem.SAFEOP_STATE
    master.write_state()
    master.state_check(pysoem.SAFEOP_STATE, 2_000_000)
    master.read_state()
    return master.slaves[0]


def test_detect_modules_after_rim_loss_and_configured_list(rackcat):
    """Configured (0xF030) versus detected (0xF050) modules. With Detect Modules Override 0,
    the Detect Modules command enumerates only the cards it detects now (guide Table 23): RIM
    2 unplugged -> 0xF050 holds RIM 1's 19 modules, and the default configured list 0xF030
    follows it (mdp/module_enumeration.hpp), so PREOP -> SAFEOP is accepted;
    after the replug and a new scan all 27 again. A configured list that contradicts the
    detected one is refused (0x06090033 over SDO; AL 0x0070 on PREOP -> SAFEOP, ETG.5001.1)."""
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        emergencies = []
        s.add_emergency_callback(emergencies.append)
        # A configured list that contradicts the detected one is refused and changes nothing
        # (guide abort table: 0x06090033 module ident lists do not match).
        assert abort_code(s.sdo_write, 0xF030, 1, struct.pack("<I", 0x0064D116)) == 0x06090033
        assert module_list(s, 0xF030) == DEFAULT_IDENTS
        s.sdo_write(0x2000, 0x0B, b"\x00")  # Detect Modules Override = 0

        rc.cli("unplug", "--rim", 2)
        assert detect_modules(s) == 200  # guide Appendix A: 200 = command 100 % done
        assert module_list(s, 0xF050) == DEFAULT_IDENTS[:19]
        assert module_list(s, 0xF030) == DEFAULT_IDENTS[:19]
        master.config_map()
        s = request_safeop(master)
        assert s.state == pysoem.SAFEOP_STATE, (hex(s.state), hex(s.al_status))
        go(master, pysoem.PREOP_STATE)

        rc.cli("replug", "--rim", 2)
        assert detect_modules(s) == 200  # guide Appendix A: 200 = command 100 % done
        assert module_list(s, 0xF050) == DEFAULT_IDENTS
        assert module_list(s, 0xF030) == DEFAULT_IDENTS
        # A master starting from scratch (SOEM keeps the sizes of its first config_map).
        assert master.config_init() == 1
        assert master.state_check(pysoem.PREOP_STATE, 2_000_000) == pysoem.PREOP_STATE
        master.slaves[0].add_emergency_callback(emergencies.append)
        master.config_map()
        s = request_safeop(master)
        assert s.state == pysoem.SAFEOP_STATE, (hex(s.state), hex(s.al_status))
        go(master, pysoem.INIT_STATE)


def test_device_reset_command_restarts_the_slave_in_init(rackcat):
    """0xFBF0 "teser\\0" (device reset, docs/MDP.md): the master gets its SDO answer, then the
    slave is back in INIT without an error, and a new scan takes it to PREOP again; a
    parameter written but not stored is back at its power-on value."""
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        s.sdo_write(0x2000, 4, b"10.1.2.3")  # written, not stored
        device_reset(master, s)  # INIT: no error flag
        assert s.al_status == 0  # no AL status code
        assert master.config_init() == 1
        assert master.state_check(pysoem.PREOP_STATE, 2_000_000) == pysoem.PREOP_STATE
        assert text(master.slaves[0], 0x2000, 4) == "192.168.9.50"
