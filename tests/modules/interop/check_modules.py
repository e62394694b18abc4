#!/usr/bin/env python3
"""pysoem checks of the modules behaviour on the wire (run by run_pysoem.sh inside a netns).

In OP: digital outputs of RIM 1 slot 1 (CDO-10) come back through the loopback-wired input of
slot 2 (CDI-10). Leaving OP: the 0x4000 safe values appear. Unplugging RIM 2 through
`rackcat ctl`: 0x2021:08, 0xF388 and 0xF380 change and the CoE Emergency 0xA001 arrives;
after replug 0xFBF1 clears the latched bits. UART: bytes written to channel 0's
pseudo-terminal arrive through 0x512B and the status word 0x5126:05.
"""
import os
import struct
import subprocess
import sys
import threading
import time

import pysoem

iface, pty, rackcat, port, state = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]
failures = []


def check(what, got, expect):
    ok = got == expect
    print(("ok   " if ok else "FAIL ") + f"{what}: {got!r}" + ("" if ok else f" (expected {expect!r})"))
    if not ok:
        failures.append(what)


def ctl(*args):
    subprocess.run([rackcat, "ctl", "--port", port, "--state-dir", state, *args], check=True,
                   capture_output=True)


def u32(b):
    return int.from_bytes(b, "little")


m = pysoem.Master()
m.open(iface)
assert m.config_init() == 1
s = m.slaves[0]
emcy = []
s.add_emergency_callback(emcy.append)
m.config_map()
stop = False


def process_data():
    while not stop:
        m.send_processdata()
        m.receive_processdata(2000)
        time.sleep(0.001)


m.state = pysoem.SAFEOP_STATE
m.write_state()
m.state_check(pysoem.SAFEOP_STATE, 3_000_000)
t = threading.Thread(target=process_data)
t.start()
m.state = pysoem.OP_STATE
m.write_state()
check("OP reached", m.state_check(pysoem.OP_STATE, 3_000_000), pysoem.OP_STATE)
# Safe state of module 1 (0x4000, Appendix A: writable in OP): every channel set to 0x1234.
s.sdo_write(0x4000, 1, struct.pack("<H", 0xFFFF))
s.sdo_write(0x4000, 2, struct.pack("<H", 0xFFFF))
s.sdo_write(0x4000, 3, struct.pack("<H", 0x1234))
out = bytearray(len(s.output))
out[0:2] = struct.pack("<H", 0xA55A)  # module 1 is the first RxPDO (0x1600)
s.output = bytes(out)
time.sleep(0.3)
check("OP: DIN of slot 2 (first TxPDO 0x1A01)", struct.unpack_from("<H", s.input, 0)[0], 0xA55A)
s.state = pysoem.SAFEOP_STATE
s.write_state()
time.sleep(0.3)
check("SAFEOP: safe value on the wire", struct.unpack_from("<H", s.input, 0)[0], 0x1234)

emcy.clear()
ctl("unplug", "--rim", "2")
check("unplugged: 0x2021:08", u32(s.sdo_read(0x2021, 8)), 0x8)
check("unplugged: 0xF388:01", u32(s.sdo_read(0xF388, 1)), 0x4)
check("unplugged: 0xF380", u32(s.sdo_read(0xF380, 0)), 0x8)
check("emergency 0xA001 for RIM 2", [(e.error_code, e.b1) for e in emcy][:1], [(0xA001, 2)])
ctl("replug", "--rim", "2")
check("replugged: 0x2021:08 (bit 3 latched)", u32(s.sdo_read(0x2021, 8)), 0xA)
check("replugged: 0xF390", u32(s.sdo_read(0xF390, 0)), 0x8)
s.sdo_write(0xFBF1, 1, b"teser")
check("after 0xFBF1: 0x2021:08", u32(s.sdo_read(0x2021, 8)), 0x2)
check("after 0xFBF1: 0xF390", u32(s.sdo_read(0xF390, 0)), 0x0)

fd = os.open(pty, os.O_RDWR | os.O_NOCTTY)
os.write(fd, b"hello")
time.sleep(0.3)
check("UART status 0x5126:05 bytes available", struct.unpack("<H", s.sdo_read(0x5126, 5))[0] & 0xFFF, 5)
count = s.sdo_read(0x512B, 0)[0]
check("UART 0x512B", bytes(s.sdo_read(0x512B, k)[0] for k in range(1, count + 1)), b"hello")
os.close(fd)

stop = True
t.join()
m.state = pysoem.INIT_STATE
m.write_state()
m.close()
print("FAILED: " + ", ".join(failures) if failures else "all checks passed")
sys.exit(1 if failures else 0)
