#include "esi/rack.hpp"

#include <fmt/format.h>

#include <map>

#include "esi/describe_dictionary.hpp"
#include "mdp/card_catalogue.hpp"
#include "mdp/diagnosis_catalogue.hpp"
#include "mdp/rack_config.hpp"
#include "mdp/sync_manager_layout.hpp"

namespace rackcat::esi {
namespace {

SmPlan rack_sm_plan(const mdp::RackConfig& config) {
  namespace sm = mdp::sm;
  SmPlan p;
  p.foe = true;
  p.boot_out_start = sm::kBootMailboxOutStart;
  p.boot_out_size = config.control.boot_mailbox_size;
  p.boot_in_start = sm::kBootMailboxInStart;
  p.boot_in_size = config.control.boot_mailbox_size;
  p.mailbox_out_start = sm::kMailboxOutStart;
  p.mailbox_out_size = sm::kMailboxOutSize;
  p.mailbox_out_control = sm::kMailboxOutControl;
  p.mailbox_in_start = sm::kMailboxInStart;
  p.mailbox_in_size = sm::kMailboxInSize;
  p.mailbox_in_control = sm::kMailboxInControl;
  p.outputs_start = sm::kOutputsStart;
  p.outputs_control = sm::kOutputsControl;
  p.inputs_start = sm::kInputsStart;
  p.inputs_control = sm::kInputsControl;
  p.max_process_data_bytes = sm::kMaxProcessDataBytes;
  return p;
}

DeviceTexts rack_texts(const mdp::RackConfig& config) {
  DeviceTexts t;
  t.vendor_name = config.control.vendor_name;
  t.order_code = config.control.part_number;
  t.group_type = "FusionIO";
  t.group_name = "Fusion.IO-style modular I/O racks";
  return t;
}

// Module objects live in 0x3nn1..0x7nnX and, for encoder cards, the configuration and
// information areas 0x8nnX / 0x9nnX (ETG.5001.1 §4, docs/MDP.md, docs/ENCODER.md); nibble 0 of
// the 0x3000 area is the device's module ident list 0x3000, not a module object.
bool belongs_to_module(uint16_t index, uint16_t nn) {
  if (index < 0x3000 || index > 0x9FFF) return false;
  if (((index >> 4) & 0xFF) != nn) return false;
  return !(index >= 0x3000 && index <= 0x3FFF && (index & 0xF) == 0);
}

// A copy of `src` at index `index` (same entries, layout and current values).
coe::Object relocate(const coe::Object& src, uint16_t index) {
  coe::Object o(index, src.code(), src.name(), src.data_type());
  o.set_packed(src.packed());
  for (const auto& e : src.entries()) o.add(e);
  o.finalize();
  auto from = src.image();
  auto to = o.image();
  for (size_t i = 0; i < to.size() && i < from.size(); ++i) to[i] = from[i];
  return o;
}

PdoDescription relocate_pdo(PdoDescription p, uint16_t pdo_index, uint16_t offset) {
  p.index = pdo_index;
  for (auto& e : p.entries)
    if (e.index >= 0x3000 && e.index <= 0x7FFF) e.index = static_cast<uint16_t>(e.index - offset);
  return p;
}

}  // namespace

DeviceDescription describe_device(const mdp::Device& device) {
  DeviceDescription d = describe_dictionary(device.dictionary(), rack_texts(device.config()),
                                            rack_sm_plan(device.config()));
  // The slots' PDOs: module n at 0x1600/0x1A00 + n - 1 (docs/MDP.md PDO index rule); the user
  // PDOs and the device's own (0x1BFF diagnosis) are not overwritten by a module.
  for (auto* pdos : {&d.rx_pdos, &d.tx_pdos}) {
    for (auto& p : *pdos) {
      const auto slot = static_cast<uint32_t>(p.index & 0xFF);
      p.from_module = slot < mdp::kMaxModules && (p.index >> 8 == 0x16 || p.index >> 8 == 0x1A);
    }
  }
  // Sized for the rack: a master's PREOP->SAFEOP of a full rack reads and checks the mapping of
  // every module (two PDOs and the 0x1C12/0x1C13 entries each by SDO), so 50 ms per module on
  // top of the usual 10 s; the SDO Information answers of a large dictionary travel in many
  // fragments, 20 ms per module on top of 2 s.
  const auto modules = static_cast<int>(device.modules().size());
  d.timeouts.safeop_op = 10000 + 50 * modules;
  d.timeouts.mailbox_response = 2000 + 20 * modules;
  return d;
}

SiiImage build_sii(const mdp::Device& device) {
  return encode_sii(describe_device(device));
}

namespace {

// One card per distinct ident, in catalogue order: cards that share an ident (CDI-10, CDI-11,
// CDI-12 are all "16-Channel Digital Input") are one ETG.5001 module with the same objects;
// the module's Type lists all their names.
std::vector<const mdp::CardType*> representatives(std::map<uint32_t, std::string>* names) {
  std::vector<const mdp::CardType*> out;
  std::map<uint32_t, std::string> local;
  auto& n = names ? *names : local;
  for (const auto& card : mdp::card_catalogue()) {
    auto [it, fresh] = n.emplace(card.module_ident, std::string(card.name));
    if (fresh)
      out.push_back(&card);
    else
      it->second += ", " + std::string(card.name);
  }
  return out;
}

// A module's name true for every card of its ident: the card's own description when it has
// the ident alone, otherwise the card names and what they share ("CDI-12/CDI-11/CDI-10
// 16-channel digital input").
std::string module_name(const mdp::CardType& card, const std::string& type_list) {
  if (type_list.find(',') == std::string::npos) return std::string(card.slot_card_type);
  std::string names;
  for (const char c : type_list) {
    if (c == ' ') continue;  // card names have no blanks; the list separator is ", "
    names.push_back(c == ',' ? '/' : c);
  }
  // Guide Table 5 ident, bits 15..12: 0xD digital, 0xA analog, 0xC temperature/serial.
  const uint32_t family = (card.module_ident >> 12) & 0xF;
  const char* kind = family == 0xD ? "digital" : family == 0xA ? "analog" : "thermocouple";
  return fmt::format("{} {}-channel {} {}", names, card.channels, kind,
                     card.input ? "input" : "output");
}

}  // namespace

std::string catalogue_rack_yaml() {
  auto cards = representatives(nullptr);
  std::string yaml = "rims:\n";
  for (size_t i = 0; i < cards.size(); ++i) {
    if (i % 24 == 0)
      yaml += fmt::format("  - rim: {}\n    type: 24-slot\n    slots:\n", i / 24 + 1);
    yaml += fmt::format("      - {{slot: {}, card: \"{}\"}}\n", i % 24 + 1, cards[i]->name);
  }
  return yaml;
}

std::vector<ModuleDescription> describe_module_types() {
  std::map<uint32_t, std::string> names;
  representatives(&names);
  // The catalogue rack is built by mdp itself, so the objects are the ones a real rack has.
  const std::string yaml = catalogue_rack_yaml();
  mdp::DeviceOptions options;
  options.load_stored_parameters = false;
  mdp::Device device(mdp::parse_rack_config(yaml, "<catalogue rack>"), options);
  const auto& od = device.dictionary();

  std::vector<ModuleDescription> out;
  for (const auto& m : device.modules()) {
    ModuleDescription md;
    md.ident = m.card->module_ident;
    md.type = names[md.ident];
    md.name = module_name(*m.card, md.type);
    const uint16_t nn = m.nn();
    const auto offset = static_cast<uint16_t>(nn * mdp::kIndexDistance);
    for (const auto& [index, en] : od.enums()) md.dictionary.add_enum(en);
    od.for_each([&](const coe::Object& obj) {
      if (belongs_to_module(obj.index(), nn))
        md.dictionary.add(relocate(obj, static_cast<uint16_t>(obj.index() - offset)));
    });
    if (const auto* rx = od.find(mdp::sm::rx_pdo_index(m.number)))
      md.rx_pdos.push_back(relocate_pdo(describe_pdo(od, *rx, 2), mdp::sm::kRxPdoBase, offset));
    if (const auto* tx = od.find(mdp::sm::tx_pdo_index(m.number)))
      md.tx_pdos.push_back(relocate_pdo(describe_pdo(od, *tx, 3), mdp::sm::kTxPdoBase, offset));
    out.push_back(std::move(md));
  }
  return out;
}

std::string write_esi(const mdp::Device& device) {
  auto d = describe_device(device);
  auto sii = encode_sii(d);
  EsiContent c;
  c.device = &d;
  c.dictionary = &device.dictionary();
  c.config_data = encode_config_area(d.config);
  c.eeprom_bytes = sii.bytes.size();
  c.modules = describe_module_types();
  for (const auto& m : device.modules()) {
    device.dictionary().for_each([&](const coe::Object& obj) {
      if (belongs_to_module(obj.index(), m.nn())) c.module_objects.insert(obj.index());
    });
  }
  c.slots.max_slots = mdp::kMaxModules;
  c.slots.index_increment = mdp::kIndexDistance;
  c.slots.pdo_increment = mdp::sm::kPdoIndexIncrement;
  // The rack's 0x10F3 texts (mdp/diagnosis_catalogue.hpp): %1 RIM, %2 module, %3 channel,
  // %4 detail.
  for (const mdp::diag::DiagText& t : mdp::diag::catalogue()) {
    c.diag_messages.push_back({t.text_id, std::string(t.text), mdp::diag::type_of(t.text_id)});
  }
  return write_esi(c);
}

}  // namespace rackcat::esi
