"""The master developers' package (python/rackcat_line) as a master developer uses it: its
pytest fixture starts rackcat on a virtual line, pysoem drives the slave to OP on the handed
interface, and the control API calls change what the master sees and read the diagnosis
history. (The other interop tests use the package too: conftest.VethNamespace is its
rackcat_line.netns.Namespace.)"""
import time

import pytest

pysoem = pytest.importorskip("pysoem")


def _go_op(master):
    assert master.config_init() == 1
    master.config_map()
    master.state = pysoem.SAFEOP_STATE
    master.write_state()
    assert master.state_check(pysoem.SAFEOP_STATE, 2_000_000) == pysoem.SAFEOP_STATE
    master.state = pysoem.OP_STATE
    master.write_state()
    for _ in range(200):
        master.send_processdata()
        master.receive_processdata(2000)
        if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
            return
        time.sleep(0.001)
    raise AssertionError(f"no OP: AL status 0x{master.slaves[0].al_status:04X}")


def test_fixture_line_reaches_op_and_control_api_acts(rackcat_line):
    master = pysoem.Master()
    master.open(rackcat_line.master_iface)
    try:
        _go_op(master)
        # A constant on CAI-15 (module 14) channel 2 shows up in the module's live values.
        module = rackcat_line.control.set_channel(module=14, channel=2, value=1.25)
        assert module["inputs"][2]["value"] == pytest.approx(1.25, abs=0.01), module["inputs"][2]
        # Unplugging RIM 2 is seen in the rack state and logged by rackcat.
        rackcat_line.control.unplug_rim(2)
        rack = rackcat_line.control.rack()
        rims = {r["rim"]: r for r in rack["rims"]}
        assert rims[2]["state"].lower() == "offline", rims[2]
        for _ in range(100):
            master.send_processdata()
            master.receive_processdata(2000)
            time.sleep(0.001)
        rackcat_line.control.replug_rim(2)
        # An unsafe wiring fault on CDO-10 (module 1) channel 3 is in the diagnosis history.
        rackcat_line.control.wiring_fault(module=1, channel=3, fault="unsafe")
        messages = rackcat_line.control.diagnosis_messages()
        assert any(m["module"] == 1 and m["channel"] == 3 and m["type"] == "error"
                   for m in messages), messages
    finally:
        master.close()
    # The log is written by rackcat's logging thread: wait for it, generously.
    deadline = time.monotonic() + 5
    while not all(x in rackcat_line.log() for x in ("RIM 2 ONLINE -> OFFLINE", "ESM SAFEOP -> OP")):
        assert time.monotonic() < deadline, rackcat_line.log()
        time.sleep(0.05)


def test_control_errors_are_exceptions_with_the_api_reason(rackcat_line):
    from rackcat_line import ControlError
    with pytest.raises(ControlError) as e:
        rackcat_line.control.unplug_rim(7)
    assert e.value.status == 400
    assert "rim" in e.value.reason
    # Wrong methods: 405 with a JSON reason, for every method.
    for method in ("POST", "PUT", "DELETE", "PATCH"):
        with pytest.raises(ControlError) as e:
            rackcat_line.control.request(method, "/api/rack", {} if method != "DELETE" else None)
        assert e.value.status == 405, (method, e.value)
        assert e.value.reason, "a 405 carries a JSON reason"
