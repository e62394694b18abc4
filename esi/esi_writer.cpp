#include "esi/esi_writer.hpp"

#include <fmt/format.h>

#include <map>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "coe/access.hpp"
#include "coe/data_type.hpp"
#include "coe/diagnosis_history.hpp"
#include "coe/unit_code.hpp"

namespace rackcat::esi {
namespace {

using coe::access::kReadOp;
using coe::access::kReadPreOp;
using coe::access::kReadSafeOp;
using coe::access::kWriteOp;
using coe::access::kWritePreOp;
using coe::access::kWriteSafeOp;

// ETG.2000 AccessType restriction names for a subset of {PREOP, SAFEOP, OP}.
std::string restriction(bool preop, bool safeop, bool op) {
  if (preop && safeop && op) return "";
  // The schema's enumeration: PreOP, PreOP_SafeOP, PreOP_OP, SafeOP, SafeOP_OP, OP.
  static constexpr const char* kNames[8] = {"",      "OP",       "SafeOP",       "SafeOP_OP",
                                            "PreOP", "PreOP_OP", "PreOP_SafeOP", ""};
  return kNames[(preop ? 4 : 0) | (safeop ? 2 : 0) | (op ? 1 : 0)];
}

std::string hex_bytes(std::span<const uint8_t> bytes) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (uint8_t b : bytes) {
    out.push_back(kDigits[b >> 4]);
    out.push_back(kDigits[b & 0xF]);
  }
  return out;
}

// The current value of an entry, little-endian, (bit_length + 7) / 8 bytes: what a master
// reads after start-up is what the ESI announces as default.
std::vector<uint8_t> entry_value(const coe::Object& obj, const coe::Entry& e) {
  auto image = obj.image();
  std::vector<uint8_t> out(e.byte_length(), 0);
  if (e.bit_offset % 8 == 0 && e.bit_length % 8 == 0) {
    size_t start = e.bit_offset / 8;
    for (size_t i = 0; i < out.size() && start + i < image.size(); ++i) out[i] = image[start + i];
    return out;
  }
  for (uint16_t bit = 0; bit < e.bit_length; ++bit) {
    size_t src = size_t{e.bit_offset} + bit;
    if (src / 8 >= image.size()) break;
    if (image[src / 8] & (1u << (src % 8))) out[bit / 8] |= static_cast<uint8_t>(1u << (bit % 8));
  }
  return out;
}

std::string visible_string(std::span<const uint8_t> bytes) {
  std::string s(bytes.begin(), bytes.end());
  auto end = s.find('\0');
  if (end != std::string::npos) s.resize(end);
  return s;
}

void text_child(pugi::xml_node parent, const char* name, const std::string& text) {
  parent.append_child(name).text().set(text.c_str());
}

// The basic type an enumeration of `bits` bits is carried in: BITn below a byte, else the
// unsigned integer of that size.
std::string enum_base_type(uint16_t bits) {
  if (bits < 8) return fmt::format("BIT{}", bits);
  if (bits == 8) return "USINT";
  if (bits == 16) return "UINT";
  return "UDINT";
}

bool is_readable(uint16_t access) {
  return (access & coe::access::kReadAll) != 0;
}

// Writes one Dictionary (ETG.2000 DictionaryType): the DataTypes every object uses, then the
// Objects. `depend_on_slot` marks module objects whose index moves with the slot.
class DictionaryWriter {
 public:
  DictionaryWriter(pugi::xml_node dictionary, const coe::ObjectDictionary& od, bool depend_on_slot)
      : od_(od), depend_on_slot_(depend_on_slot) {
    types_ = dictionary.append_child("DataTypes");
    objects_ = dictionary.append_child("Objects");
  }

  // `skip`: objects described elsewhere (a module's objects at device level).
  void write_all(const std::set<uint16_t>* skip = nullptr) {
    // Enumeration objects (0x0800..0x0FFF) are data types: the ESI carries them once, as the
    // DataType with EnumInfo their users declare, not as Objects.
    od_.for_each([&](const coe::Object& obj) {
      if (skip != nullptr && skip->count(obj.index()) != 0) return;
      if (!coe::is_enum_type(obj.index())) write_object(obj);
    });
    write_unit_types();
  }

