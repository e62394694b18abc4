// The ETG.2000 EtherCAT Slave Information (ESI) file of the device, written with pugixml from
// the same DeviceDescription as the SII image and from the live object dictionary: the device
// dictionary holds the device's own objects (module objects are defined once, in their
// Module), the RxPdo/TxPdo elements every mapping object with its Sm assignment (a slot's PDO
// marked OverwrittenByModule), and the ETG.5001 modular part (Slots, Modules) lets a
// configuration tool build any rack offline.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "coe/diagnosis_history.hpp"
#include "coe/object_dictionary.hpp"
#include "esi/device_description.hpp"

namespace rackcat::esi {

// One slot-card type as an ETG.5001 Module: its PDOs and objects at the indices of module 1
// (nn = 0); the Slot increments move them for other positions.
struct ModuleDescription {
  uint32_t ident = 0;  // ModuleIdent (0xF030/0xF050 value)
  std::string type;    // Module/Type text, e.g. the card name
  std::string name;    // Module/Name, e.g. the card description
  std::vector<PdoDescription> rx_pdos;
  std::vector<PdoDescription> tx_pdos;
  coe::ObjectDictionary dictionary;  // the module's objects only
};

// ETG.5001 slot rules (ETG.2000 Slots): module n's objects sit at base + (n-1)*index_increment
// and its PDOs at base + (n-1)*pdo_increment.
struct SlotRules {
  uint16_t max_slots = 255;
  uint16_t index_increment = 0x10;
  uint16_t pdo_increment = 1;
  std::string slot_name = "Module";
};

// One ETG.2000 DiagMessage (DiagnosticsType) of the 0x10F3 history (ETG.1020 ch. 13): a text ID,
// its text (%1..%4 = the message's parameters by position) and its class.
struct DiagMessage {
  uint16_t text_id = 0;
  std::string text;
  coe::diag::Type type = coe::diag::Type::Info;
};

struct EsiContent {
  const DeviceDescription* device = nullptr;
  const coe::ObjectDictionary* dictionary = nullptr;
  std::vector<uint8_t> config_data;        // SII words 0..7 (16 bytes, CRC included)
  size_t eeprom_bytes = 0;                 // SII image size
  std::vector<ModuleDescription> modules;  // empty: no Slots/Modules elements
  SlotRules slots;
  // Objects of the device's modules: defined in their <Module> (ETG.5001), so the device-level
  // Dictionary leaves them out and a configurator filling the slots gets each once.
  std::set<uint16_t> module_objects;
  // The device's diagnosis texts, written when it has the 0x10F3 history (empty: none).
  std::vector<DiagMessage> diag_messages;
};

// The ESI document as UTF-8 XML text.
std::string write_esi(const EsiContent& content);

// ESI notation helpers (ETG.2000 HexDecValue "#x..."), shared with the tests.
std::string esi_hex(uint32_t value, int digits);
// The ETG.2000 access text and restrictions of an access word: {"rw", "PreOP", ""} means
// readable always, writable only in PREOP. Empty restriction = every state.
struct EsiAccess {
  std::string access;
  std::string read_restrictions;
  std::string write_restrictions;
};
EsiAccess esi_access(uint16_t access_bits);
// "T", "R", "TR" or "" from the PDO-mappable access bits.
std::string esi_pdo_mapping(uint16_t access_bits);
// The ESI data type name of an entry: "UINT", "STRING(16)", "BIT4", an enum's name...
std::string esi_type_name(const coe::ObjectDictionary& od, const coe::Entry& entry);

}  // namespace rackcat::esi
