"""[modules] The absolute rotary encoder card (CAE-10, docs/ENCODER.md) driven by a real master
(pysoem) over veth at 1 ms: position and velocity of a shaft at constant speed, the Eigen motor
model closed through an analog output, a preset through the process data acknowledged in the
status word and kept across a restart (0xFBF2), the error bit and code for each injected fault
and for a stopped master sign-of-life.

Rack: examples/encoder-rack.yaml. Module 1 = encoder on a 10 rev/s ramp (16-bit single-turn:
655360 steps/s), module 2 = CAO-15, module 3 = encoder on a motor model driven by module 2's
channel 0 (1 V -> 1 rev/s). Telegram (encoder guide "Standard Telegram 83"): outputs 0x7nnD
STW2_ENC, G1_STW1; inputs 0x6nnD ZSW2_ENC, G1_ZSW1, G1_XIST1, G1_XIST2, NIST_B.
"""
import concurrent.futures
from pathlib import Path
import struct
import time

from rackcat_helpers import (cycle, get_bits, go, open_master, pysoem, rackcat, read_pdo_map,
                             run_cycles, set_bits, store_parameters, to_op)
from test_rackcat_diagnosis import read_history

assert rackcat  # the fixture, imported for pytest

RACK = Path(__file__).resolve().parents[2] / "examples" / "encoder-rack.yaml"
STEPS_PER_S = 10 * 65536  # 10 rev/s x 65536 steps
TOTAL = 1 << 28
ENC1, AO, ENC3 = 1, 2, 3


def idx(base, module, nibble):
    return base + (module - 1) * 0x10 + nibble


class Telegram:
    """The encoder module's mapped entries in the process image."""

    def __init__(self, pdo, module):
        self.stw2 = pdo.find(idx(0x7000, module, 0xD), 1, "out")
        self.stw = pdo.find(idx(0x7000, module, 0xD), 2, "out")
        self.zsw2 = pdo.find(idx(0x6000, module, 0xD), 1, "in")
        self.zsw = pdo.find(idx(0x6000, module, 0xD), 2, "in")
        self.xist1 = pdo.find(idx(0x6000, module, 0xD), 3, "in")
        self.xist2 = pdo.find(idx(0x6000, module, 0xD), 4, "in")
        self.nist_b = pdo.find(idx(0x6000, module, 0xD), 5, "in")

    def velocity(self, s):
        v = get_bits(s.input, self.nist_b)
        return v - (1 << 32) if v & 0x80000000 else v


def start(rc):
    master = open_master(rc.iface, 1)
    s = master.slaves[0]
    pdo = read_pdo_map(s)
    return master, s, pdo


def test_position_and_velocity_at_constant_speed_and_motor_model(rackcat):
    rc = rackcat(config=RACK)
    master, s, pdo = start(rc)
    try:
        # Encoder 3 reports rpm (guide 3.11.11 unit 3); encoder 1 keeps steps/s.
        s.sdo_write(idx(0x8000, ENC3, 0), 0x08, b"\x03")
        e1, e3 = Telegram(pdo, ENC1), Telegram(pdo, ENC3)
        ao0 = pdo.find(idx(0x7000, AO, 2), 1, "out")
        master.config_map()
        to_op(master)
        # 2 V on the motor: code round(2 x 32767 / 10) = 6553 (docs/MODULES.md analog code).
        s.output = set_bits(s.output, ao0, 6553)
        run_cycles(master, 1000)  # 10 time constants of the motor: at speed
        samples = []
        deadline = time.monotonic() + 2.5
        while time.monotonic() < deadline:
            run_cycles(master, 1)
            samples.append((time.monotonic(), get_bits(s.input, e1.xist2), e1.velocity(s),
                            e3.velocity(s)))
        t0, x0 = samples[0][:2]
        t1, x1 = samples[-1][:2]
        # Position: the count advanced by 655360 steps/s. The host time stamps the reply, the
        # slave sampled when it built it: the two differ by at most one frame's latency
        # (< 20 ms receive timeout) at each end, which over >= 2 s is at most 2 %.
        slope = ((x1 - x0) % TOTAL) / (t1 - t0)
        assert abs(slope - STEPS_PER_S) < 0.02 * STEPS_PER_S, slope
        # Velocity: the slave differentiates its own samples on its own time base over a 20 ms
        # gate (docs/ENCODER.md), so the master's frame jitter does not enter and only
        # quantisation remains: one step per 20 ms = 50 steps/s (0.008 %). Every reading
        # within 0.5 %, the mean within 0.1 %.
        v = [x[2] for x in samples]
        assert all(abs(x - STEPS_PER_S) < 0.005 * STEPS_PER_S for x in v), (min(v), max(v))
        mean = sum(v) / len(v)
        assert abs(mean - STEPS_PER_S) < 0.001 * STEPS_PER_S, mean
        # Motor model: 2 V -> 2 rev/s = 120 rpm after the 0.1 s time constant. The
        # plant holds its output for its 1 ms step, so each end of the 20 ms gate lags by up to
        # 1 ms of motion: a reading is within 5 % + 1 rpm; the lags average out over the 2.5 s,
        # the mean within 2 rpm.
        rpm = [x[3] for x in samples]
        assert all(abs(x - 120) <= 7 for x in rpm), (min(rpm), max(rpm))
        assert abs(sum(rpm) / len(rpm) - 120) <= 2, sum(rpm) / len(rpm)
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()


