"""The master-neutral conformance scenario (docs/INTEROP.md "Conformance matrix").

One list of steps, one description of what each rack must show, and the recorder every driver
writes its results with. A driver (tests/conformance/drivers/, interop/ethercrab) runs as many
steps as its master's API offers against `rackcat run` and records each one as

- ``pass``: the step ran and rackcat answered as the specification says;
- ``fail``: it ran and something differed (the error text is kept);
- ``n/a``: the master's API does not offer it (the reason is kept);
- ``not reached``: a step it depends on did not pass.

The expectations (identity, SII words, object dictionary, PDO assignment and mapping, loopback
wiring) come from rackcat's own offline tools (`rackcat od`, `rackcat sii`) on the same rack
file, and from the rack files in examples/; the golden byte layouts of complete access follow
ETG.1000.6 §5.6.2.1.2 (subindex 0 as 16 bits, then the entries).
"""
import json
import struct
import subprocess
import time
import traceback
from pathlib import Path

# (id, what it checks) in scenario order. The ids are the matrix's rows.
STEPS = [
    ("scan", "slave count (BRD working counter / the master's scan)"),
    ("identity", "vendor, product, revision from the SII = 0x1018 = the rack file"),
    ("sii", "SII words 0x00-0x3F read through the master's EEPROM access = `rackcat sii`"),
    ("preop", "INIT -> PRE-OP on every slave, AL status code 0"),
    ("sdo_upload_expedited", "expedited upload: 0x1018:01-04 = the rack file"),
    ("sdo_download_expedited", "expedited download 0x2000:09, read back, restored"),
    ("sdo_upload_normal", "normal upload: 0x2000:01 part number (64-byte string)"),
    ("sdo_download_normal", "download of more than 4 bytes: 0x2000:04 (16-byte string), read back"),
    ("sdo_upload_segmented",
     "segmented upload: complete access of 0x2000 (229 bytes, 128-byte mailbox)"),
    ("complete_access", "complete access of 0x1C12, 0x1C13, 0x1018 = golden bytes"),
    ("sdo_abort", "abort codes: 0x1234:00 -> 0x06020000, write 0x1018:01 -> 0x06010002"),
    ("sdo_info_list", "SDO information: OD list (all objects) = `rackcat od`"),
    ("sdo_info_desc", "SDO information: object and entry descriptions = `rackcat od`"),
    ("pdo_sizes", "process image sizes per slave = 0x1C12/0x1C13 and the mapping objects"),
    ("dc_sync0", "distributed clocks configured, SYNC0 at the cycle time"),
    ("safeop", "PRE-OP -> SAFE-OP on every slave"),
    ("op", "SAFE-OP -> OP on every slave"),
    ("cycles", "N process-data cycles with the expected working counter"),
    ("loopback", "DO -> DI loopback: each output pattern seen on the wired inputs"),
    ("emergency", "an Emergency (0x4210, CPU temperature) received through the master"),
    ("init", "back to INIT on every slave"),
]
STEP_IDS = [s for s, _ in STEPS]

# The racks of the matrix. `loops`: output entry -> input entry wired channel for channel
# (the rack file's `loopback:`), `channels` the number of wired low bits.
RACKS = {
    "default": {
        "title": "default rack (27 modules), 1 slave",
        "config": None,
        "slaves": 1,
        # RIM 1 slot 1 CDO-10 -> slot 2 CDI-10 (16 channels); RIM 2 slot 7 -> slot 8 (0, 1)
        "loops": [((0x7000, 1), (0x6010, 1), 16), ((0x7190, 1), (0x61A0, 1), 2)],
    },
    "tiny16": {
        "title": "16 tiny racks (examples/tiny-rack.yaml), 16 slaves",
        "config": "examples/tiny-rack.yaml",
        "slaves": 16,
        # RIM 1 slot 1 CRS-10 relays (0x7001:01) -> slot 2 CDI-13 (0x6011:01), 8 channels
        "loops": [((0x7001, 1), (0x6011, 1), 8)],
    },
    "rack120": {
        "title": "120-module rack (examples/rack-120.yaml), 1 slave",
        "config": "examples/rack-120.yaml",
        "slaves": 1,
        # RIM 1 slot 1 CDO-10 -> slot 2 CDI-10 (16 channels)
        "loops": [((0x7000, 1), (0x6010, 1), 16)],
    },
}

