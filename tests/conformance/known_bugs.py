"""Failures of the matrix that are the master's bug, with the evidence, and what rackcat did
there, asserted from the capture instead (docs/INTEROP.md "Master bugs").

A fail cell whose text matches `match` becomes "master bug" in the table and the rackcat-side
check runs on the cell's capture; when a fixed master release passes the step, the entry is
reported as stale so it can be removed. `reproducer` is the smallest program showing the bug
(tests/conformance/reproducers/), kept so a fixed release can be adopted.
"""
import re
import struct
from dataclasses import dataclass
from typing import Callable

import capture


@dataclass
class Bug:
    match: str
    evidence: str
    rackcat_side: Callable  # (pcap, expectations) -> text; raises AssertionError
    reproducer: str = ""


def _send_mbx(exp):
    return exp["sii_words"][0x1A]  # SII word 0x1A: standard send mailbox offset (ETG.2010)


def od_list_in_capture(pcap, exp):
    lists = capture.od_lists(pcap, _send_mbx(exp))
    assert lists, "no Get OD List response in the capture"
    for station, indices in lists.items():
        assert sorted(indices) == exp["od_indices"], \
            f"station 0x{station:04X}: {len(indices)} indices sent, expected " \
            f"{len(exp['od_indices'])}"
    return f"rackcat sent all {len(exp['od_indices'])} indices (capture)"


def emergency_in_capture(pcap, exp):
    code = exp["emergency"]["code"]
    got = capture.emergencies(pcap, _send_mbx(exp))
    assert any(c == code and reg & 0x01 for _, c, reg in got), \
        f"no Emergency 0x{code:04X} with the generic error bit in the capture: {got}"
    return f"rackcat sent Emergency 0x{code:04X} (capture)"


def segmented_upload_in_capture(pcap, exp):
    """The initiate response of the complete-access upload of 0x2000: segmented (complete
    size > what the mailbox holds), the size of the object, the data starting with subindex
    0 (15) and its padding byte, then the part number."""
    ups = [u for u in capture.sdo_uploads(pcap, _send_mbx(exp)) if u["index"] == 0x2000 and
           u["ca"]]
    assert ups, "no complete-access upload of 0x2000 in the capture"
    up = ups[-1]
    # the object's bit size has subindex 0 in 16 bits; from subindex 1 on it is left out
    want = exp["ca_2000_bytes"] - (2 if up["sub"] == 1 else 0)
    assert up["size"] == want, f"complete size {up['size']}, expected {want}"
    data = bytes(up["data"])
    assert len(data) < up["size"] or up["complete"], "not a segmented upload"
    head = exp["part_number"].encode()
    if up["sub"] == 0:
        head = b"\x0f\x00" + head
    assert data.startswith(head), f"first bytes {data[:16].hex()}"
    if up["complete"]:
        assert len(data) == up["size"], f"{len(data)} bytes in the segments"
    return (f"rackcat's initiate response: complete size {up['size']}, {len(data)} data "
            f"bytes from subindex 0 on (capture)")


BUGS = {
    ("soemx", "sdo_info_list"): Bug(
        match=r"1 indices, expected",
        evidence="soemx 0.1.1 `soemx_read_od_entry` (soemx_native.c) takes the return value "
                 "of SOEM 2.x `ecx_readODlist` - the working counter, 1 - as the number of "
                 "objects instead of `od.Entries`, so `sdo_info()` lists only the first object "
                 "(it also re-reads the whole list for every object)",
        rackcat_side=od_list_in_capture,
        reproducer="reproducers/soemx_sdo_info.py"),
    ("soemx", "emergency"): Bug(
        match=r"no Emergency 0x4210; got \['0x94210'",
        evidence="soemx 0.1.1 `Master.pop_error` builds `Emergency(slave, abort_code, ...)` "
                 "from SOEM's `ec_errort`, where the 32-bit `AbortCode` overlays `ErrorCode` "
                 "(16 bits), `ErrorReg` and `b1`: `error_code` is 0x94210 = error register "
                 "0x09 << 16 | 0x4210",
        rackcat_side=emergency_in_capture,
        reproducer="reproducers/soemx_emergency.py"),
}