def preset_edge(master, s, e, shift=False):
    """G1_STW1 bit 12 rising edge (bit 11 = shift) with STW2_ENC bit 10 "control by PLC";
    cycles until G1_ZSW1 bit 12 acknowledges; returns G1_XIST2 of that cycle."""
    s.output = set_bits(s.output, e.stw2, 1 << 10)
    s.output = set_bits(s.output, e.stw, (1 << 12) | ((1 << 11) if shift else 0))
    for _ in range(200):
        cycle(master)
        if get_bits(s.input, e.zsw) & (1 << 12):
            return get_bits(s.input, e.xist2)
        time.sleep(0.001)
    raise AssertionError("preset not acknowledged in G1_ZSW1 bit 12")


def test_preset_through_process_data_kept_across_restart(rackcat):
    rc = rackcat(config=RACK)
    master, s, pdo = start(rc)
    try:
        s.sdo_write(idx(0x8000, ENC1, 0), 0x0A, struct.pack("<i", 1000))
        e = Telegram(pdo, ENC1)
        master.config_map()
        to_op(master)
        run_cycles(master, 100)
        # While the shaft turns: the acknowledged cycle reads 1000 plus at most the motion
        # since the edge was taken (a few frames: < 50 ms = 32768 steps).
        x = preset_edge(master, s, e)
        assert 1000 <= x < 1000 + STEPS_PER_S // 20, x
        s.output = set_bits(s.output, e.stw, 0)
        run_cycles(master, 20)
        assert get_bits(s.input, e.zsw) & (1 << 12) == 0, "acknowledgement follows bit 12"
        offset = struct.unpack("<i", s.sdo_read(idx(0x8000, ENC1, 1), 1))[0]
        assert offset != 0
        # Offset = preset - position before it, modulo 2^28 (docs/ENCODER.md).
        assert store_parameters(s) == 0
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.restart()
    master, s, pdo = start(rc)
    try:
        assert struct.unpack("<i", s.sdo_read(idx(0x8000, ENC1, 1), 1))[0] == offset
        assert struct.unpack("<i", s.sdo_read(idx(0x8000, ENC1, 0), 0x0A))[0] == 1000
        e = Telegram(pdo, ENC1)
        master.config_map()
        to_op(master)
        run_cycles(master, 50)
        # The shaft starts again at 0 with the restart: position = offset + steps since start.
        x = get_bits(s.input, e.xist2)
        assert (x - offset) % TOTAL < STEPS_PER_S * 30, (x, offset)
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()


class Master:
    """A master that counts its sign-of-life (STW2_ENC bits 12..15, 1..15) every cycle."""

    def __init__(self, master, e):
        self.m, self.s, self.e, self.ls, self.counting = master, master.slaves[0], e, 0, True

    def run(self, n, stw=0):
        for _ in range(n):
            if self.counting:
                self.ls = 1 if self.ls >= 15 else self.ls + 1
            self.s.output = set_bits(self.s.output, self.e.stw2, (self.ls << 12) | (1 << 10))
            self.s.output = set_bits(self.s.output, self.e.stw, stw)
            cycle(self.m)
            time.sleep(0.001)

    def zsw(self):
        return get_bits(self.s.input, self.e.zsw)

    def until_error(self, want, n=500):
        for _ in range(n):
            self.run(1)
            if bool(self.zsw() & (1 << 15)) == want:
                return
        raise AssertionError(f"G1_ZSW1 bit 15 never {want}: 0x{self.zsw():04X}")

    def cli(self, rc, *args):
        """`rackcat ctl ARGS` while this master keeps cycling with its sign-of-life counting
        (the helper's cli_while_cycling would freeze it and trip the monitoring)."""
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            future = pool.submit(rc.cli, *args)
            while not future.done():
                self.run(1)
            return future.result()

    def acknowledge(self):
        self.run(2)
        self.run(2, 1 << 15)
        self.until_error(False)