 private:
  // A basic or enum type by name, declared once.
  std::string declare_entry_type(const coe::Entry& e) {
    std::string name = esi_type_name(od_, e);
    if (!declared_.insert(name).second) return name;
    if (coe::is_enum_type(e.data_type)) {
      const auto* en = od_.find_enum(e.data_type);
      const uint16_t bits = en ? en->bit_size : e.bit_length;
      // ETG.2000 §5.4.3 DataType/BaseType: the basic type the enumeration values are of, itself
      // a declared DataType (the schema's BaseTypeRef key).
      const std::string base = enum_base_type(bits);
      if (declared_.insert(base).second) {
        auto b = types_.append_child("DataType");
        text_child(b, "Name", base);
        const int base_bits = bits < 8 ? bits : bits == 8 ? 8 : bits == 16 ? 16 : 32;
        b.append_child("BitSize").text().set(base_bits);
      }
      auto dt = types_.append_child("DataType");
      text_child(dt, "Name", name);
      text_child(dt, "BaseType", base);
      dt.append_child("BitSize").text().set(bits);
      if (en) {
        for (const auto& v : en->values) {
          auto info = dt.append_child("EnumInfo");
          text_child(info, "Text", v.name);
          info.append_child("Enum").text().set(static_cast<long long>(v.value));
        }
      }
    } else {
      auto dt = types_.append_child("DataType");
      text_child(dt, "Name", name);
      dt.append_child("BitSize").text().set(e.bit_length);
    }
    return name;
  }

  void flags(pugi::xml_node parent, uint16_t access, bool with_pdo) {
    auto f = parent.append_child("Flags");
    auto a = esi_access(access);
    auto node = f.append_child("Access");
    node.text().set(a.access.c_str());
    if (!a.read_restrictions.empty())
      node.append_attribute("ReadRestrictions").set_value(a.read_restrictions.c_str());
    if (!a.write_restrictions.empty())
      node.append_attribute("WriteRestrictions").set_value(a.write_restrictions.c_str());
    if (with_pdo) {
      auto m = esi_pdo_mapping(access);
      if (!m.empty()) text_child(f, "PdoMapping", m);
    }
    if (access & coe::access::kBackup) f.append_child("Backup").text().set(1);
    if (access & coe::access::kSettings) f.append_child("Setting").text().set(1);
  }

  // The entry's values (default, range) and its ETG.1004 unit, in ObjectInfoType order.
  void default_info(pugi::xml_node info, const coe::Object& obj, const coe::Entry& e) {
    value_info(info, obj, e);
    if (e.unit != 0) {
      text_child(info, "Unit", esi_hex(e.unit, 8));
      units_.insert(coe::unit::numerator(e.unit));
      units_.insert(coe::unit::denominator(e.unit));
    }
  }

  // ETG.2000 DictionaryType/UnitTypes (before DataTypes): name and symbol of every notation
  // index an entry's Unit uses (coe/unit_code.hpp), so a configurator shows "°C" without its
  // own copy of the ETG.1004 table.
  void write_unit_types() {
    units_.erase(coe::unit::kNone);
    if (units_.empty()) return;
    auto list = types_.parent().insert_child_before("UnitTypes", types_);
    for (uint8_t index : units_) {
      const auto n = coe::unit::notation(index);
      if (!n) continue;  // every code rackcat writes is built from kNotations
      auto u = list.append_child("UnitType");
      text_child(u, "NotationIndex", esi_hex(index, 2));
      text_child(u, "Name", std::string(n->name));
      text_child(u, "Symbol", std::string(n->symbol));
    }
  }

