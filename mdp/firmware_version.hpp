// The version objects of the running firmware (docs/FOE.md "The firmware container"): 0x100A
// manufacturer software version (ETG.1000.6 Table 63), 0x1018:03 revision number, and the guide's
// 0x2000:02 "FW Version" (Appendix A). They are fixed from power-on; the device reset 0xFBF0
// (ETG.5003.1) restarts the firmware, so a container installed over FoE since power-on is what
// they report afterwards, as after a restart of the process.
#pragma once

#include "coe/object_dictionary.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::mdp {

// Sets the power-on values (defaults; the device's object reset loads them) of 0x100A,
// 0x1018:03 and 0x2000:02 from `cm`. 0x100A is a VISIBLE_STRING as long as its text: a version of
// another length replaces the object (same name and access, no hooks on it).
void apply_firmware_version(coe::ObjectDictionary& od, const ControlModule& cm);

}  // namespace rackcat::mdp
