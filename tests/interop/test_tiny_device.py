"""The out-of-tree example device (examples/tiny_device), built against an installed rackcat
(tests/install/test_install.sh: cmake --install into a fresh prefix, then find_package), reaches
OP under pysoem over a veth pair and its one TxPDO counts in the process image."""
import os
import shlex
import subprocess
import time
from pathlib import Path

import pytest

from conftest import BUILD, REPO, go

pysoem = pytest.importorskip("pysoem", reason="pysoem not installed (scripts/setup.sh)")


@pytest.fixture(scope="module")
def tiny_device(tmp_path_factory):
    work = tmp_path_factory.mktemp("install")
    r = subprocess.run(["sh", str(REPO / "tests/install/test_install.sh"), str(BUILD), str(work)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"install and out-of-tree build failed:\n{r.stdout}\n{r.stderr}"
    exe = work / "tiny_device" / "tiny_device"
    assert exe.is_file()
    return exe


def test_installed_tiny_device_reaches_op(ecat_segment, tiny_device):
    iface, slave = ecat_segment(cmd=f"{shlex.quote(str(tiny_device))} --iface {{iface}}", pcap=False)
    master = pysoem.Master()
    master.open(iface)
    try:
        assert master.config_init() == 1
        dev = master.slaves[0]
        assert dev.name == "rackcat tiny device"
        assert (dev.man, dev.id, dev.rev) == (0, 0x7141, 1)
        # The PDO as a master reads it over CoE: 0x1C13 assigns 0x1A00, which maps 0x6000.
        assert int.from_bytes(dev.sdo_read(0x1C13, 1), "little") == 0x1A00
        assert int.from_bytes(dev.sdo_read(0x1A00, 1), "little") == 0x60000010
        master.config_map()
        assert len(dev.input) == 2 and len(dev.output) == 0
        go(master, pysoem.SAFEOP_STATE)
        master.send_processdata()
        master.receive_processdata(2000)
        master.state = pysoem.OP_STATE
        master.write_state()
        deadline = time.monotonic() + 5
        while master.state_check(pysoem.OP_STATE, 1000) != pysoem.OP_STATE:
            master.send_processdata()
            master.receive_processdata(2000)
            assert time.monotonic() < deadline, f"no OP: AL status {hex(dev.al_status)}"
        counts = []
        for _ in range(50):
            master.send_processdata()
            wkc = master.receive_processdata(2000)
            if wkc == 1:
                counts.append(int.from_bytes(dev.input, "little"))
            time.sleep(0.002)
        assert len(counts) >= 45, f"only {len(counts)} of 50 cycles with WKC 1"
        assert all(b != a for a, b in zip(counts, counts[1:])), counts
        go(master, pysoem.INIT_STATE)
    finally:
        master.close()
    assert slave.stop() == 0, slave.log()