  void value_info(pugi::xml_node info, const coe::Object& obj, const coe::Entry& e) {
    if (!is_readable(e.access)) return;
    auto value = entry_value(obj, e);
    if (e.type() == coe::DataType::VisibleString) {
      text_child(info, "DefaultString", visible_string(value));
    } else {
      // A range narrower than the type's (ETG.2000 ObjectInfoType MinData/MaxData, before
      // DefaultData): the limits SDO Information reports and a write is checked against.
      auto limit = [&](const char* name, std::optional<int64_t> v) {
        if (!v) return;
        std::vector<uint8_t> b(e.byte_length());
        for (size_t i = 0; i < b.size() && i < 8; ++i)
          b[i] = static_cast<uint8_t>(static_cast<uint64_t>(*v) >> (8 * i));
        text_child(info, name, hex_bytes(b));
      };
      limit("MinData", e.min);
      limit("MaxData", e.max);
      text_child(info, "DefaultData", hex_bytes(value));
    }
  }

  // ARRAY objects whose elements share type, size and access get an ETG.2000 array type
  // (BaseType + ArrayInfo); anything else is described entry by entry as a record.
  static bool uniform_array(const coe::Object& obj) {
    if (obj.code() != coe::ObjectCode::Array) return false;
    const auto& es = obj.entries();
    if (es.size() < 2) return false;
    const auto& first = es[1];
    for (size_t i = 1; i < es.size(); ++i) {
      const auto& e = es[i];
      if (e.padding || e.subindex != i || e.data_type != first.data_type ||
          e.bit_length != first.bit_length || e.access != first.access ||
          e.bit_offset != first.bit_offset + (i - 1) * first.bit_length) {
        return false;
      }
    }
    return true;
  }

  void write_object(const coe::Object& obj) {
    // An object without entries has no type to announce (the dictionary never builds one).
    if (obj.entries().empty()) return;
    auto o = objects_.append_child("Object");
    auto idx = o.append_child("Index");
    idx.text().set(esi_hex(obj.index(), 4).c_str());
    if (depend_on_slot_) idx.append_attribute("DependOnSlot").set_value(true);
    text_child(o, "Name", obj.name());

    if (obj.code() == coe::ObjectCode::Var) {
      const auto* e = obj.entry(0);
      if (!e) e = &obj.entries().front();
      text_child(o, "Type", declare_entry_type(*e));
      o.append_child("BitSize").text().set(e->bit_length);
      auto info = o.append_child("Info");
      default_info(info, obj, *e);
      if (!info.first_child()) o.remove_child(info);
      flags(o, e->access, true);
      return;
    }

    std::string dt_name = fmt::format("DT{:04X}", obj.index());
    auto size = static_cast<unsigned>(obj.bit_size());
    text_child(o, "Type", dt_name);
    o.append_child("BitSize").text().set(size);
    auto info = o.append_child("Info");
    auto dt = types_.append_child("DataType");
    text_child(dt, "Name", dt_name);
    dt.append_child("BitSize").text().set(size);
    declared_.insert(dt_name);

    const auto& es = obj.entries();
    if (uniform_array(obj)) {
      const auto& sub0 = es[0];
      const auto& first = es[1];
      std::string elem = declare_entry_type(first);
      std::string arr_name = dt_name + "ARR";
      auto n = static_cast<unsigned>(es.size() - 1);
      // The array type goes before the object type that uses it.
      auto arr = types_.insert_child_before("DataType", dt);
      text_child(arr, "Name", arr_name);
      text_child(arr, "BaseType", elem);
      arr.append_child("BitSize").text().set(n * first.bit_length);
      auto ai = arr.append_child("ArrayInfo");
      ai.append_child("LBound").text().set(1);
      ai.append_child("Elements").text().set(n);
      declared_.insert(arr_name);
      write_subitem(dt, sub0, sub0.name, declare_entry_type(sub0));
      auto elems = dt.append_child("SubItem");
      text_child(elems, "Name", "Elements");
      text_child(elems, "Type", arr_name);
      elems.append_child("BitSize").text().set(n * first.bit_length);
      elems.append_child("BitOffs").text().set(first.bit_offset);
      flags(elems, first.access, true);
      // Defaults for the elements in use (subindex 0 = count, ETG.1000.6 §5.6.7.4.2); the
      // slots above it hold no configuration (0xF030, 0x1C12 with 255 slots, UART buffers).
      const uint8_t in_use = obj.sub0();
      for (const auto& e : es) {
        if (!is_readable(e.access)) continue;
        if (e.subindex > in_use) break;
        auto si = info.append_child("SubItem");
        text_child(si, "Name", fmt::format("SubIndex {:03d}", e.subindex));
        default_info(si.append_child("Info"), obj, e);
      }
    } else {
      std::set<std::string> names;
      for (const auto& e : es) {
        if (e.padding) continue;    // a layout gap, not an addressable subindex
        std::string name = e.name;  // the name SDO Information gives, subindex 0 included
        if (name.empty() || !names.insert(name).second) {
          name = fmt::format("{} (SubIndex {:03d})", e.name.empty() ? "Entry" : e.name, e.subindex);
          names.insert(name);
        }
        write_subitem(dt, e, name, declare_entry_type(e));
        if (!is_readable(e.access)) continue;
        auto si = info.append_child("SubItem");
        text_child(si, "Name", name);
        default_info(si.append_child("Info"), obj, e);
      }
    }
    if (!info.first_child()) o.remove_child(info);
    const auto* sub0 = obj.entry(0);
    flags(o, sub0 ? sub0->access : coe::access::kRo, false);
  }

