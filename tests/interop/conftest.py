"""Fixtures for driving an emulated EtherCAT segment with a real master over a veth pair.

Each test gets a private network namespace holding one end of a veth pair; the slave process
runs inside the namespace on that end, and the master (pysoem, in the pytest process) uses the
other end, which stays in the host namespace under a unique name. Namespaces, interfaces and
processes are removed after every test, whatever happens.

The command that starts the slave is a template, so the same tests drive any slave program:

    pytest tests/interop                                   # build/ecat_wire_slave (default)
    pytest tests/interop --slave-cmd "build/rackcat run --iface {iface} --slaves {slaves}"

Placeholders: {iface} (slave end), {slaves} (segment size), {pcap} (capture file). Extra
arguments a test needs (--busy-poll, --pcap ...) are appended. RACKCAT_BUILD_DIR selects the
build directory (default: build).

Everything here needs root (netns, veth, raw sockets); the tests skip with a message otherwise.
"""
import os
import select
import shlex
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
try:  # installed into .venv by scripts/setup.sh (pip install -e python)
    from rackcat_line.netns import Namespace
except ImportError:  # pure Python: the checkout's copy serves as well
    sys.path.insert(0, str(REPO / "python"))
    from rackcat_line.netns import Namespace
BUILD = Path(os.environ.get("RACKCAT_BUILD_DIR", REPO / "build"))
if not BUILD.is_absolute():
    BUILD = REPO / BUILD
# The wire test slave (tests/ecat_wire_slave): hand-built SII, outputs looped back to inputs.
# (the path quoted: the template is split like a shell line, and a checkout path may hold spaces)
TEST_SLAVE_CMD = f"{shlex.quote(str(BUILD / 'ecat_wire_slave'))} --iface {{iface}} --slaves {{slaves}}"
DEFAULT_SLAVE_CMD = TEST_SLAVE_CMD
# The rackcat_line fixture (python/, the master developers' package) runs this build's rackcat.
os.environ.setdefault("RACKCAT_BIN", str(BUILD / "rackcat"))
ETHERTYPE_ECAT = 0x88A4


def pytest_addoption(parser):
    parser.addoption(
        "--slave-cmd",
        default=os.environ.get("RACKCAT_SLAVE_CMD", DEFAULT_SLAVE_CMD),
        help="command template that starts the slave: {iface} {slaves} placeholders",
    )


def _run(*cmd, check=True):
    return subprocess.run(cmd, check=check, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)


def require_root():
    if os.geteuid() != 0:
        pytest.skip("wire interop tests need root: they create a network namespace and a veth "
                    "pair and open raw sockets (run pytest as root, e.g. with sudo)")
    if shutil.which("ip") is None:
        pytest.skip("wire interop tests need iproute2 ('ip'); run scripts/setup.sh")


class VethNamespace(Namespace):
    """A private namespace with the slave end of a veth pair; the master end stays here. The
    master developers' package (python/rackcat_line, rackcat_line.netns) makes it: the project's
    interop tests are that package's test (issue 23)."""

    def __init__(self):
        super().__init__(prefix="rackcat-it")


def probe_brd(iface, timeout_s=10.0):
    """Sends BRD 0x0000 frames until a slave answers; returns the working counter."""
    s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHERTYPE_ECAT))
    try:
        s.bind((iface, ETHERTYPE_ECAT))
        mac = s.getsockname()[4]
        # Ethernet, EtherCAT header (length 12, type 1), BRD idx 0x5A ADP 0 ADO 0 len 2.
        dgram = struct.pack("<BBHHHH", 0x07, 0x5A, 0, 0, 2, 0) + b"\0\0" + b"\0\0"
        frame = b"\xff" * 6 + mac + struct.pack(">H", ETHERTYPE_ECAT) + \
            struct.pack("<H", len(dgram) | 0x1000) + dgram
        frame = frame.ljust(60, b"\0")
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            s.send(frame)
            end = time.monotonic() + 0.1
            while time.monotonic() < end:
                r, _, _ = select.select([s], [], [], max(0.0, end - time.monotonic()))
                if not r:
                    break
                reply, addr = s.recvfrom(2048)
                outgoing = addr[2] == socket.PACKET_OUTGOING  # our own frame, not a reply
                if not outgoing and len(reply) >= 30 and reply[6] & 0x02 and reply[17] == 0x5A:
                    return struct.unpack_from("<H", reply, 28)[0]
        return None
    finally:
        s.close()


