"""The conformance scenario through ethercrab (Rust, crates.io): runs the interop program
(interop/ethercrab, built by scripts/ethercrab_interop.sh) with the rack's loopback wiring
and sorts its PASS/FAIL checks into the scenario's steps.

ethercrab's API has no complete access, no SDO information beyond object lists, no
Emergencies, and SDO downloads of at most 4 bytes; the program sends the longer downloads as
raw mailbox frames through ethercrab's register commands (docs/INTEROP.md).

    ethercrab_driver.py --iface IF --expect FILE --out FILE [--binary PATH]
"""
import argparse
import re
import subprocess
from pathlib import Path

from common import Recorder, load
from scenario import STEP_IDS

REPO = Path(__file__).resolve().parents[3]
BINARY = REPO / "interop/ethercrab/target/release/ethercrab-interop"

# Check texts -> step, first match wins (interop/ethercrab/src/main.rs).
RULES = [
    (r"^init: |^SubDevice count", "scan"),
    (r"SII: (identity words|vendor|product)|matches the SII identity|serial differs", "identity"),
    (r"\) SII: |reading the SII|description from SII", "sii"),
    (r"\(expected Pre-Operational\)", "preop"),
    (r"\(expected Safe-Operational\)", "safeop"),
    (r"\(expected Init\)|^back to INIT", "init"),
    (r"expedited download|restoring 0x2000:09|upload 0x2000:09", "sdo_download_expedited"),
    (r"aborts with|refused|was accepted|expected an SDO abort|instead of an abort", "sdo_abort"),
    (r"(normal|segmented) download|restored to|after restoring|ethercrab upload of|raw mailbox",
     "sdo_download_normal"),
    (r"0x2000:01 is \d+ bytes|upload 0x2000:04", "sdo_upload_normal"),
    (r"SDO info|Get OD List|object list", "sdo_info_list"),
    (r"CoE: ", "sdo_upload_expedited"),
    (r"image sizes|PDO mapping|loopback wire\(s\) to check|default-rack loopback", "pdo_sizes"),
    (r"^OP reached", "op"),
    (r"SYNC0|0x092C|System Time", "dc_sync0"),
    (r"loopback of", "loopback"),
    (r"^\d+ cycles|^cycle \d+", "cycles"),
]
# Fatal errors ("stopped: ...") -> the step that was running.
STOPS = [
    (r"ethercrab init", "scan"),
    (r"into_pre_op_pdi|PDO mapping", "pdo_sizes"),
    (r"configure_dc_sync", "dc_sync0"),
    (r"PRE-OP -> SAFE-OP", "safeop"),
    (r"SAFE-OP -> OP", "op"),
    (r"process data exchange", "cycles"),
    (r"OP -> SAFE-OP|SAFE-OP -> PRE-OP|PRE-OP -> INIT", "init"),
]
NOT_OFFERED = {
    "sdo_upload_segmented": "reached only with complete access, which ethercrab 0.7.1 lacks "
                            "(its longest single entry here, 64 bytes, fits the mailbox)",
    "complete_access": "no complete access in ethercrab 0.7.1",
    "sdo_info_desc": "no object or entry descriptions in ethercrab 0.7.1 (object lists only)",
    "emergency": "no Emergency API in ethercrab 0.7.1 (an Emergency in place of an SDO "
                 "response panics it: docs/INTEROP.md)",
}


def step_of(text, rules):
    for pattern, step in rules:
        if re.search(pattern, text):
            return step
    return None


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--iface", required=True)
    p.add_argument("--expect", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--binary", default=str(BINARY))
    a = p.parse_args()
    exp = load(a.expect)
    rec = Recorder(a.out, "ethercrab", "ethercrab 0.7.1")
    wires = ",".join(f"{lp['out_bit'] + b}:{lp['in_bit'] + b}"
                     for lp in exp["loops"] for b in range(lp["bits"]))
    cmd = [a.binary, "--iface", a.iface, "--expect-slaves", str(exp["slaves"]), "--mode",
           "rackcat", "--cycles", str(exp["cycles"]), "--cycle-us", str(exp["cycle_us"]),
           "--expect-vendor", str(exp["identity"][0]), "--expect-product",
           str(exp["identity"][1]), "-v"]
    if wires:
        cmd += ["--wire", wires]
    out = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         timeout=900).stdout
    print(out)
    passes, fails, unsorted = {}, {}, []
    stopped = None
    for line in out.splitlines():
        if line.startswith("FAIL stopped: "):
            stopped = line[len("FAIL stopped: "):]
            step = step_of(stopped, STOPS) or "scan"
            fails.setdefault(step, []).append(stopped)
            continue
        for tag, box in (("PASS ", passes), ("FAIL ", fails)):
            if line.startswith(tag):
                text = line[len(tag):]
                step = step_of(text, RULES)
                if step is None:
                    unsorted.append(line)
                else:
                    box.setdefault(step, []).append(text)
    reached = True
    stop_step = step_of(stopped, STOPS) if stopped else None
    for step in STEP_IDS:
        if step in NOT_OFFERED:
            rec.not_offered(step, NOT_OFFERED[step])
        elif step in fails:
            rec.set(step, "fail", f"{len(fails[step])} check(s) failed: " + " / ".join(
                fails[step][:2]))
        elif step in passes:
            rec.set(step, "pass", f"{len(passes[step])} check(s)")
        elif not reached:
            rec.set(step, "not reached", f"ethercrab-interop stopped: {stopped}")
        else:
            rec.set(step, "fail", "no check of this step in the program's output")
        if step == stop_step:
            reached = False
    for line in unsorted:
        rec.note(f"check not sorted into a step: {line}")


if __name__ == "__main__":
    main()