  void write_subitem(pugi::xml_node dt, const coe::Entry& e, const std::string& name,
                     const std::string& type) {
    auto si = dt.append_child("SubItem");
    text_child(si, "SubIdx", std::to_string(e.subindex));
    text_child(si, "Name", name);
    text_child(si, "Type", type);
    si.append_child("BitSize").text().set(e.bit_length);
    si.append_child("BitOffs").text().set(e.bit_offset);
    flags(si, e.access, true);
  }

  const coe::ObjectDictionary& od_;
  bool depend_on_slot_;
  pugi::xml_node types_;
  pugi::xml_node objects_;
  std::set<std::string> declared_;
  std::set<uint8_t> units_;  // notation indices the Units use
};

pugi::xml_node write_profile(pugi::xml_node parent, const char* element,
                             const coe::ObjectDictionary& od, bool depend_on_slot,
                             const std::set<uint16_t>* skip = nullptr) {
  auto profile = parent.append_child(element);
  // ETG.5001: a modular device announces profile 5001.
  profile.append_child("ProfileNo").text().set(5001);
  DictionaryWriter(profile.append_child("Dictionary"), od, depend_on_slot).write_all(skip);
  return profile;
}

// The texts of the 0x10F3 messages (ETG.2000 DiagnosticsType, ETG.1020 ch. 13): one
// DiagMessage per text ID with its class; %1..%4 stand for the message's parameters by
// position (the device's own; for the rack RIM, module, channel, detail).
void write_diag_messages(pugi::xml_node profile, const std::vector<DiagMessage>& texts) {
  auto messages = profile.append_child("DiagMessages");
  for (const DiagMessage& t : texts) {
    auto m = messages.append_child("DiagMessage");
    text_child(m, "TextId", esi_hex(t.text_id, 4));
    auto text = m.append_child("MessageText");
    text.text().set(t.text.c_str());
    text.append_attribute("LcId").set_value(1033);
    const auto type = t.type;
    text_child(m.append_child("Flags"), "DiagClass",
               type == coe::diag::Type::Error     ? "error"
               : type == coe::diag::Type::Warning ? "warning"
                                                  : "information");
  }
}

void write_pdo(pugi::xml_node parent, const char* element, const PdoDescription& p,
               const coe::ObjectDictionary* od, bool depend_on_slot) {
  auto node = parent.append_child(element);
  if (p.fixed) node.append_attribute("Fixed").set_value(true);
  // A slot's PDO at device level describes the default rack; a configurator that fills the
  // slots replaces it with the module's own (ETG.2000 PdoType/@OverwrittenByModule).
  if (p.from_module) node.append_attribute("OverwrittenByModule").set_value(true);
  if (p.mandatory) node.append_attribute("Mandatory").set_value(true);
  // Sm present = assigned by default (ETG.2000 PdoType/@Sm).
  if (p.assigned) node.append_attribute("Sm").set_value(p.sm);
  auto idx = node.append_child("Index");
  idx.text().set(esi_hex(p.index, 4).c_str());
  if (depend_on_slot) idx.append_attribute("DependOnSlot").set_value(true);
  text_child(node, "Name", p.name);
  for (const auto& e : p.entries) {
    auto en = node.append_child("Entry");
    auto ei = en.append_child("Index");
    ei.text().set(esi_hex(e.index, 4).c_str());
    if (e.index == 0) {  // padding gap
      en.append_child("BitLen").text().set(e.bit_length);
      continue;
    }
    if (depend_on_slot && e.index >= 0x2000) ei.append_attribute("DependOnSlot").set_value(true);
    text_child(en, "SubIndex", esi_hex(e.subindex, 2));
    en.append_child("BitLen").text().set(e.bit_length);
    if (!e.name.empty()) text_child(en, "Name", e.name);
    std::string type;
    if (od) {
      if (const auto* obj = od->find(e.index))
        if (const auto* entry = obj->entry(e.subindex)) type = esi_type_name(*od, *entry);
    }
    if (type.empty()) {
      coe::Entry synthetic;
      synthetic.data_type = e.data_type;
      synthetic.bit_length = e.bit_length;
      type = od ? esi_type_name(*od, synthetic) : std::string(coe::type_name(synthetic.type()));
    }
    if (!type.empty()) text_child(en, "DataType", type);
  }
}

const char* sm_text(SmType t) {
  switch (t) {
    case SmType::MailboxOut:
      return "MBoxOut";
    case SmType::MailboxIn:
      return "MBoxIn";
    case SmType::ProcessOut:
      return "Outputs";
    case SmType::ProcessIn:
      return "Inputs";
    default:
      return "";
  }
}

const char* fmmu_text(FmmuUsage f) {
  switch (f) {
    case FmmuUsage::Outputs:
      return "Outputs";
    case FmmuUsage::Inputs:
      return "Inputs";
    case FmmuUsage::SmStatus:
      return "MBoxState";
    default:
      return "";
  }
}

struct StringWriter : pugi::xml_writer {
  std::string out;
  void write(const void* data, size_t size) override {
    out.append(static_cast<const char*>(data), size);
  }
};

}  // namespace