class SlaveProcess:
    """The slave program running in the namespace, with its log and optional capture."""

    def __init__(self, ns, cmd_template, slaves, extra_args, pcap, log_path, prefix=()):
        self.ns = ns
        self.pcap = pcap
        self.log_path = log_path
        fields = {"iface": ns.slave_iface, "slaves": slaves, "pcap": pcap or ""}
        cmd = [part.format(**fields) for part in shlex.split(cmd_template)]
        cmd += list(extra_args)
        if pcap and "{pcap}" not in cmd_template:
            cmd += ["--pcap", str(pcap)]
        self.cmd = cmd
        self._log = open(log_path, "w")
        # `ip netns exec` and the optional prefix (setpriv ...) exec into the slave: the
        # process id is the slave's own.
        self.proc = subprocess.Popen(ns.exec_prefix() + list(prefix) + cmd, stdout=self._log,
                                     stderr=subprocess.STDOUT)
        self.returncode = None

    def log(self):
        if not self._log.closed:
            self._log.flush()
        return Path(self.log_path).read_text(errors="replace")

    def wait_ready(self, expected_slaves):
        wkc = probe_brd(self.ns.master_iface)
        if wkc is None:
            self.stop()
            pytest.fail(f"slave did not answer a BRD within 10 s: {self.cmd}\n{self.log()}")
        assert wkc == expected_slaves, f"BRD working counter {wkc}, expected {expected_slaves}"

    def stop(self, sig=signal.SIGTERM, timeout=10):
        if self.returncode is None:
            if self.proc.poll() is None:
                self.proc.send_signal(sig)
                try:
                    self.proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
            self.returncode = self.proc.returncode
            self._log.close()
        return self.returncode


@pytest.fixture
def slave_cmd(request):
    return request.config.getoption("--slave-cmd")


@pytest.fixture
def ecat_segment(slave_cmd, tmp_path):
    """Factory: ecat_segment(slaves=1, extra_args=(), pcap=True, prefix=(), cmd=None) ->
    (master_iface, slave). `cmd` overrides the --slave-cmd template for this start; `prefix`
    goes before the command (e.g. setpriv to start it as another user).

    Starts the slave in a fresh namespace and waits until it answers on the wire. Everything
    is torn down after the test.
    """
    require_root()
    started = []

    def start(slaves=1, extra_args=(), pcap=True, prefix=(), cmd=None):
        ns = VethNamespace().__enter__()
        started.append(ns)
        n = len(started)
        cap = tmp_path / f"segment{n}.pcap" if pcap else None
        slave = SlaveProcess(ns, cmd or slave_cmd, slaves, extra_args, cap,
                             tmp_path / f"slave{n}.log", prefix)
        started.append(slave)
        slave.wait_ready(slaves)
        return ns.master_iface, slave

    yield start
    for item in reversed(started):
        if isinstance(item, SlaveProcess):
            item.stop()
        else:
            item.__exit__(None, None, None)


def proc_status(pid):
    """/proc/PID/status as a dict (Uid, CapEff, ...)."""
    fields = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, value = line.partition(":")
        fields[key] = value.strip()
    return fields


def go(master, state, timeout_us=3_000_000):
    """Requests `state` of every slave (pysoem master) and waits for it; fails naming the
    first slaves' AL status and code."""
    master.state = state
    master.write_state()
    reached = master.state_check(state, timeout_us)
    master.read_state()
    detail = [(s.name, hex(s.state), hex(s.al_status)) for s in master.slaves[:4]]
    assert reached == state, f"state {hex(state)} not reached: {detail}"


SAFEOP_ERROR = 0x14  # AL status: SAFEOP with the error flag (ETG.1000.6 §5.3.2)


def wait_watchdog_safeop(master, timeout_s=5.0):
    """After the master fell silent in OP: reads the AL status (reads do not retrigger the SM2
    watchdog) until slave 0 reports SAFEOP with the error flag, for at most timeout_s; returns
    slave 0 with state and al_status read. The watchdog's timing is measured by
    test_master_loss.py; here only the outcome counts, so a slow machine gets a generous
    deadline instead of a fixed sleep."""
    s = master.slaves[0]
    deadline = time.monotonic() + timeout_s
    while True:
        master.read_state()
        if s.state == SAFEOP_ERROR or time.monotonic() > deadline:
            return s
        time.sleep(0.01)


def tshark_problems(pcap):
    """(total frames, frames dissected as EtherCAT, lines of malformed/error output)."""
    if shutil.which("tshark") is None:
        pytest.skip("tshark not installed (scripts/setup.sh installs it)")

    def lines(*args):
        out = _run("tshark", "-n", "-r", str(pcap), *args).stdout
        return [line for line in out.splitlines() if line.strip()]

    total = len(lines("-T", "fields", "-e", "frame.number"))
    ecat = len(lines("-Y", "ecat", "-T", "fields", "-e", "frame.number"))
    bad = lines("-Y", "_ws.malformed || _ws.expert.severity >= error")
    return total, ecat, bad
