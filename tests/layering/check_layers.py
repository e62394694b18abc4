#!/usr/bin/env python3
"""Fails when a source file includes a layer it must not (README "A tour of the folders").

Layers, top to bottom:  apps -> ecat, esi, modules, device -> mdp -> coe, foe -> base
(device/ serves any device from its ESI: coe, foe, esi and the ecat::Application seam only).
Inside ecat/ the firmware (ecat/slave) and the LAN9252 access (ecat/lan9252) see the chip only
through the PDI port (ecat/pdi_port.hpp), never the chip's internals (ecat/esc) or the host
I/O (ecat/host); the chip knows nothing of the firmware.

The compiler already refuses most of this: each library's include path holds only its own
headers and those of what it links (docs/ESC.md "Layers, enforced by the build";
layering_compiler_refuses). This check stays for what the compiler cannot see: tests,
benchmarks and fuzz targets (which share one tests/ include root), headers no library
compiles, and rules finer than a link (device/ links the firmware but may use only its
mailbox seam).

Every quoted #include "area/..." of every .hpp/.cpp below the library folders is checked
against RULES: the longest folder prefix of the including file names what it may include
(path prefixes; a file may always include its own folder). Tests, benchmarks and fuzz targets
follow the rule of the layer they test. Usage: check_layers.py [repository root].
"""
import pathlib
import re
import sys

# folder of the including file -> include path prefixes it may use (besides its own folder).
BASE = ["base/"]
COE = BASE + ["coe/"]
MDP = COE + ["mdp/", "foe/"]
ECAT_PORT = ["ecat/pdi_port.hpp"]
# What a device sees of ecat/: the device seam and the mailbox it registers its protocols with.
ECAT_DEVICE_SEAM = ["ecat/application.hpp", "ecat/slave/mailbox_protocol.hpp",
                    "ecat/slave/mailbox_server.hpp"]
