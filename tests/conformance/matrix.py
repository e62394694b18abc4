"""Runs one cell of the conformance matrix (a master on a rack) and renders the matrix.

A cell: a private network namespace with a veth pair, `rackcat run` (capture on) on one end,
the master's driver on the other, both at SCHED_FIFO 10 as the other interop runs; the driver
writes its step results (scenario.Recorder); a driver that dies leaves the steps it did not
record as "not reached" with its last output.

    python3 tests/conformance/matrix.py --master pysoem --rack default   # one cell, by hand
"""
import argparse
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))

from scenario import RACKS, STEP_IDS, STEPS, build_expectations  # noqa: E402

BUILD = Path(os.environ.get("RACKCAT_BUILD_DIR", REPO / "build"))
if not BUILD.is_absolute():
    BUILD = REPO / BUILD
RACKCAT = BUILD / "rackcat"
ETHERCRAB = REPO / "interop/ethercrab/target/release/ethercrab-interop"
CONTROL_PORT = 8765
RT = ["chrt", "-f", "10"]

# Cycles per rack; fewer on the big segment, where each cycle carries 16 slaves.
CYCLES = {"default": 2000, "tiny16": 1000, "rack120": 2000}


def _py(driver):
    return [sys.executable, str(HERE / "drivers" / driver)]


# Every master of the matrix: how to start its driver, the Python module it needs, its
# version. `racks` limits where it runs (CI time, docs/INTEROP.md says why).
MASTERS = {
    "pysoem": {"cmd": _py("pysoem_driver.py"), "module": "pysoem"},
    "soemx": {"cmd": _py("soemx_driver.py"), "module": "soemx"},
    "pyecm": {"cmd": _py("pyecm_driver.py"), "module": "pyecm"},
    "kickcat": {"cmd": _py("kickcat_driver.py"), "module": "kickcat"},
    "ebpfcat": {"cmd": _py("ebpfcat_driver.py"), "module": "ebpfcat"},
    "ethercrab": {"cmd": _py("ethercrab_driver.py"), "binary": ETHERCRAB},
}


# EtherCAT masters found in the registries (the package lists of /work/.library were grepped for
# EtherCAT, SOEM, ethercrab, KickCAT) that are not a column, with the exact reason.
NOT_RUNNABLE = {
    "EcMasterPython 3.1.4.4 (PyPI, acontis)": "installs, but `import EcMasterPython` fails: "
    "\"Error: EC-Master package not found. Please install EC-Master package ... or contact "
    "support to request an EVAL version\" - a wrapper of the commercial EC-Master binaries, "
    "which no registry carries",
    "darra-ethercat-master 2.10.0 (PyPI)": "`pip download --no-deps darra-ethercat-master` "
    "here: \"No matching distribution found\" (no distribution for Linux x86-64 / CPython "
    "3.11); its own description ties it to the DarraRT real-time kernel driver",
    "ethercat-master 0.1.11 (PyPI)": "installs and imports; a bus-management layer over pysoem "
    "(its requirement), so it is SOEM 1.4 again through the pysoem column",
    "pysoem-nt15 0.0.2, pysoemdanfoss 0.0.4 (PyPI)": "forks of pysoem's Cython wrapper (same "
    "SOEM 1.4 API), covered by the pysoem column",
    "autd3-link-soem, autd3-link-ethercrab, autd3-link-echocat, pyautd3-link-* (PyPI)": "links "
    "of the AUTD3 ultrasound-array library: they only send AUTD3 device frames, no general "
    "master API (no SDO, no state machine)",
    "industriagents-ethercat-mcp, am-sdk, gsv8-ethercat, hdrive-etc, pyetg1510 (PyPI)": "an MCP "
    "server over pysoem and SDKs of particular devices / an ETG.1510 diagnosis client, not "
    "masters of their own",
    "ethercat 0.3.1 (crates.io, `cargo info ethercat`)": "Rust binding of the IgH EtherLab "
    "master, which runs as a kernel module driven through /dev/EtherCAT0: no registry here "
    "carries that module (`apt-cache search ethercat` finds nothing) and this machine's kernel "
    "(6.18.44-fc, no /lib/modules for it) loads no out-of-tree module",
    "soem 0.3.0, ethercat-soem 0.2.0 (crates.io, `cargo info`)": "Rust bindings that compile "
    "SOEM's C sources: SOEM again, as in the pysoem, soemx and pyecm columns",
}
# crates.io has no package list to grep here and `cargo search` is not served by the registry
# mirror: the crates above were looked up by name (`cargo info NAME`).


