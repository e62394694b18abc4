// Module enumeration (guide §4.2 Table 23 "Detect Modules Override", §2.3 0x3000; ETG.5001.1
// Modular Device Profile: 0xF030 configured / 0xF050 detected module ident lists): which of the
// rack's modules the device enumerates, at power-on, on a device reset 0xFBF0 and on the Detect
// Modules command 0xF002. With Detect Modules Override 0 only the modules whose RIM is online
// then; with 1 every configured module. Every object that describes the enumerated modules
// follows, so a master that starts from scratch reaches OP without edits:
//   0xF050 detected list and 0x3000 module ident map: the enumerated modules' idents, in order;
//   0xF030 configured list: the same, unless the master wrote its own (it differs from the
//          previous enumeration): then it is kept, and PREOP->SAFEOP refuses a difference with
//          AL status 0x0070 (ETG.5001.1, module_lists_mismatch());
//   0x1C12/0x1C13: the enumerated modules' PDOs (default_assignment()), unless the master
//          assigned its own.
// The power-on values (defaults) of these objects become the new enumeration's, so an object
// reset (0xFBF0) starts from it.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "coe/object_dictionary.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::mdp {

// `previous` and `present`: one byte per module of `config` (non-zero = enumerated).
void enumerate_modules(coe::ObjectDictionary& od, const RackConfig& config,
                       std::span<const uint8_t> previous, std::span<const uint8_t> present);

// Why 0xF030 and 0xF050 disagree (for the log), empty when they do not.
std::string module_list_difference(const coe::ObjectDictionary& od);

}  // namespace rackcat::mdp