def test_error_bits_for_each_fault_and_sign_of_life(rackcat):
    rc = rackcat(config=RACK)
    master, s, pdo = start(rc)
    try:
        s.sdo_write(idx(0x8000, ENC1, 0), 0x07, b"\x05")  # 5 sign-of-life failures tolerated
        e = Telegram(pdo, ENC1)
        emergencies = []
        s.add_emergency_callback(lambda x: emergencies.append(x.error_code))
        master.config_map()
        to_op(master)
        m = Master(master, e)
        m.run(100)
        assert m.zsw() & (1 << 15) == 0
        _, before = read_history(s)
        # (ctl fault, G1_XIST2 code, text ID, Emergency)
        for fault, code, text, emcy in [("hardware", 0x0001, 0x8801, 0x5000),
                                        ("jump", 0x1002, 0x8802, 0x7300),
                                        ("frozen", 0x1003, 0x8803, 0x7300)]:
            m.cli(rc, "encoder-fault", "--module", ENC1, "--fault", fault)
            m.until_error(True)
            assert get_bits(s.input, e.xist2) == code
            m.cli(rc, "encoder-fault", "--module", ENC1, "--fault", fault, "--clear")
            m.run(5)
            assert m.zsw() & (1 << 15), "the sensor error stays until acknowledged"
            m.acknowledge()
            _, msgs = read_history(s)
            texts = [x["text"] for x in msgs[len(before):]]
            assert text in texts and (text & 0x0FFF) | 0x1000 in texts, texts
            a = next(x for x in msgs[len(before):] if x["text"] == text)
            assert (a["module"], a["detail"], a["emcy"]) == (ENC1, code, emcy), a
        # The master's sign-of-life stops: 10 per failure, fault at 10 x 5 = 50.
        m.counting = False
        m.run(4)
        assert m.zsw() & (1 << 15) == 0, "4 failures of 5 tolerated"
        m.until_error(True, n=20)
        assert get_bits(s.input, e.xist2) == 0x0F04
        m.counting = True
        m.acknowledge()
        assert get_bits(s.input, e.xist2) != 0x0F04
        _, msgs = read_history(s)
        assert 0x8804 in [x["text"] for x in msgs[len(before):]]
        s.sdo_read(0x1018, 1)  # lets pysoem take the queued Emergencies
        for code in (0x5000, 0x7300, 0x8100):
            assert code in emergencies, [hex(c) for c in emergencies]
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()


def test_impossible_combination_answers_an_abort(rackcat):
    rc = rackcat(config=RACK)
    master, s, _ = start(rc)
    try:
        emergencies = []
        s.add_emergency_callback(lambda x: emergencies.append(x.error_code))
        settings = idx(0x8000, ENC1, 0)
        # 65537 measuring units per revolution on a 65536-step encoder: value too high.
        try:
            s.sdo_write(settings, 0x05, struct.pack("<I", 65537))
            raise AssertionError("accepted")
        except pysoem.SdoError as err:
            assert err.abort_code == 0x06090031
        # 1000 units with the 2^28 range: above 1000 x 4096 turns, a combination.
        try:
            s.sdo_write(settings, 0x05, struct.pack("<I", 1000))
            raise AssertionError("accepted")
        except pysoem.SdoError as err:
            assert err.abort_code == 0x06040043
        assert struct.unpack("<I", s.sdo_read(settings, 0x05))[0] == 65536
        # Round axis: 100 turns of 1000 units (4096 x 1000 / 100000 is not an integer).
        s.sdo_write(settings, 0x06, struct.pack("<I", 100000))
        s.sdo_write(settings, 0x05, struct.pack("<I", 1000))
        _, msgs = read_history(s)
        refused = [x for x in msgs if x["text"] == 0x4805]
        assert [x["detail"] for x in refused][-2:] == [5, 5], refused
        assert emergencies.count(0x6320) == 2, [hex(c) for c in emergencies]
    finally:
        master.close()
    rc.stop()