std::string esi_hex(uint32_t value, int digits) {
  return fmt::format("#x{:0{}X}", value, digits);
}

EsiAccess esi_access(uint16_t a) {
  bool r = (a & coe::access::kReadAll) != 0;
  bool w = (a & coe::access::kWriteAll) != 0;
  EsiAccess out;
  out.access = r && w ? "rw" : w ? "wo" : "ro";
  if (r) out.read_restrictions = restriction(a & kReadPreOp, a & kReadSafeOp, a & kReadOp);
  if (w) out.write_restrictions = restriction(a & kWritePreOp, a & kWriteSafeOp, a & kWriteOp);
  return out;
}

std::string esi_pdo_mapping(uint16_t a) {
  std::string m;
  if (a & coe::access::kTxPdoMappable) m += "T";
  if (a & coe::access::kRxPdoMappable) m += "R";
  return m;
}

std::string esi_type_name(const coe::ObjectDictionary& od, const coe::Entry& e) {
  if (coe::is_enum_type(e.data_type)) {
    if (const auto* en = od.find_enum(e.data_type)) return en->name;
    return fmt::format("DT{:04X}", e.data_type);
  }
  auto t = e.type();
  if (coe::is_string(t)) return fmt::format("{}({})", coe::type_name(t), e.bit_length / 8);
  auto name = coe::type_name(t);
  if (!name.empty()) return std::string(name);
  // Unknown type index: name it by size so the file stays self-consistent.
  switch (e.bit_length) {
    case 8:
      return "USINT";
    case 16:
      return "UINT";
    case 32:
      return "UDINT";
    case 64:
      return "ULINT";
    default:
      if (e.bit_length < 8) return fmt::format("BIT{}", e.bit_length);
      return fmt::format("OCTET_STRING({})", (e.bit_length + 7) / 8);
  }
}

