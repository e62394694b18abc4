"""A raw AF_PACKET socket on the master end of a veth pair, for the interop tests that craft
frames a master library does not send (ETG.1000.4 §5: frame header, datagram header, working
counter) or that touch registers behind the master's back (e.g. the process-data watchdog time
0x0420 while the control API is asked)."""
import select
import socket
import struct
import time

ETHERTYPE_ECAT = 0x88A4
PACKET_OUTGOING = 4  # sll_pkttype of frames this host sends (the tap sees them too)

# Datagram commands (ETG.1000.4 Table 10).
APRD, APWR, FPRD, FPWR, BRD, BWR, LRD, LRW = 0x01, 0x02, 0x04, 0x05, 0x07, 0x08, 0x0A, 0x0C


def dgram(cmd, idx, address, data, more=False, length=None):
    """One datagram: header (cmd, idx, 32-bit address = ADP/ADO or logical, length with the
    "more follows" bit 15, IRQ), data, working counter 0."""
    n = len(data) if length is None else length
    return struct.pack("<BBIHH", cmd, idx, address, (n & 0x7FF) | (0x8000 if more else 0), 0) \
        + bytes(data) + b"\0\0"


def phys(adp, ado):
    return (ado << 16) | adp


class RawMaster:
    """A raw socket on the master end of the veth pair: sends crafted frames, returns the
    frame the segment sends back."""

    def __init__(self, iface):
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHERTYPE_ECAT))
        self.sock.bind((iface, ETHERTYPE_ECAT))
        self.mac = self.sock.getsockname()[4]
        self.idx = 0x80  # SOEM uses indices 0..15: stale replies never look like its own

    def close(self):
        self.sock.close()

    def next_idx(self):
        self.idx = 0x80 + (self.idx + 1) % 0x80
        return self.idx

    def frame(self, payload, ecat_len=None):
        n = len(payload) if ecat_len is None else ecat_len
        return b"\xff" * 6 + self.mac + struct.pack(">H", ETHERTYPE_ECAT) + \
            struct.pack("<H", (n & 0x7FF) | 0x1000) + payload

    def _drain(self):
        while select.select([self.sock], [], [], 0)[0]:
            self.sock.recv(4096)

    def exchange(self, frame, timeout_s=1.0):
        """Sends `frame` (unpadded: veth carries short frames as they are) and returns the
        returned frame of the same length and first 18 bytes apart from the source MAC, or None."""
        self._drain()
        self.sock.send(frame)
        deadline = time.monotonic() + timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.sock], [], [], left)[0]:
                return None
            data, addr = self.sock.recvfrom(4096)
            if addr[2] == PACKET_OUTGOING:
                continue
            if len(data) == len(frame) and data[:6] == frame[:6] and data[12:18] == frame[12:18]:
                return data

    def datagram(self, cmd, address, data):
        """One well-formed datagram in its own frame: (working counter, data)."""
        idx = self.next_idx()
        reply = self.exchange(self.frame(dgram(cmd, idx, address, data)))
        assert reply is not None, f"no reply to command {cmd} at 0x{address:08X}"
        n = len(data)
        return struct.unpack_from("<H", reply, 26 + n)[0], reply[26:26 + n]

    def aprd(self, ado, n, pattern=0):
        return self.datagram(APRD, phys(0, ado), bytes([pattern]) * n)

    def apwr(self, ado, data):
        return self.datagram(APWR, phys(0, ado), data)[0]

    def fprd(self, station, ado, n):
        return self.datagram(FPRD, phys(station, ado), bytes(n))

    def fpwr(self, station, ado, data):
        return self.datagram(FPWR, phys(station, ado), data)[0]

    def brd(self, ado, n):
        return self.datagram(BRD, phys(0, ado), bytes(n))

    def bwr(self, ado, data):
        return self.datagram(BWR, phys(0, ado), data)[0]

    def reg16(self, ado):
        wkc, data = self.aprd(ado, 2)
        assert wkc == 1, f"APRD 0x{ado:04X} working counter {wkc}"
        return struct.unpack("<H", data)[0]


def ecat_datagrams(reply):
    """(command, idx, working counter, data) of each complete datagram of a returned frame."""
    out, pos = [], 16
    while pos + 12 <= len(reply):
        cmd, idx, _addr, ln, _irq = struct.unpack_from("<BBIHH", reply, pos)
        n = ln & 0x7FF
        if pos + 12 + n > len(reply):
            break
        out.append((cmd, idx, struct.unpack_from("<H", reply, pos + 10 + n)[0],
                    reply[pos + 10:pos + 10 + n]))
        pos += 12 + n
        if not ln & 0x8000:
            break
    return out