BUGS[("kickcat", "sdo_upload_segmented")] = Bug(
    match=r"died with SIGSEGV",
    evidence="KickCAT 2.5 `SDOMessage::processUpload` (lib/src/CoE/mailbox/request.cc), "
             "segmented branch: after the complete size it reads a second UINT32 'size' "
             "where ETG.1000.6 §5.6.2.4 puts the first data bytes, and copies that many bytes "
             "(0x4946000F for 0x2000: subindex 0 = 15, then 'FI') into the client buffer: "
             "segmentation fault",
    rackcat_side=segmented_upload_in_capture,
    reproducer="reproducers/kickcat_segmented_upload.py")


def abort_in_capture(pcap, exp):
    aborts = [(st, *struct.unpack_from("<HBI", body, 1))
              for st, service, body in capture.coe_messages(pcap, _send_mbx(exp))
              if service == 2 and body[:1] == b"\x80"]
    assert any(a[1:] == (0x1234, 0, 0x06020000) for a in aborts), \
        f"no abort 0x06020000 for 0x1234:00 (CoE service 2, command 0x80) in the capture: {aborts}"
    return "rackcat sent abort 0x06020000 for 0x1234:00 (capture)"


def entry_descriptions_in_capture(pcap, exp):
    eds = capture.entry_descriptions(pcap, _send_mbx(exp))
    checked = 0
    for key in ("0x1018", "0x2000", "0x1C12"):
        for sub, want in exp["objects"][key]["entries"].items():
            got = eds.get((int(key, 16), int(sub)))
            if got is None:
                continue
            info, dtype, bits, default, name = got
            assert (dtype, bits, name) == (want["data_type"], want["bit_size"], want["name"]), \
                f"{key}:{sub}: {got}"
            assert not info & 0x10 or len(default) == (bits + 7) // 8, f"{key}:{sub} default"
            checked += 1
    assert checked, "no entry description response in the capture"
    return f"rackcat's {checked} entry descriptions: value info, default value, name (capture)"


BUGS[("kickcat", "sdo_abort")] = Bug(
    match=r"Error while reading SDO - Timeout",
    evidence="KickCAT 2.5 takes the abort but does not report it: `Bus::readSDO` "
             "(lib/master/src/CoE.cc) throws 'Error while reading SDO' only for a finished "
             "message whose status is neither SUCCESS nor TIMEDOUT - here the abort code - and "
             "the Python exception renders that status as 'Timeout', without the code; "
             "rackcat's abort (CoE service 2, command 0x80, 0x1234:00, 0x06020000, ETG.1000.6 "
             "§5.6.2.7) is in the capture, and SOEM (pysoem, soemx, pyecm) and ethercrab "
             "decode the same abort",
    rackcat_side=abort_in_capture,
    reproducer="reproducers/kickcat_abort.py")
BUGS[("kickcat", "sdo_info_desc")] = Bug(
    match=r"name starts with the \d+-byte default value|name not decodable",
    evidence="KickCAT 2.5 `Bus.read_entry_description` asks for the default value (value "
             "info 0x10) and returns everything after the fixed part as the name: the "
             "entry's default value comes first (ETG.1000.6 §5.6.3.6.3), e.g. "
             "'\\x01\\x00\\x00\\x00Serial number' for 0x1018:04; a default with bytes that "
             "are no UTF-8 (0x2000:09 = 0xFFFFFFFF) raises UnicodeDecodeError",
    rackcat_side=entry_descriptions_in_capture,
    reproducer="reproducers/kickcat_entry_description.py")


def assignment_in_capture(pcap, exp):
    """The PDO assignment rackcat answered while the master read it (0x1C12/0x1C13)."""
    ups = {(u["index"], u["sub"]): bytes(u["data"])
           for u in capture.sdo_uploads(pcap, _send_mbx(exp)) if not u["ca"]}
    seen = 0
    for index, pdos in ((0x1C12, exp["rx_assign"]), (0x1C13, exp["tx_assign"])):
        for k, want in enumerate([bytes([len(pdos)])] + [struct.pack("<H", p) for p in pdos]):
            got = ups.get((index, k))
            if got is not None:  # what the master asked before it gave up
                assert got == want, f"0x{index:04X}:{k:02X} = {got.hex()}, expected {want.hex()}"
                seen += 1
    assert seen, "no upload of 0x1C12/0x1C13 in the capture"
    return f"rackcat's {seen} answers from 0x1C12/0x1C13 = the rack (capture)"