std::string write_esi(const EsiContent& c) {
  const DeviceDescription& d = *c.device;
  pugi::xml_document doc;
  auto decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version").set_value("1.0");
  decl.append_attribute("encoding").set_value("UTF-8");
  auto root = doc.append_child("EtherCATInfo");
  root.append_attribute("xmlns:xsi").set_value("http://www.w3.org/2001/XMLSchema-instance");
  root.append_attribute("xsi:noNamespaceSchemaLocation").set_value("EtherCATInfo.xsd");
  root.append_attribute("Version").set_value("1.14");

  auto vendor = root.append_child("Vendor");
  text_child(vendor, "Id", esi_hex(d.vendor_id, 8));
  text_child(vendor, "Name", d.vendor_name);

  auto descriptions = root.append_child("Descriptions");
  auto group = descriptions.append_child("Groups").append_child("Group");
  text_child(group, "Type", d.group_type);
  text_child(group, "Name", d.group_name);

  auto device = descriptions.append_child("Devices").append_child("Device");
  device.append_attribute("Physics").set_value("YY");
  auto type = device.append_child("Type");
  type.text().set(d.order_code.c_str());
  type.append_attribute("ProductCode").set_value(esi_hex(d.product_code, 8).c_str());
  type.append_attribute("RevisionNo").set_value(esi_hex(d.revision, 8).c_str());
  text_child(device, "Name", d.device_name);
  {
    // ETG.2000 InfoType: the state-machine and mailbox timeouts a master should allow.
    auto info = device.append_child("Info");
    auto sm_timeout = info.append_child("StateMachine").append_child("Timeout");
    sm_timeout.append_child("PreopTimeout").text().set(d.timeouts.preop);
    sm_timeout.append_child("SafeopOpTimeout").text().set(d.timeouts.safeop_op);
    sm_timeout.append_child("BackToInitTimeout").text().set(d.timeouts.back_to_init);
    sm_timeout.append_child("BackToSafeopTimeout").text().set(d.timeouts.back_to_safeop);
    auto mbx_timeout = info.append_child("Mailbox").append_child("Timeout");
    mbx_timeout.append_child("RequestTimeout").text().set(d.timeouts.mailbox_request);
    mbx_timeout.append_child("ResponseTimeout").text().set(d.timeouts.mailbox_response);
  }
  text_child(device, "GroupType", d.group_type);
  // Module objects are defined once, in their <Module> (ETG.5001; a configurator that fills the
  // slots offline adds them per slot): the device level carries the device's own objects.
  auto device_profile = write_profile(device, "Profile", *c.dictionary, false, &c.module_objects);
  if (d.coe.diag_history && c.dictionary->find(coe::diag::kIndex) && !c.diag_messages.empty()) {
    write_diag_messages(device_profile, c.diag_messages);
  }

  for (auto f : d.fmmus) text_child(device, "Fmmu", fmmu_text(f));
  for (const auto& sm : d.sms) {
    auto node = device.append_child("Sm");
    node.text().set(sm_text(sm.type));
    node.append_attribute("MinSize").set_value(sm.min_size);
    node.append_attribute("MaxSize").set_value(sm.max_size);
    node.append_attribute("DefaultSize").set_value(sm.default_size);
    node.append_attribute("StartAddress").set_value(esi_hex(sm.start, 4).c_str());
    node.append_attribute("ControlByte").set_value(esi_hex(sm.control, 2).c_str());
    node.append_attribute("Enable").set_value(sm.enable ? 1 : 0);
  }
  for (const auto& p : d.rx_pdos) write_pdo(device, "RxPdo", p, c.dictionary, false);
  for (const auto& p : d.tx_pdos) write_pdo(device, "TxPdo", p, c.dictionary, false);

  auto mailbox = device.append_child("Mailbox");
  auto coe_node = mailbox.append_child("CoE");
  coe_node.append_attribute("SdoInfo").set_value(d.coe.sdo_info);
  coe_node.append_attribute("PdoAssign").set_value(d.coe.pdo_assign);
  coe_node.append_attribute("PdoConfig").set_value(d.coe.pdo_config);
  coe_node.append_attribute("PdoUpload").set_value(d.coe.upload_at_startup);
  coe_node.append_attribute("CompleteAccess").set_value(d.coe.complete_access);
  coe_node.append_attribute("SegmentedSdo").set_value(d.coe.segmented_sdo);
  if (d.coe.diag_history && c.dictionary->find(coe::diag::kIndex)) {
    coe_node.append_attribute("DiagHistory").set_value(true);
  }
  if (d.foe) mailbox.append_child("FoE");

  if (!d.dc_modes.empty()) {
    auto dc = device.append_child("Dc");
    for (const auto& m : d.dc_modes) {
      auto om = dc.append_child("OpMode");
      text_child(om, "Name", m.name);
      text_child(om, "Desc", m.description);
      text_child(om, "AssignActivate", esi_hex(m.assign_activate, 4));
      if (m.assign_activate & 0x0100) {  // SYNC0 active: cycle = factor x master cycle
        auto ct = om.append_child("CycleTimeSync0");
        ct.text().set(static_cast<long long>(m.cycle_time_sync0));
        ct.append_attribute("Factor").set_value(m.cycle_time_sync0_factor);
        om.append_child("ShiftTimeSync0").text().set(m.shift_time_sync0);
      }
    }
  }

  if (!c.modules.empty()) {
    auto slots = device.append_child("Slots");
    slots.append_attribute("DownloadModuleIdentList").set_value(true);
    slots.append_attribute("MaxSlotCount").set_value(c.slots.max_slots);
    slots.append_attribute("SlotPdoIncrement").set_value(c.slots.pdo_increment);
    slots.append_attribute("SlotIndexIncrement")
        .set_value(esi_hex(c.slots.index_increment, 2).c_str());
    slots.append_attribute("IdentifyModuleBy").set_value("ModuleIdent");
    auto slot = slots.append_child("Slot");
    slot.append_attribute("MinInstances").set_value(0);
    slot.append_attribute("MaxInstances").set_value(c.slots.max_slots);
    slot.append_attribute("SlotPdoIncrement").set_value(c.slots.pdo_increment);
    slot.append_attribute("SlotIndexIncrement")
        .set_value(esi_hex(c.slots.index_increment, 2).c_str());
    text_child(slot, "Name", c.slots.slot_name);
    for (const auto& m : c.modules) text_child(slot, "ModuleIdent", esi_hex(m.ident, 8));
  }

  auto eeprom = device.append_child("Eeprom");
  eeprom.append_child("ByteSize").text().set(static_cast<unsigned long long>(c.eeprom_bytes));
  text_child(eeprom, "ConfigData", hex_bytes(c.config_data));
  if (d.bootstrap.receive_size != 0) {
    // SII words 0x14-0x17 as stored: receive offset, receive size, send offset, send size.
    std::vector<uint8_t> boot;
    for (uint16_t w : {d.bootstrap.receive_offset, d.bootstrap.receive_size,
                       d.bootstrap.send_offset, d.bootstrap.send_size}) {
      boot.push_back(static_cast<uint8_t>(w));
      boot.push_back(static_cast<uint8_t>(w >> 8));
    }
    text_child(eeprom, "BootStrap", hex_bytes(boot));
  }

  if (!c.modules.empty()) {
    auto modules = descriptions.append_child("Modules");
    for (const auto& m : c.modules) {
      auto mod = modules.append_child("Module");
      auto t = mod.append_child("Type");
      t.text().set(m.type.c_str());
      t.append_attribute("ModuleIdent").set_value(esi_hex(m.ident, 8).c_str());
      text_child(mod, "Name", m.name);
      for (const auto& p : m.rx_pdos) write_pdo(mod, "RxPdo", p, &m.dictionary, true);
      for (const auto& p : m.tx_pdos) write_pdo(mod, "TxPdo", p, &m.dictionary, true);
      write_profile(mod, "Profile", m.dictionary, true);
    }
  }

  StringWriter w;
  // Tabs, as vendor ESI files use: one byte per level keeps large racks small.
  doc.save(w, "\t", pugi::format_default, pugi::encoding_utf8);
  return std::move(w.out);
}

}  // namespace rackcat::esi
