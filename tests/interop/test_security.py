"""[reliability] What `rackcat run` exposes: it keeps no privilege once its raw socket is open,
its control API cannot be reached from the EtherCAT wire, and nothing that arrives over the wire
or from its files makes it write outside its state directory.

Needs root (network namespace, veth, raw sockets); skips with a message otherwise.
"""
import os
import pwd
import socket
import struct
import subprocess
import tempfile
import time
from pathlib import Path

import pytest

from conftest import proc_status
from rackcat_helpers import (CONTROL_PORT, go, open_master, pysoem, rackcat,
                             store_parameters)

assert rackcat  # the fixture, imported for pytest


def check_no_capabilities(pid):
    st = proc_status(pid)
    assert st["Name"].startswith("rackcat"), st["Name"]
    for key in ("CapEff", "CapPrm", "CapInh", "CapAmb"):
        assert int(st[key], 16) == 0, f"{key} = {st[key]}"
    assert int(st["CapBnd"], 16) == 0, f"bounding set not emptied: {st['CapBnd']}"
    assert st["NoNewPrivs"] == "1"
    return st


def test_no_capabilities_after_socket_open_and_user_switch(rackcat, tmp_path):
    # As root without --user (and no SUDO_UID): uid stays, every capability is gone.
    env_sudo = os.environ.pop("SUDO_UID", None)
    try:
        rc = rackcat(pcap=False)
    finally:
        if env_sudo is not None:
            os.environ["SUDO_UID"] = env_sudo
    check_no_capabilities(rc.proc.proc.pid)
    master = open_master(rc.iface, 1)  # the socket still works without CAP_NET_RAW
    try:
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()

    # --user nobody: real, effective, saved and filesystem uid and gid all switched.
    nobody = pwd.getpwnam("nobody")
    state = _state_for(nobody, tmp_path)
    rc = rackcat(pcap=False, state_dir=state, extra=("--user", "nobody"))
    st = check_no_capabilities(rc.proc.proc.pid)
    assert st["Uid"].split() == [str(nobody.pw_uid)] * 4, st["Uid"]
    assert st["Gid"].split() == [str(nobody.pw_gid)] * 4, st["Gid"]
    assert st["Groups"] in ("", str(nobody.pw_gid)), f"supplementary groups kept: {st['Groups']}"
    master = open_master(rc.iface, 1)
    try:
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()


def _tcp_listeners(pid):
    """(local address hex, port) of every listening TCP socket of the process's namespace."""
    out = []
    for table in ("tcp", "tcp6"):
        lines = Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]
        for line in lines:
            fields = line.split()
            addr, port = fields[1].split(":")
            if fields[3] == "0A":  # TCP_LISTEN
                out.append((table, addr, int(port, 16)))
    return out


def test_control_api_listens_on_loopback_only(rackcat):
    rc = rackcat(pcap=False)
    # Give both ends of the EtherCAT veth pair an IPv4 address (a /30 unique to this run).
    n = os.getpid() % 250 + 1
    host_ip, slave_ip = f"10.231.{n}.1", f"10.231.{n}.2"
    subprocess.run(["ip", "addr", "add", f"{host_ip}/30", "dev", rc.iface], check=True)
    subprocess.run(rc.ns.exec_prefix() + ["ip", "addr", "add", f"{slave_ip}/30", "dev",
                                          rc.ns.slave_iface], check=True)
    # Positive control: a listener on every address inside the namespace is reachable from
    # the host over the veth pair, so a refusal below is the control API's doing.
    probe_port = CONTROL_PORT + 1
    probe = subprocess.Popen(rc.ns.exec_prefix() + [
        "python3", "-c",
        "import socket\n"
        f"s = socket.create_server(('0.0.0.0', {probe_port}))\n"
        "s.settimeout(20)\n"
        "c, _ = s.accept(); c.sendall(b'reachable'); c.close()"])
    try:
        got = b""
        deadline = time.monotonic() + 10
        while not got:
            try:
                with socket.create_connection((slave_ip, probe_port), timeout=2) as c:
                    got = c.recv(64)
            except (ConnectionRefusedError, socket.timeout):
                assert time.monotonic() < deadline, "the veth address is not reachable at all"
                time.sleep(0.1)
        assert got == b"reachable"
    finally:
        probe.kill()
        probe.wait()

    with pytest.raises(ConnectionRefusedError):
        socket.create_connection((slave_ip, CONTROL_PORT), timeout=5).close()
    # The listening socket is bound to 127.0.0.1 (0100007F), nothing on 0.0.0.0 or IPv6.
    listeners = [x for x in _tcp_listeners(rc.proc.proc.pid) if x[2] == CONTROL_PORT]
    assert listeners == [("tcp", "0100007F", CONTROL_PORT)], listeners
    # ... and it answers there.
    assert rc.ctl("GET", "/api/esm")["state"] == "INIT"
    rc.stop()


def _tree(root):
    return {p.relative_to(root): p.is_symlink() for p in Path(root).rglob("*")}