CPU_TEMP_EMERGENCY = 0x4210  # modules/rack.hpp: CPU zone at or above its limit


class NotOffered(Exception):
    """The master's API has no way to do this step."""


class MasterBug(Exception):
    """The step failed because of a known bug of the master (docs/INTEROP.md has the
    evidence); rackcat's side is asserted from the capture by the matrix test."""


def _int(text):
    return int(text, 0)


def build_expectations(rackcat, repo, rack_id, state_dir, control_port, cycles):
    """What every driver compares against, from `rackcat od` / `rackcat sii` on the rack file."""
    rack = RACKS[rack_id]
    cfg = ["--config", str(Path(repo) / rack["config"])] if rack["config"] else []
    od = json.loads(subprocess.run(
        [str(rackcat), "od", "--format", "json", "--state-dir", str(state_dir), *cfg],
        check=True, stdout=subprocess.PIPE, timeout=60).stdout)
    objects = {_int(o["index"]): o for o in od["objects"]}
    sii_file = Path(state_dir).parent / f"sii-{rack_id}.bin"
    subprocess.run([str(rackcat), "sii", "-o", str(sii_file), *cfg], check=True,
                   stdout=subprocess.PIPE, timeout=60)
    sii = sii_file.read_bytes()

    def value(index, sub):
        for e in objects[index]["entries"]:
            if e["subindex"] == sub:
                return e["value"]
        raise KeyError(f"0x{index:04X}:{sub}")

    identity = [_int(value(0x1018, k)) for k in (1, 2, 3, 4)]

    def assigned(index):
        return [_int(value(index, k)) for k in range(1, _int(value(index, 0)) + 1)]

    def mapping(pdos):
        entries = []
        for pdo in pdos:
            for k in range(1, _int(value(pdo, 0)) + 1):
                raw = _int(value(pdo, k))
                entries.append((raw >> 16, (raw >> 8) & 0xFF, raw & 0xFF))
        return entries

    rx, tx = assigned(0x1C12), assigned(0x1C13)
    out_entries, in_entries = mapping(rx), mapping(tx)

    def offset(entries, index, sub):
        bit = 0
        for i, s, bits in entries:
            if (i, s) == (index, sub):
                return bit
            bit += bits
        raise KeyError(f"0x{index:04X}:{sub} is not mapped")

    loops = [{"out_bit": offset(out_entries, *o), "in_bit": offset(in_entries, *i),
              "bits": n, "what": f"0x{o[0]:04X}:{o[1]:02X} -> 0x{i[0]:04X}:{i[1]:02X}"}
             for o, i, n in rack["loops"]]

    def ca(index, values, fmt):
        return (struct.pack("<BB", len(values), 0) +
                b"".join(struct.pack(fmt, v) for v in values)).hex()

    desc = {}
    for index, o in objects.items():
        desc[f"0x{index:04X}"] = {
            "name": o["name"],
            "object_code": o["object_code"],
            "entries": {str(e["subindex"]): {"name": e["name"], "data_type": e["data_type"],
                                             "bit_size": e["bit_size"]}
                        for e in o["entries"]},
        }
    part_number = value(0x2000, 1).strip('"')
    ca_2000_bytes = (objects[0x2000]["bit_size"] + 7) // 8
    return {
        "rack": rack_id,
        "slaves": rack["slaves"],
        "identity": identity,
        "sii_words": list(struct.unpack_from("<64H", sii, 0)),
        "od_indices": sorted(objects),
        "objects": desc,
        "rx_assign": rx,
        "tx_assign": tx,
        "output_bits": sum(b for _, _, b in out_entries),
        "input_bits": sum(b for _, _, b in in_entries),
        "loops": loops,
        "part_number": part_number,
        "ipv4_address": value(0x2000, 4).strip('"'),
        "event_mask": _int(value(0x2000, 9)),
        "ca_1c12": ca(0x1C12, rx, "<H"),
        "ca_1c13": ca(0x1C13, tx, "<H"),
        "ca_1018": (struct.pack("<BB", 4, 0) + struct.pack("<IIII", *identity)).hex(),
        "ca_2000_bytes": ca_2000_bytes,
        "emergency": {
            "code": CPU_TEMP_EMERGENCY,
            "raise": [str(rackcat), "ctl", "--port", str(control_port), "--state-dir",
                      str(state_dir), "cpu-temp",
                      "--celsius", "95", "--now"],
            "clear": [str(rackcat), "ctl", "--port", str(control_port), "--state-dir",
                      str(state_dir), "cpu-temp",
                      "--celsius", "40", "--now"],
        },
        "cycles": cycles,
        "cycle_us": 1000,
    }


