"""rackcat's side of a conversation, from the capture `rackcat run --pcap` wrote: the CoE
messages it put into its send mailbox (SM1), so a step that failed because of the master can
still assert what rackcat answered.

Layouts: pcap (classic, libpcap), Ethernet II with EtherType 0x88A4, the EtherCAT frame header
and datagrams (ETG.1000.4 §5.3/5.4), the mailbox header (ETG.1000.4 §5.6: length, address,
channel/priority, type/counter), the CoE header (ETG.1000.6 §5.6.1: number, service) and the
SDO information header (ETG.1000.6 §5.6.3.2: opcode, fragments left).
"""
import struct

FPRD = 4
COE = 3
COE_EMERGENCY = 1
COE_SDO_INFO = 8
INFO_OD_LIST_RESPONSE = 2


def frames(pcap):
    data = open(pcap, "rb").read()
    magic = struct.unpack_from("<I", data, 0)[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    pos = 24
    while pos + 16 <= len(data):
        _, _, incl, _ = struct.unpack_from(endian + "IIII", data, pos)
        yield data[pos + 16:pos + 16 + incl]
        pos += 16 + incl


def slave_mailbox_reads(pcap, send_mbx_offset):
    """(station address, mailbox bytes) of every FPRD of the send mailbox in a frame rackcat
    returned (source MAC with the locally-administered bit, as an ESC sets it)."""
    for f in frames(pcap):
        if len(f) < 16 or f[12:14] != b"\x88\xa4" or not f[6] & 0x02:
            continue
        pos = 16
        end = 16 + (struct.unpack_from("<H", f, 14)[0] & 0x07FF)
        while pos + 10 <= min(end, len(f)):
            cmd, _, adp, ado, lf = struct.unpack_from("<BBHHH", f, pos)
            n = lf & 0x07FF
            payload = f[pos + 10:pos + 10 + n]
            wkc = struct.unpack_from("<H", f, pos + 10 + n)[0] if pos + 12 + n <= len(f) else 0
            if cmd == FPRD and ado == send_mbx_offset and wkc:
                yield adp, payload
            pos += 12 + n
            if not lf & 0x8000:  # "more datagrams follow"
                break


def coe_messages(pcap, send_mbx_offset):
    """(station, CoE service, CoE body) of every CoE message rackcat sent."""
    seen = set()
    for station, mbx in slave_mailbox_reads(pcap, send_mbx_offset):
        if len(mbx) < 8:
            continue
        length, _, _, type_cnt = struct.unpack_from("<HHBB", mbx, 0)
        if type_cnt & 0x0F != COE or length < 2 or 6 + length > len(mbx):
            continue
        # a master re-reading a full mailbox sees the same message twice (same counter)
        key = (station, bytes(mbx[:6 + length]))
        if key in seen:
            continue
        seen.add(key)
        coe = struct.unpack_from("<H", mbx, 6)[0]
        yield station, coe >> 12, bytes(mbx[8:6 + length])


def emergencies(pcap, send_mbx_offset):
    """[(station, error code, error register)] of the Emergencies rackcat sent."""
    return [(st, *struct.unpack_from("<HB", body, 0))
            for st, service, body in coe_messages(pcap, send_mbx_offset)
            if service == COE_EMERGENCY and len(body) >= 3]


def od_lists(pcap, send_mbx_offset):
    """{station: [indices]} of the Get OD List (all objects) responses rackcat sent: the list
    type in the first fragment only (ETG.1000.6 §5.6.3.3.2), then UINT indices."""
    lists, current = {}, {}
    for st, service, body in coe_messages(pcap, send_mbx_offset):
        if service != COE_SDO_INFO or len(body) < 4:
            continue
        opcode, _, left = struct.unpack_from("<BBH", body, 0)
        if opcode & 0x7F != INFO_OD_LIST_RESPONSE:
            continue
        payload = body[4:]
        if st not in current:
            list_type = struct.unpack_from("<H", payload, 0)[0]
            current[st] = {"type": list_type, "indices": []}
            payload = payload[2:]
        current[st]["indices"] += list(struct.unpack_from(f"<{len(payload) // 2}H", payload))
        if left == 0:
            done = current.pop(st)
            if done["type"] == 1:  # all objects
                lists[st] = done["indices"]
    return lists


COE_SDO_RESPONSE = 3


def sdo_uploads(pcap, send_mbx_offset):
    """The SDO uploads rackcat answered, as dicts (station, index, sub, ca, size, data,
    complete): the initiate response and, for a segmented one, the segments that followed
    (ETG.1000.6 §5.6.2.4/5.6.2.5: normal/segmented initiate: complete size (4 bytes), then
    data; a segment: 7 data bytes at most, unused count in bits 3..1, last-segment bit 0)."""
    done, open_ = [], {}
    for st, service, body in coe_messages(pcap, send_mbx_offset):
        if service != COE_SDO_RESPONSE or len(body) < 1:
            continue
        cmd = body[0]
        scs = cmd >> 5
        if scs == 2 and len(body) >= 8:  # initiate upload response
            index, sub = struct.unpack_from("<HB", body, 1)
            up = {"station": st, "index": index, "sub": sub, "ca": bool(cmd & 0x10)}
            if cmd & 0x02:  # expedited
                n = 4 - ((cmd >> 2) & 0x03) if cmd & 0x01 else 4
                done.append(dict(up, size=n, data=body[4:4 + n], complete=True))
                continue
            size = struct.unpack_from("<I", body, 4)[0]
            data = bytearray(body[8:8 + size])
            up.update(size=size, data=data, complete=len(data) >= size)
            done.append(up)
            if not up["complete"]:
                open_[st] = up
        elif scs == 0 and st in open_:  # upload segment response
            up = open_[st]
            if len(body) == 8:
                up["data"] += body[1:8 - ((cmd >> 1) & 0x07)]
            else:
                up["data"] += body[1:]
            if cmd & 0x01:
                up["complete"] = len(up["data"]) >= up["size"]
                del open_[st]
    return done


INFO_ED_RESPONSE = 6


def entry_descriptions(pcap, send_mbx_offset):
    """{(index, subindex): (value info, data type, bit length, default value or None, name)}
    of the Get Entry Description responses rackcat sent (ETG.1000.6 §5.6.3.6.3: the optional
    unit type, default, minimum, maximum values precede the name as value info selects)."""
    out = {}
    for _, service, body in coe_messages(pcap, send_mbx_offset):
        if service != COE_SDO_INFO or len(body) < 14 or body[0] & 0x7F != INFO_ED_RESPONSE:
            continue
        index, sub, info, dtype, bits, _ = struct.unpack_from("<HBBHHH", body, 4)
        pos = 14
        if info & 0x08:
            pos += 2
        default = None
        n = (bits + 7) // 8
        if info & 0x10:
            default = body[pos:pos + n]
            pos += n
        if info & 0x20:
            pos += n
        if info & 0x40:
            pos += n
        out[(index, sub)] = (info, dtype, bits, default, body[pos:].decode(errors="replace"))
    return out