def test_nothing_written_outside_the_state_directory(rackcat, tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    victims = {name: outside / name for name in ("tmp-target", "bin-target")}
    for path in victims.values():
        path.write_bytes(b"must stay as it is")
    # The state directory given with a ".." component, and prepared by someone hostile:
    # the store's temp file and the parameter file are symlinks to files outside it.
    (tmp_path / "sub").mkdir()
    state = tmp_path / "state"
    state.mkdir()
    (state / "parameters.bin.tmp").symlink_to(victims["tmp-target"])
    (state / "parameters.bin").symlink_to(victims["bin-target"])
    rc = rackcat(pcap=False, state_dir=tmp_path / "sub" / ".." / "state")
    before = _tree(tmp_path)

    master = open_master(rc.iface, 1)
    try:
        s = master.slaves[0]
        # Values from the wire that look like paths are refused or stored as plain bytes.
        s.sdo_write(0x2000, 9, struct.pack("<I", 0x0000FF0F))
        try:
            s.sdo_write(0x2000, 4, b"../../../../tmp/x")
        except pysoem.SdoError:
            pass
        # Either stored (0) in a plain file of its own or refused with an I/O error (2).
        statuses = [store_parameters(s) for _ in range(2)]
        assert set(statuses) <= {0, 2}, statuses
        stored_ok = statuses[-1] == 0
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()

    for name, path in victims.items():
        assert path.read_bytes() == b"must stay as it is", f"{name} written through a symlink"
    after = _tree(tmp_path)
    new = sorted(str(p) for p in after if p not in before)
    assert new == [], f"files created: {new}"
    if stored_ok:
        # The store replaced the symlinks by its own plain file (rename does not follow).
        assert sorted(p.name for p in state.iterdir()) == ["control-port", "control-token",
                                                           "parameters.bin"]
        assert not (state / "parameters.bin").is_symlink()


# --- the privilege drop covers every thread -----------------------------------------------------

def _every_task(pid):
    """/proc/PID/task/*/status of every thread of the process."""
    tasks = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        fields = {}
        for line in (task / "status").read_text().splitlines():
            key, _, value = line.partition(":")
            fields[key] = value.strip()
        tasks[task.name] = fields
    return tasks


def _state_for(user, tmp_path, mode=0o700):
    """A state directory `user` can reach (pytest's own directories are root's, mode 0700)."""
    base = Path(tempfile.mkdtemp(prefix="rackcat-sec-"))
    base.chmod(0o755)
    state = base / "state"
    state.mkdir()
    if user is not None:
        os.chown(state, user.pw_uid, user.pw_gid)
    state.chmod(mode)
    (tmp_path / "state-link").symlink_to(base)  # removed with tmp_path; base by the test
    return state


def _check_tasks(pid, uid, min_threads, bounding=True):
    tasks = _every_task(pid)
    # Parameter workers (one per slave), the control API and the UART pseudo-terminals run
    # beside the device thread: all of them must show the drop.
    assert len(tasks) >= min_threads, f"only {len(tasks)} threads: {sorted(tasks)}"
    for tid, st in tasks.items():
        # Without CAP_SETPCAP (started unprivileged) the bounding set cannot be emptied;
        # NoNewPrivs then keeps execve from gaining anything.
        for key in ("CapEff", "CapPrm", "CapInh", "CapAmb") + (("CapBnd",) if bounding else ()):
            assert int(st[key], 16) == 0, f"task {tid} ({st['Name']}): {key} = {st[key]}"
        assert st["NoNewPrivs"] == "1", f"task {tid} ({st['Name']}): NoNewPrivs {st['NoNewPrivs']}"
        assert st["Uid"].split() == [str(uid)] * 4, f"task {tid}: Uid {st['Uid']}"
    return len(tasks)


def test_every_thread_drops_privileges_as_root_with_user(rackcat, tmp_path):
    nobody = pwd.getpwnam("nobody")
    state = _state_for(nobody, tmp_path)
    rc = rackcat(slaves=3, pcap=False, state_dir=state, extra=("--user", "nobody"))
    _check_tasks(rc.proc.proc.pid, nobody.pw_uid, min_threads=5)
    rc.stop()


def test_every_thread_drops_cap_net_raw_when_started_unprivileged(rackcat, tmp_path):
    # Started as nobody with CAP_NET_RAW only (inheritable + ambient, as a service manager's
    # AmbientCapabilities= would): once the socket is open no thread keeps it.
    nobody = pwd.getpwnam("nobody")
    state = _state_for(nobody, tmp_path)
    prefix = ["setpriv", f"--reuid={nobody.pw_uid}", f"--regid={nobody.pw_gid}",
              "--clear-groups", "--inh-caps=+net_raw", "--ambient-caps=+net_raw"]
    rc = rackcat(slaves=2, pcap=False, state_dir=state, prefix=prefix)
    _check_tasks(rc.proc.proc.pid, nobody.pw_uid, min_threads=3, bounding=False)
    master = open_master(rc.iface, 2)  # the socket opened before the drop still works
    try:
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()


def test_store_into_a_root_owned_read_only_state_directory_fails(rackcat, tmp_path):
    # Item 5: the writer thread kept root's capabilities and stored into a mode-0500 root
    # directory. As nobody the store must fail (status 2) and leave the directory empty.
    state = _state_for(None, tmp_path, 0o500)  # root's, r-x for root only
    rc = rackcat(pcap=False, state_dir=state, extra=("--user", "nobody", "--no-control"))
    master = open_master(rc.iface, 1)
    try:
        assert store_parameters(master.slaves[0]) == 2
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    rc.stop()
    assert list(state.iterdir()) == []


# --- a VLAN-tagged request is answered tagged, at full length --------------

SOL_PACKET = 263
PACKET_AUXDATA = 8
TP_STATUS_VLAN_VALID = 0x10
PACKET_OUTGOING = 4


def test_vlan_tagged_request_is_answered_tagged(rackcat):
    rc = rackcat(pcap=True)
    tci = (5 << 13) | 42  # priority 5, VLAN 42
    # BRD of register 0x0000 (type, revision), ETG.1000.4 §5.4: header, 2 data bytes, WKC.
    datagram = struct.pack("<BBHHHH", 0x07, 0x11, 0, 0x0000, 2, 0) + b"\0\0" + b"\0\0"
    ecat = struct.pack("<H", len(datagram) | 0x1000) + datagram
    src = bytes.fromhex("020000000a01")
    frame = b"\xff" * 6 + src + struct.pack("!HHH", 0x8100, tci, 0x88A4) + ecat
    frame += b"\0" * (64 - len(frame))
    s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x0003))
    s.bind((rc.iface, 0))
    s.setsockopt(SOL_PACKET, PACKET_AUXDATA, 1)
    s.settimeout(0.2)
    seen = []
    try:
        got = None
        deadline = time.monotonic() + 5
        while got is None and time.monotonic() < deadline:
            s.send(frame)
            end = time.monotonic() + 0.5
            while time.monotonic() < end:
                try:
                    data, anc, _, addr = s.recvmsg(2048, socket.CMSG_SPACE(32))
                except socket.timeout:
                    break
                seen.append((addr[2], data[:20].hex(), [(a, b, c.hex()) for a, b, c in anc]))
                if addr[2] == PACKET_OUTGOING or len(data) < 14:
                    continue
                vlan = None
                for level, kind, payload in anc:
                    if level == SOL_PACKET and kind == PACKET_AUXDATA:
                        status, _, _, _, _, vtci, vtpid = struct.unpack("<IIIHHHH", payload[:20])
                        if status & TP_STATUS_VLAN_VALID:
                            vlan = (vtpid or 0x8100, vtci)
                # The kernel strips the tag on our side too: the frame is 4 bytes short here and
                # the tag is in PACKET_AUXDATA; a tag left in the data shows as 0x8100.
                if data[12:14] == b"\x81\x00":
                    vlan = (0x8100, struct.unpack("!H", data[14:16])[0])
                    data = data[:12] + data[16:]
                if data[12:14] != b"\x88\xa4" or data[6:12] == src and vlan is None:
                    continue
                if data[16] == 0x07 and data[17] == 0x11:
                    got = (data, vlan)
                    break
    finally:
        s.close()
    rc.stop()
    assert got is not None, f"no answer to the tagged BRD; seen {seen[:6]}"
    data, vlan = got
    assert vlan == (0x8100, tci), f"answered untagged or with another tag: {vlan}"
    assert len(data) + 4 == len(frame), f"answer {len(data) + 4} bytes, request {len(frame)}"
    assert struct.unpack("<H", data[14 + 2 + 10 + 2:14 + 2 + 10 + 4])[0] == 1  # WKC: one slave


