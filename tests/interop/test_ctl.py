"""`rackcat ctl` against a running rack: every subcommand prints text by
default and the API's JSON with --json (before or after the command name); every answer to a
change shows the state after it; a refused request prints the API's reason and exits 2.

Needs root (network namespace, veth); skips otherwise. About 5 s (no master: the control API
answers in INIT).
"""
import json
import subprocess

from rackcat_helpers import CONTROL_PORT, RACKCAT, rackcat

assert rackcat  # the fixture, imported for pytest

SOUT = 1     # default rack: CDO-10 16xDout Source (detects wiring faults, guide 4.7)
AIN = 12     # CAI-11 8xAin
AOUT = 11    # CAO-15 8xAout
TC = 15      # CTP-11 8x K thermocouple
UART = 19    # CUR-12 4xUART

# Each subcommand with arguments that change something (or read), in the order they run.
COMMANDS = [
    ("list",),
    ("list", "--module", AIN),
    ("esm",),
    ("exceptions",),
    ("set", "--module", AIN, "--channel", 0, "--value", 3.5),
    ("set", "--module", AIN, "--channel", 1, "--source", "sine", "--param", "amplitude=1",
     "--param", "frequency=2"),
    ("unplug", "--rim", 2),
    ("replug", "--rim", 2),
    ("rim-state", "--rim", 2, "--state", "online"),
    ("mcm-error", "--rim", 1),
    ("fan", "--rim", 1, "--zone", "slot_card", "--rpm", 2000),
    ("cpu-temp", "--celsius", 47.5, "--now"),
    ("diag",),
    ("output-fault", "--module", AOUT, "--channel", 0, "--overload", "false"),
    ("wiring-fault", "--module", SOUT, "--channel", 3, "--fault", "none"),
    ("sensor", "--module", TC, "--channel", 0, "--close"),
    ("uart", "--module", UART, "--channel", 0, "--text", "hi"),
]


def ctl(rc, *args):
    cmd = rc.ns.exec_prefix() + [str(RACKCAT), "ctl", "--port", str(CONTROL_PORT),
                                 "--state-dir", str(rc.state_dir)] + [str(a) for a in args]
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          timeout=20)


def test_every_subcommand_prints_text_or_json(rackcat):
    rc = rackcat(pcap=False)
    for args in COMMANDS:
        text = ctl(rc, *args)
        assert text.returncode == 0, (args, text.stderr)
        assert text.stdout.strip(), args
        try:
            json.loads(text.stdout)
            raise AssertionError(f"ctl {args} printed JSON without --json:\n{text.stdout}")
        except json.JSONDecodeError:
            pass
        for where in ("before", "after"):
            full = ("--json",) + args if where == "before" else args + ("--json",)
            out = ctl(rc, *full)
            assert out.returncode == 0, (full, out.stderr)
            assert isinstance(json.loads(out.stdout), dict), full


def test_answers_show_the_state_after_the_change(rackcat):
    rc = rackcat(pcap=False)
    out = ctl(rc, "wiring-fault", "--module", SOUT, "--channel", 3, "--fault", "unsafe")
    assert out.returncode == 0, out.stderr
    assert "out3" in out.stdout and "wiring fault: unsafe" in out.stdout, out.stdout
    assert "errors 0xF384 0x00000008" in out.stdout, out.stdout  # channel 3 (guide 3.4)
    out = ctl(rc, "wiring-fault", "--module", SOUT, "--channel", 3, "--fault", "none")
    assert "errors 0xF384 0x00000000" in out.stdout, out.stdout
    out = ctl(rc, "set", "--module", AIN, "--channel", 2, "--value", -2.5)
    assert "in2   -2.5" in out.stdout, out.stdout
    out = ctl(rc, "fan", "--rim", 1, "--zone", "slot_card", "--rpm", 1500)
    assert "slot card 1500" in out.stdout, out.stdout
    out = ctl(rc, "cpu-temp", "--celsius", 61.2, "--now")
    assert "61.2 degC, 0x2000:0F publishes 61.0 degC" in out.stdout, out.stdout


def test_refusals_name_the_reason(rackcat):
    rc = rackcat(pcap=False)
    out = ctl(rc, "set", "--module", AIN, "--channel", 0, "--source", "sine", "--param",
              "amplitud=1")
    assert out.returncode == 2
    assert "unknown parameter 'amplitud'" in out.stderr, out.stderr
    out = ctl(rc, "mcm-error", "--rim", 1, "--error", "bogus")
    assert out.returncode == 2 and '"bogus"' in out.stderr, out.stderr
    # Every source a channel can take is listed in the help.
    helptext = subprocess.run([str(RACKCAT), "ctl", "set", "--help"], stdout=subprocess.PIPE,
                              text=True, check=True).stdout
    for kind in ("constant", "ramp", "sine", "noise", "replay", "loopback", "plant", "clock"):
        assert kind in helptext, kind
    # The raw API: a misspelt key is named; a wrong method is 405 with Allow.
    answer = rc.ctl("POST", "/api/channel", {"valu": 1}, expect=400)
    assert answer["error"].startswith("unknown field 'valu'"), answer
    answer = rc.ctl("GET", "/api/wiring_fault", expect=405)
    assert "use POST" in answer["error"], answer