def assignment_ca_in_capture(pcap, exp):
    """The complete-access uploads of 0x1C12/0x1C13 from subindex 1: initiate (and any
    segments the master asked for) agree with the rack's assignment."""
    seen = 0
    for u in capture.sdo_uploads(pcap, _send_mbx(exp)):
        key = {0x1C12: "ca_1c12", 0x1C13: "ca_1c13"}.get(u["index"])
        if key is None or not u["ca"]:
            continue
        want = bytes.fromhex(exp[key])[2 if u["sub"] == 1 else 0:]
        assert u["size"] == len(want), f"0x{u['index']:04X}: complete size {u['size']}"
        assert want.startswith(bytes(u["data"])), f"0x{u['index']:04X}: data differs"
        seen += 1
    assert seen, "no complete access of 0x1C12/0x1C13 in the capture"
    return f"rackcat's {seen} complete-access answers = the rack's assignment (capture)"


def download_abort_in_capture(pcap, exp):
    aborts = [(st, *struct.unpack_from("<HBI", body, 1))
              for st, service, body in capture.coe_messages(pcap, _send_mbx(exp))
              if service == 2 and body[:1] == b"\x80"]
    assert any(a[1:3] == (0x2000, 4) for a in aborts), \
        f"no abort for 0x2000:04 in the capture: {aborts}"
    return "rackcat refused the 0-byte value with an abort and kept 0x2000:04 (capture)"


BUGS[("ebpfcat", "sdo_download_normal")] = Bug(
    match=r"expected CoE SDORES, got 2",
    evidence="ebpfcat 1.0.0 `Terminal.sdo_write` packs a normal download as "
             "`\"HBHB4x\"` with command 0x21 (size indicated): the complete size is always 0, "
             "then the data (ETG.1000.6 §5.6.2.2: the complete size is the number of bytes); "
             "rackcat takes the 0-byte value and refuses it (0x06090030, no IPv4 address)",
    rackcat_side=download_abort_in_capture,
    reproducer="reproducers/ebpfcat_normal_download.py")
BUGS[("ebpfcat", "sdo_upload_segmented")] = Bug(
    match=r"TypeError: sequence item 1: expected a bytes-like object, int found",
    evidence="ebpfcat 1.0.0 `Terminal.sdo_read`, segmented upload: `ret += data[3:]` extends "
             "the list of byte strings with the segment's integers, so `b\"\".join(ret)` "
             "raises TypeError after the first segment",
    rackcat_side=segmented_upload_in_capture,
    reproducer="reproducers/ebpfcat_segmented_upload.py")
BUGS[("ebpfcat", "complete_access")] = Bug(
    match=BUGS[("ebpfcat", "sdo_upload_segmented")].match,
    evidence=BUGS[("ebpfcat", "sdo_upload_segmented")].evidence + " (here: the complete "
             "access of a PDO assignment longer than the mailbox)",
    rackcat_side=lambda pcap, exp: assignment_ca_in_capture(pcap, exp),
    reproducer="reproducers/ebpfcat_segmented_upload.py")
BUGS[("kickcat", "complete_access")] = Bug(
    match=BUGS[("kickcat", "sdo_upload_segmented")].match,
    evidence=BUGS[("kickcat", "sdo_upload_segmented")].evidence + " (here: the complete "
             "access of a PDO assignment longer than the mailbox)",
    rackcat_side=lambda pcap, exp: assignment_ca_in_capture(pcap, exp),
    reproducer="reproducers/kickcat_segmented_upload.py")
BUGS[("ebpfcat", "pdo_sizes")] = Bug(
    match=r"KeyError: 128",
    evidence="ebpfcat 1.0.0 `Terminal.parse_pdos` knows PDO entries of 1-7, 8, 16, 32 and 64 "
             "bits only (`{8: \"B\", 16: \"H\", 32: \"I\", 64: \"Q\"}[bits]`); the default "
             "and 120-module racks map 128-bit entries (ETG.1000.6 allows any length)",
    rackcat_side=lambda pcap, exp: assignment_in_capture(pcap, exp),
    reproducer="")


def classify(master, step, cell):
    """The Bug a fail cell is, or None."""
    bug = BUGS.get((master, step))
    if bug and cell["result"] == "fail" and re.search(bug.match, cell["detail"]):
        return bug
    return None