# --- kill -9 loses at most 100 ms of capture ----------------------------------

def _pcap_times(path):
    data = Path(path).read_bytes()
    assert data[:4] == struct.pack("<I", 0xA1B23C4D), "not a nanosecond pcap"
    times = []
    pos = 24
    while pos + 16 <= len(data):
        sec, nsec, incl, _ = struct.unpack("<IIII", data[pos:pos + 16])
        if pos + 16 + incl > len(data):
            break  # a record cut by the kill
        times.append(sec + nsec / 1e9)
        pos += 16 + incl
    return times


def test_kill_9_loses_at_most_100_ms_of_capture(rackcat):
    import signal
    rc = rackcat(pcap=True)
    master = open_master(rc.iface, 1)
    try:
        master.config_map()
        go(master, pysoem.SAFEOP_STATE)
        end = time.monotonic() + 1.5
        while time.monotonic() < end:
            master.send_processdata()
            master.receive_processdata(20_000)
            time.sleep(0.001)
        last_sent = time.time()
        os.kill(rc.proc.proc.pid, signal.SIGKILL)
        rc.proc.proc.wait(timeout=10)
    finally:
        master.close()
    times = _pcap_times(rc.pcap)
    assert len(times) > 500, f"only {len(times)} frames captured"
    lost = last_sent - times[-1]
    print(f"capture: {len(times)} frames, last one {lost * 1000:.1f} ms before the kill")
    assert lost <= 0.100, f"{lost * 1000:.0f} ms of frames lost on kill -9"