class Recorder:
    """Records step results into a JSON file after every step, so a master that crashes the
    driver still leaves what it did."""

    def __init__(self, path, master, version):
        self.path = Path(path)
        self.doc = {"master": master, "version": version, "steps": {}, "notes": []}
        self._save()

    def _save(self):
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps(self.doc, indent=1))
        tmp.replace(self.path)

    def set(self, step, result, detail=""):
        assert step in STEP_IDS, step
        self.doc["steps"][step] = {"result": result, "detail": str(detail)[:600]}
        self._save()

    def passed(self, step):
        return self.doc["steps"].get(step, {}).get("result") == "pass"

    def note(self, text):
        self.doc["notes"].append(text)
        self._save()

    def not_offered(self, step, why):
        self.set(step, "n/a", why)

    def run(self, step, fn, requires=()):
        """Runs `fn()` as `step` unless a prerequisite did not pass ("not reached"). fn may
        return a detail text; NotOffered / MasterBug / any other exception become n/a, master
        bug, fail. Returns True when the step passed."""
        missing = [r for r in requires if not self.passed(r)]
        if missing:
            self.set(step, "not reached", f"needs {', '.join(missing)}")
            return False
        t0 = time.monotonic()
        try:
            detail = fn()
        except NotOffered as e:
            self.set(step, "n/a", str(e))
            return False
        except MasterBug as e:
            self.set(step, "master bug", str(e))
            return False
        except Exception as e:  # noqa: BLE001 - every failure becomes the cell's text
            self.set(step, "fail", f"{type(e).__name__}: {e}".strip())
            self.note(f"{step}: {traceback.format_exc(limit=4)}")
            return False
        took = time.monotonic() - t0
        self.set(step, "pass", f"{detail} ({took:.1f} s)" if detail else f"{took:.1f} s")
        return True


def run_isolated(rec, step, fn, requires=()):
    """rec.run in a forked child: for a call that may crash the master's process (a native
    binding's segfault). The child records the step; a child killed by a signal records
    "fail" with the signal. The parent's master state is untouched by the child."""
    import os
    import signal
    if any(not rec.passed(r) for r in requires):
        return rec.run(step, fn, requires)
    pid = os.fork()
    if pid == 0:
        try:
            rec.run(step, fn)
        finally:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    rec.doc = json.loads(rec.path.read_text())
    if os.WIFSIGNALED(status):
        sig = signal.Signals(os.WTERMSIG(status)).name
        rec.set(step, "fail", f"the master's process died with {sig} in this step")
    return rec.passed(step)


def load(path):
    return json.loads(Path(path).read_text())


def hexs(data):
    return bytes(data).hex()


def get_bits(data, bit, bits):
    v = int.from_bytes(bytes(data), "little")
    return (v >> bit) & ((1 << bits) - 1)


def set_bits(data, bit, bits, value):
    b = bytearray(data)
    v = int.from_bytes(b, "little")
    mask = ((1 << bits) - 1) << bit
    v = (v & ~mask) | ((value << bit) & mask)
    return bytes(v.to_bytes(len(b), "little"))


def trigger(cmd):
    """Runs a control API command (rackcat ctl ...) inside the namespace the driver runs in."""
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                       timeout=20)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[1:])}: {r.stderr.strip()}")
