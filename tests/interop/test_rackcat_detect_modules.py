"""Detect Modules with Detect Modules Override 0 and a RIM offline (guide §4.2 Table 23,
ETG.5001.1), seen by pysoem: after 0xF002 "scan" and after a device reset
0xFBF0, 0xF050 detected, 0x3000, the default 0xF030 and the default 0x1C12/0x1C13 describe the
same modules, so the master's normal start-up (config_init, config_map, SAFEOP, OP) reaches OP
without hand edits.
"""
import struct

from rackcat_helpers import (device_reset, go, open_master, pysoem, rack_with_master, rackcat,
                             ride_through_rim_loss, run_command, run_cycles, store_parameters,
                             to_op)

assert rackcat  # the fixture, imported for pytest

SCAN = b"scan"  # 0xF002:01 (docs/MDP.md)
RIM1_MODULES, RIM2_FIRST_MODULE = 19, 20  # default rack: RIM 1 slots 1..19, RIM 2 from 20


def array(slave, index, fmt="<I"):
    n = slave.sdo_read(index, 0)[0]
    size = struct.calcsize(fmt)
    return [struct.unpack(fmt, slave.sdo_read(index, k)[:size])[0] for k in range(1, n + 1)]


def check_consistent(slave, modules):
    detected = array(slave, 0xF050)
    assert len(detected) == modules
    assert array(slave, 0x3000) == detected
    assert array(slave, 0xF030) == detected
    for assign, base in ((0x1C12, 0x1600), (0x1C13, 0x1A00)):
        for pdo in array(slave, assign, "<H"):
            assert pdo - base + 1 < RIM2_FIRST_MODULE or modules > RIM1_MODULES, hex(pdo)


def reach_op(master):
    master.config_map()
    to_op(master)
    run_cycles(master, 100)
    master.read_state()
    assert master.slaves[0].state == pysoem.OP_STATE, hex(master.slaves[0].state)
    go(master, pysoem.INIT_STATE)


def test_scan_with_a_rim_offline_then_op_from_scratch(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        ride_through_rim_loss(s)
        rc.cli("unplug", "--rim", 2)
        assert run_command(s, 0xF002, SCAN) == 200  # scan complete
        check_consistent(s, RIM1_MODULES)
        reach_op(master)


def test_device_reset_with_a_rim_offline_then_op_from_scratch(rackcat):
    with rack_with_master(rackcat) as (rc, master):
        s = master.slaves[0]
        ride_through_rim_loss(s)
        assert store_parameters(s) == 0  # Override 0 survives the reset
        rc.cli("unplug", "--rim", 2)
        device_reset(master, s)
        master.close()
        master = open_master(rc.iface, 1)
        s = master.slaves[0]
        s.add_emergency_callback(lambda e: None)
        check_consistent(s, RIM1_MODULES)
        reach_op(master)