ECAT = BASE + ["ecat/"]
RULES = {
    "base": BASE,
    "coe": COE,
    "foe": BASE + ["foe/"],
    "mdp": MDP,
    "esi": MDP + ["esi/"],
    # Generic devices from their ESI: the generic CoE/SII layers and the device seam only.
    "modules/signals": BASE + ["modules/signals/"],
    "modules/canopen": COE + ["modules/canopen/"],
    "modules/cards": MDP + ["modules/signals/", "modules/cards/"],
    "modules/rack": MDP + ["modules/signals/", "modules/cards/", "modules/rack/"],
    "modules/control": MDP + ["modules/signals/", "modules/cards/", "modules/rack/"],
    "modules/rim": MDP + ["modules/signals/", "modules/cards/", "modules/rack/",
                          "modules/canopen/", "modules/rim/"],
    # ecat/ is below every device layer: it never sees a dictionary or a rack.
    "ecat": ECAT,
    "ecat/esc": BASE + ECAT_PORT + ["ecat/esc/", "ecat/registers.hpp", "ecat/clock.hpp",
                                    "ecat/frame.hpp", "ecat/lan9252/"],
    "ecat/slave": BASE + ECAT_PORT + ["ecat/slave/", "ecat/application.hpp",
                                      "ecat/al_status_code.hpp", "ecat/registers.hpp"],
    "ecat/lan9252": BASE + ECAT_PORT + ["ecat/lan9252/"],
    "ecat/host": ECAT,
    # Any device from its vendor ESI, served as an ecat::Application (like apps/rack_slave).
    "device": COE + ["esi/", "foe/"] + ECAT_DEVICE_SEAM,
    "apps/rack_slave": MDP + ["ecat/", "esi/", "modules/", "apps/rack_slave/"],
    "apps": MDP + ["ecat/", "esi/", "modules/", "device/", "apps/"],
    # Tests and benchmarks of a layer see that layer and what it may see, plus their own folder.
    "tests/coe": COE + ["tests/coe/", "tests/support/"],
    "tests/foe": BASE + ["foe/", "tests/foe/"],
    "tests/mdp": MDP + ["tests/mdp/", "tests/support/"],
    "tests/esi": MDP + ["esi/", "tests/esi/", "tests/support/"],
    "tests/ecat": ECAT + ["tests/ecat/", "tests/support/"],
    "tests/ecat_wire_slave": ECAT + ["tests/ecat_wire_slave/", "tests/ecat/"],
    "tests/modules": MDP + ["modules/", "tests/modules/", "tests/support/"],
    "tests/device": COE + ["esi/", "ecat/", "foe/", "device/", "tests/device/", "tests/support/"],
    "tests/apps": MDP + ["ecat/", "esi/", "modules/", "device/", "apps/rack_slave/", "apps/line/",
                        "tests/"],
    "tests/can_vm": MDP + ["modules/", "tests/can_vm/", "tests/support/"],
    "tests/support": BASE + ["tests/support/"],
    "tests/install": COE,
    "tests/install/coe_mdp": MDP,  # find_package(rackcat COMPONENTS coe mdp)
    # The out-of-tree example device uses the installed generic layers only.
    "examples": COE + ["esi/", "ecat/"],
    "bench/coe": COE + ["tests/coe/"],
    "bench/mdp": MDP + ["tests/mdp/"],
    "bench/esi": MDP + ["esi/", "tests/esi/"],
    "bench/ecat": ECAT + ["tests/ecat/", "apps/rack_slave/"],
    "bench/modules": MDP + ["modules/", "tests/modules/"],
    "fuzz/coe": COE + ["tests/coe/"],
    "fuzz/foe": BASE + ["foe/"],
    "fuzz/mdp": MDP,
    "fuzz/esi": MDP + ["esi/"],
    "fuzz/ecat": ECAT + ["tests/ecat/"],
    "fuzz/modules": MDP + ["modules/", "tests/modules/"],
    "fuzz/apps": MDP + ["ecat/", "esi/", "modules/", "device/", "apps/line/"],
}
OWN_AREAS = {p.split("/")[0] for p in RULES}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def rule_for(rel: str):
    folder = rel.rsplit("/", 1)[0] if "/" in rel else ""
    best = None
    for prefix in RULES:
        if folder == prefix or folder.startswith(prefix + "/"):
            if best is None or len(prefix) > len(best):
                best = prefix
    return best


def main() -> int:
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    problems = []
    checked = 0
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".hpp", ".cpp", ".h", ".cc"):
            continue
        rel = path.relative_to(root).as_posix()
        area = rel.split("/")[0]
        if any(part.startswith(("build", ".")) for part in rel.split("/")):
            continue
        if rel.startswith("tests/layering/"):
            continue  # the check's own test tree, with its deliberate violation
        prefix = rule_for(rel)
        if prefix is None:
            problems.append(f"{rel}: no layering rule for its folder (add it to {__file__})")
            continue
        allowed = RULES[prefix] + [prefix + "/"]
        checked += 1
        text = path.read_text(encoding="utf-8", errors="replace")
        for m in INCLUDE.finditer(text):
            inc = m.group(1)
            if "/" not in inc:
                # A header next to the file, in its own folder.
                if (path.parent / inc).exists():
                    continue
                problems.append(f"{rel}:{text.count(chr(10), 0, m.start()) + 1}: "
                                f"#include \"{inc}\" is not a repository path")
                continue
            if not (root / inc).exists() and inc.split("/")[0] not in OWN_AREAS:
                continue  # a system or third-party header
            if not any(inc == a or (a.endswith("/") and inc.startswith(a)) for a in allowed):
                line = text.count("\n", 0, m.start()) + 1
                problems.append(f"{rel}:{line}: {prefix}/ must not include \"{inc}\"")
    for p in problems:
        print(p)
    print(f"check_layers: {checked} files, {len(problems)} violation(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
