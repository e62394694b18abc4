"""What an audit against the guide found, with a real master (pysoem).

User-mappable PDOs: in PREOP the operator maps 0x2000:0F
(CPU temperature, guide §4.8) and a thermocouple's loop resistance (0x5nn4, guide §2.6) into the
user TxPDO 0x1B00, appends it to 0x1C13 the way configuration tools do (ETG.1000.6 §5.6.7.4.8/9:
subindex 0 to 0, the entries, subindex 0 to n), and pysoem's ordinary config_map sizes SM3 from
that; in OP both values travel every cycle and follow the rack.

The CPU temperature 0x2000:0F is a new reading every 30 s on the device's own clock (guide
§4.8), also in PREOP where no process data flows.
"""
import struct
import time

from rackcat_helpers import abort_code, go, open_master, pysoem, rackcat, run_cycles, to_op

assert rackcat  # the fixture, imported for pytest

USER_TX_PDO = 0x1B00
CPU_TEMPERATURE = 0x20000F20  # 0x2000:0F, REAL, 32 bits
TC_MODULE = 15  # default rack: RIM 1 slot 15, CTP-11 K thermocouple (nn = 0x0E)
OHMS_CH2 = 0x50E40210  # 0x50E4:02 Ohms[2], UINT, 16 bits


def u8(v):
    return struct.pack("<B", v)


def test_user_pdo_carries_cpu_temperature_and_thermocouple_ohms_in_op(rackcat):
    rc = rackcat()
    master = open_master(rc.iface, 1)
    s = master.slaves[0]
    # The mapping: entries only while subindex 0 is 0, an unmappable object refused.
    s.sdo_write(USER_TX_PDO, 0, u8(0))
    s.sdo_write(USER_TX_PDO, 1, struct.pack("<I", CPU_TEMPERATURE))
    s.sdo_write(USER_TX_PDO, 2, struct.pack("<I", OHMS_CH2))
    assert abort_code(lambda: s.sdo_write(USER_TX_PDO, 3, struct.pack("<I", 0x20000100))) \
        == 0x06040041  # 0x2000:01 Part Number is not mappable
    s.sdo_write(USER_TX_PDO, 0, u8(2))
    assert abort_code(lambda: s.sdo_write(USER_TX_PDO, 3, struct.pack("<I", OHMS_CH2))) \
        == 0x06010003  # entries change only while subindex 0 is 0
    # The assignment: appended after the module PDOs.
    n = s.sdo_read(0x1C13, 0)[0]
    s.sdo_write(0x1C13, 0, u8(0))
    s.sdo_write(0x1C13, n + 1, struct.pack("<H", USER_TX_PDO))
    s.sdo_write(0x1C13, 0, u8(n + 1))

    master.config_map()
    size = len(s.input)
    rc.cli("cpu-temp", "--celsius", "47.5", "--now")
    rc.cli("sensor", "--module", TC_MODULE, "--channel", 1, "--loop-ohms", 321)
    to_op(master)
    run_cycles(master, 20)
    assert len(s.input) == size
    temp, ohms = struct.unpack("<fH", bytes(s.input[-6:]))
    assert (temp, ohms) == (47.5, 321)

    # Both change while process data flows, without any SDO traffic.
    rc.cli_while_cycling(master, "cpu-temp", "--celsius", "52", "--now")
    rc.cli_while_cycling(master, "sensor", "--module", TC_MODULE, "--channel", 1,
                         "--loop-ohms", 1234)
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        run_cycles(master, 10)
        temp, ohms = struct.unpack("<fH", bytes(s.input[-6:]))
        if (temp, ohms) == (52.0, 1234):
            break
    assert (temp, ohms) == (52.0, 1234)
    go(master, pysoem.INIT_STATE)


def test_cpu_temperature_updates_every_30_s_in_preop(rackcat):
    rc = rackcat()
    started = time.monotonic()
    master = open_master(rc.iface, 1)
    s = master.slaves[0]

    def reading():
        return struct.unpack("<f", s.sdo_read(0x2000, 0x0F))[0]

    before = reading()
    rc.cli("cpu-temp", "--celsius", "63.3")  # the next 30 s reading, not now
    assert reading() == before
    deadline = started + 40
    value = before
    while time.monotonic() < deadline and value == before:
        time.sleep(0.5)
        value = reading()
    assert value == 63.5, f"0x2000:0F still {value} after {time.monotonic() - started:.0f} s"
    assert master.read_state() == pysoem.PREOP_STATE
