"""[esi] The ESI as a configurator reads it (issue 15): an independent, configurator-style reader
of `rackcat esi` (ElementTree only, no rackcat code) fills the ETG.5001 slots offline with the
rack's modules, the way configuration tools build a modular device from its ESI (ETG.2000
Slots/Modules: a module's objects and PDOs at slot position k move by k x SlotIndexIncrement /
SlotPdoIncrement where their Index says DependOnSlot; device-level PDOs marked
OverwrittenByModule give way to the modules'). It must find every object once - no duplicates
between the device level and the modules or between modules - every mapped entry resolvable,
and exactly the object dictionary the running rack serves (`rackcat od --format json`).
No network: about 1 s.
"""
import json
import xml.etree.ElementTree as ET
from collections import Counter

import pytest

from rackcat_helpers import rackcat_tool

TINY_RACK = """\
rims:
  - rim: 1
    type: 6-slot
    slots:
      - {slot: 1, card: CRS-10}
      - {slot: 2, card: CDI-13, loopback: {rim: 1, slot: 1}}
      - {slot: 4, card: CAI-11}
"""


def number(text):
    text = text.strip()
    return int(text[2:], 16) if text.startswith("#x") else int(text)


def depends(index_node):
    return index_node.get("DependOnSlot") in ("true", "1")


def fill_slots(esi_xml, idents):
    """Objects (index -> how often defined) and PDOs (index -> entries) of the device with
    `idents` in its slots, in order."""
    root = ET.fromstring(esi_xml)
    device = root.find("./Descriptions/Devices/Device")
    modules = {number(m.find("Type").get("ModuleIdent")): m
               for m in root.findall("./Descriptions/Modules/Module")}
    slots = device.find("Slots")
    index_inc = number(slots.get("SlotIndexIncrement", "0"))
    pdo_inc = number(slots.get("SlotPdoIncrement", "0"))
    allowed = {number(i.text) for i in slots.findall("./Slot/ModuleIdent")}

    objects = Counter(number(o.find("Index").text)
                      for o in device.findall("./Profile/Dictionary/Objects/Object"))
    pdos = Counter()
    entries = []
    for kind in ("RxPdo", "TxPdo"):
        for p in device.findall(kind):
            if p.get("OverwrittenByModule") in ("true", "1"):
                continue
            pdos[number(p.find("Index").text)] += 1
            entries += [number(e.find("Index").text) for e in p.findall("Entry")]
    for k, ident in enumerate(idents):
        assert ident in allowed, f"module {ident:#010x} is in no Slot"
        module = modules[ident]
        for o in module.findall("./Profile/Dictionary/Objects/Object"):
            idx = o.find("Index")
            objects[number(idx.text) + (k * index_inc if depends(idx) else 0)] += 1
        for kind in ("RxPdo", "TxPdo"):
            for p in module.findall(kind):
                idx = p.find("Index")
                pdos[number(idx.text) + (k * pdo_inc if depends(idx) else 0)] += 1
                for e in p.findall("Entry"):
                    ei = e.find("Index")
                    entries.append(number(ei.text) + (k * index_inc if depends(ei) else 0))
    return objects, pdos, entries


@pytest.mark.parametrize("rack", ["default", "tiny"])
def test_a_configurator_filling_the_slots_gets_every_object_once(tmp_path, rack):
    args = []
    if rack == "tiny":
        (tmp_path / "rack.yaml").write_text(TINY_RACK)
        args = ["--config", tmp_path / "rack.yaml"]
    esi = rackcat_tool("esi", *args).stdout
    od = json.loads(rackcat_tool("od", "--format", "json", *args).stdout)
    # The rack's modules, in slot order: the detected module list 0xF050 the rack serves.
    f050 = next(o for o in od["objects"] if o["index"] == "0xF050")
    idents = [int(str(e["value"]), 0) for e in f050["entries"][1:]]
    assert idents, f050

    objects, pdos, entries = fill_slots(esi, idents)
    twice = sorted(f"{i:#06x}" for i, n in objects.items() if n > 1)
    assert not twice, f"objects defined more than once: {twice}"
    assert not [i for i, n in pdos.items() if n > 1]
    unresolved = sorted({f"{i:#06x}" for i in entries if i and i not in objects})
    assert not unresolved, f"mapped objects the configurator cannot find: {unresolved}"
    # Exactly the dictionary the rack serves; the enumerations 0x0800.. are DataTypes in an ESI.
    served = {int(o["index"], 16) for o in od["objects"]} - set(range(0x0800, 0x1000))
    assert set(objects) == served, (sorted(f"{i:#06x}" for i in set(objects) - served),
                                    sorted(f"{i:#06x}" for i in served - set(objects)))