def unavailable(master):
    """Why `master` cannot run here, or None."""
    spec = MASTERS[master]
    if "module" in spec and importlib.util.find_spec(spec["module"]) is None:
        return f"Python module {spec['module']} not installed (scripts/setup.sh installs it)"
    if "binary" in spec and not Path(spec["binary"]).exists():
        return f"{spec['binary']} not built (scripts/ethercrab_interop.sh builds it)"
    return None


def _run(*cmd, check=True):
    return subprocess.run(cmd, check=check, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)


class Cell:
    """One master on one rack: namespace, veth pair, rackcat, the driver."""

    def __init__(self, master, rack, workdir, tag=""):
        self.master, self.rack = master, rack
        self.dir = Path(workdir) / f"{master}-{rack}{'-' + tag if tag else ''}"
        shutil.rmtree(self.dir, ignore_errors=True)
        self.dir.mkdir(parents=True)
        tag = f"{os.getpid() % 100000}{len(master)}{len(rack)}{int(time.monotonic()*10) % 1000}"
        self.ns = f"rcconf-{tag}"
        self.if_slave, self.if_master = "ecs0", "ecm0"
        self.pcap = self.dir / "rackcat.pcap"
        self.slave = None

    def ns_exec(self):
        return ["ip", "netns", "exec", self.ns]

    def __enter__(self):
        _run("ip", "netns", "add", self.ns)
        _run("ip", "-n", self.ns, "link", "add", self.if_slave, "type", "veth", "peer", "name",
             self.if_master)
        for i in (self.if_slave, self.if_master):
            _run(*self.ns_exec(), "sysctl", "-qw", f"net.ipv6.conf.{i}.disable_ipv6=1",
                 check=False)
            _run("ip", "-n", self.ns, "link", "set", i, "up")
        _run("ip", "-n", self.ns, "link", "set", "lo", "up")
        return self

    def __exit__(self, *exc):
        self.stop_slave()
        for pid in _run("ip", "netns", "pids", self.ns, check=False).stdout.split():
            try:
                os.kill(int(pid), 9)
            except (ProcessLookupError, ValueError):
                pass
        _run("ip", "netns", "del", self.ns, check=False)

    def start_slave(self):
        rack = RACKS[self.rack]
        state = self.dir / "state"
        state.mkdir()
        cmd = [str(RACKCAT), "run", "--iface", self.if_slave, "--slaves", str(rack["slaves"]),
               "--state-dir", str(state), "--pcap", str(self.pcap), "--no-pty",
               "--control-port", str(CONTROL_PORT)]
        if rack["config"]:
            cmd += ["--config", str(REPO / rack["config"])]
        self.slave_log = open(self.dir / "rackcat.log", "w")
        self.slave = subprocess.Popen(self.ns_exec() + RT + cmd, stdout=self.slave_log,
                                      stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline:
            if self.slave.poll() is not None:
                raise RuntimeError(f"rackcat exited: {(self.dir / 'rackcat.log').read_text()}")
            ok = _run(*self.ns_exec(), str(RACKCAT), "ctl", "--port", str(CONTROL_PORT),
                      "--state-dir", str(state), "esm",
                      check=False).returncode == 0
            if ok:
                return state
            time.sleep(0.1)
        raise RuntimeError("rackcat did not come up in 15 s")

    def stop_slave(self):
        if self.slave is None:
            return None
        if self.slave.poll() is None:
            self.slave.terminate()
            try:
                self.slave.wait(10)
            except subprocess.TimeoutExpired:
                self.slave.kill()
                self.slave.wait()
        self.slave_log.close()
        rc, self.slave = self.slave.returncode, None
        return rc

    def run(self, timeout_s=600):
        state = self.start_slave()
        exp = build_expectations(RACKCAT, REPO, self.rack, state, CONTROL_PORT,
                                 CYCLES[self.rack])
        exp_file = self.dir / "expect.json"
        exp_file.write_text(json.dumps(exp))
        out = self.dir / "result.json"
        cmd = MASTERS[self.master]["cmd"] + ["--iface", self.if_master, "--expect",
                                             str(exp_file), "--out", str(out)]
        t0 = time.monotonic()
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        try:
            p = subprocess.run(self.ns_exec() + RT + cmd, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, timeout=timeout_s, env=env)
            output, rc = p.stdout, p.returncode
        except subprocess.TimeoutExpired as e:
            output = (e.stdout or b"").decode(errors="replace") if isinstance(
                e.stdout, bytes) else (e.stdout or "")
            rc = f"killed after {timeout_s} s"
        took = time.monotonic() - t0
        (self.dir / "driver.log").write_text(output)
        slave_rc = self.stop_slave()
        res = json.loads(out.read_text()) if out.exists() else {
            "master": self.master, "version": "?", "steps": {}, "notes": []}
        tail = " | ".join(line for line in output.strip().splitlines()[-3:])
        for step in STEP_IDS:
            if step not in res["steps"]:
                res["steps"][step] = {
                    "result": "not reached",
                    "detail": f"driver ended (exit {rc}) before this step: {tail}"[:600]}
        res.update(rack=self.rack, seconds=round(took, 1), exit=rc, slave_exit=slave_rc,
                   pcap=str(self.pcap), log=str(self.dir / "driver.log"))
        if slave_rc not in (0, None):
            res["notes"].append(f"rackcat exited with {slave_rc}")
        return res


# --- the table -------------------------------------------------------------------------

MARK = {"pass": "pass", "fail": "FAIL", "n/a": "n/a", "not reached": "not reached",
        "master bug": "master bug"}


def _short(text, n=140):
    text = text.replace("|", "/").replace("\n", " ")
    return text if len(text) <= n else text[:n - 3] + "..."


def render(results, not_run):
    """results: {(master, rack): result dict}. not_run: {master: reason}. Master-bug cells
    point to a numbered list with the evidence below the tables."""
    lines, bugs = [], {}
    masters = [m for m in MASTERS if any(k[0] == m for k in results)]

    def cell(master, r):
        if r["result"] == "pass":
            return "pass"
        if r["result"] == "master bug":
            key = (master, r.get("bug", r["detail"]))
            bugs.setdefault(key, (len(bugs) + 1, r, []))
            bugs[key][2].append((rack, r))
            return f"master bug [B{bugs[key][0]}]"
        return f"{MARK.get(r['result'], r['result'])}: {_short(r.get('detail', ''))}"

    lines += ["Steps (tests/conformance/scenario.py):", ""]
    lines += [f"- `{step}`: {what}" for step, what in STEPS] + [""]
    for rack in RACKS:
        cols = [m for m in masters if (m, rack) in results]
        if not cols:
            continue
        lines += [f"### {RACKS[rack]['title']}", ""]
        lines.append("| step | " + " | ".join(cols) + " |")
        lines.append("|---|" + "---|" * len(cols))
        for step, _ in STEPS:
            row = [cell(m, results[(m, rack)]["steps"][step]) for m in cols]
            lines.append(f"| {step} | " + " | ".join(row) + " |")
        secs = [f"{m} {results[(m, rack)]['seconds']} s" for m in cols]
        lines += ["", f"Driver run time: {', '.join(secs)}.", ""]
        retried = [f"{m} ({_short(n, 200)})" for m in cols for n in results[(m, rack)]["notes"]
                   if n.startswith("first run missed")]
        if retried:
            lines += ["Run twice (the first run missed the baseline; the second is shown): " +
                      "; ".join(retried), ""]
    versions = sorted({(m, results[k]["version"]) for k in results for m in [k[0]]})
    lines += ["Versions: " + ", ".join(v for _, v in versions) + ".", ""]
    if bugs:
        lines += ["Master bugs (the cell's step failed in the master; rackcat's side of it is "
                  "asserted from the capture, tests/conformance/known_bugs.py):", ""]
        for (master, evidence), (n, r, seen) in sorted(bugs.items(), key=lambda kv: kv[1][0]):
            lines.append(f"- **B{n}** ({master}): {evidence}. The master said: "
                         f"`{_short(r.get('master_error', ''), 240)}`. rackcat's side: " +
                         "; ".join(f"{rk}: {x.get('rackcat_side', '')}" for rk, x in seen))
        lines.append("")
    if not_run:
        lines += ["Masters found in the registries that are not a column:", ""]
        for m, why in not_run.items():
            lines.append(f"- {m}: {why}")
        lines.append("")
    return "\n".join(lines)


BEGIN = "<!-- conformance-matrix:begin (written by tests/conformance, do not edit) -->"
END = "<!-- conformance-matrix:end -->"


def write_docs(results, not_run, doc=REPO / "docs/INTEROP.md", stamp=None):
    text = doc.read_text()
    table = render(results, not_run)
    stamp = stamp or time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    block = f"{BEGIN}\n\nLast run: {stamp}.\n\n{table}\n{END}"
    if BEGIN in text:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        text = head + block + tail
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    doc.write_text(text)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--master", required=True, choices=list(MASTERS))
    p.add_argument("--rack", required=True, choices=list(RACKS))
    p.add_argument("--workdir", default="/tmp/rackcat-conformance")
    a = p.parse_args()
    why = unavailable(a.master)
    if why:
        sys.exit(f"{a.master}: {why}")
    with Cell(a.master, a.rack, a.workdir) as cell:
        res = cell.run()
    for step in STEP_IDS:
        r = res["steps"][step]
        print(f"{step:24} {r['result']:12} {r['detail']}")
    print(f"{res['seconds']} s, driver exit {res['exit']}, logs in {cell.dir}")


if __name__ == "__main__":
    main()
