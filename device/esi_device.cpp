// ESI device reader (ETG.2000 EtherCATInfo; SII mapping per ETG.2010 §2).
#include "device/esi_device.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <map>
#include <pugixml.hpp>
#include <set>

#include "base/fd_io.hpp"
#include "base/little_endian.hpp"
#include "coe/access.hpp"
#include "coe/data_type.hpp"
#include "device/esi_error.hpp"
#include "esi/describe_dictionary.hpp"

namespace rackcat::device {

std::optional<int64_t> parse_hex_dec(std::string_view t) {
  while (!t.empty() && (t.front() == ' ' || t.front() == '\n' || t.front() == '\t'))
    t.remove_prefix(1);
  while (!t.empty() && (t.back() == ' ' || t.back() == '\n' || t.back() == '\t'))
    t.remove_suffix(1);
  if (t.empty()) return std::nullopt;
  int base = 10;
  if (t.size() > 2 && t[0] == '#' && (t[1] == 'x' || t[1] == 'X')) {
    t.remove_prefix(2);
    base = 16;
  }
  int64_t v = 0;
  if (base == 16) {
    uint64_t u = 0;
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), u, 16);
    if (ec != std::errc{} || p != t.data() + t.size()) return std::nullopt;
    v = static_cast<int64_t>(u);
  } else {
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v, 10);
    if (ec != std::errc{} || p != t.data() + t.size()) return std::nullopt;
  }
  return v;
}

namespace {

using esi::DeviceDescription;
using esi::PdoDescription;
using esi::PdoEntryDescription;
using esi::SmType;

// A resolved data type: a basic CoE type, or a named ETG.2000 DataType (record or array).
struct TypeInfo {
  uint16_t coe_type = 0;  // basic types; 0 for records/arrays
  uint16_t bits = 0;
  pugi::xml_node node;  // named DataType element (records, arrays, enums)
};

class Reader {
 public:
  Reader(std::string_view xml, std::string file) : xml_(xml), file_(std::move(file)) {}

  [[noreturn]] void fail(pugi::xml_node at, const std::string& reason) const {
    size_t line = 1;
    const ptrdiff_t off = at ? at.offset_debug() : -1;
    if (off > 0) {
      line += static_cast<size_t>(
          std::count(xml_.begin(), xml_.begin() + std::min<ptrdiff_t>(off, xml_.size()), '\n'));
    }
    throw FileError(file_, line, reason);
  }

  int64_t number(pugi::xml_node at, const char* text, const char* what) const {
    auto v = parse_hex_dec(text);
    if (!v) fail(at, std::string(what) + " \"" + text + "\" is not a number (#x.. or decimal)");
    return *v;
  }
  int64_t child_number(pugi::xml_node n, const char* child,
                       std::optional<int64_t> dflt = {}) const {
    auto c = n.child(child);
    if (!c) {
      if (dflt) return *dflt;
      fail(n, std::string("<") + n.name() + "> has no <" + child + ">");
    }
    return number(c, c.text().get(), child);
  }
  int64_t attr_number(pugi::xml_node n, const char* attr, int64_t dflt) const {
    auto a = n.attribute(attr);
    if (!a) return dflt;
    return number(n, a.value(), attr);
  }

  EsiDevice read(const DeviceSelector& sel) {
    pugi::xml_document doc;
    auto res = doc.load_buffer(xml_.data(), xml_.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!res) {
      size_t line =
          1 + static_cast<size_t>(std::count(
                  xml_.begin(), xml_.begin() + std::min<ptrdiff_t>(res.offset, xml_.size()), '\n'));
      throw FileError(file_, line, std::string("not well-formed XML: ") + res.description());
    }
    auto root = doc.child("EtherCATInfo");
    if (!root) fail(doc.first_child(), "root element is not <EtherCATInfo> (ETG.2000)");
    auto devices = root.child("Descriptions").child("Devices");
    std::vector<pugi::xml_node> matches;
    for (auto d : devices.children("Device")) {
      auto type = d.child("Type");
      if (!sel.name.empty()) {
        bool name_match = sel.name == type.text().get();
        for (auto n : d.children("Name")) name_match = name_match || sel.name == n.text().get();
        if (!name_match) continue;
      }
      if (sel.product_code &&
          attr_number(type, "ProductCode", -1) != static_cast<int64_t>(*sel.product_code))
        continue;
      if (sel.revision &&
          attr_number(type, "RevisionNo", -1) != static_cast<int64_t>(*sel.revision))
        continue;
      matches.push_back(d);
    }
    auto describe_sel = [&] {
      std::string s;
      if (!sel.name.empty()) s += "name \"" + sel.name + "\"";
      char buf[48];
      if (sel.product_code) {
        std::snprintf(buf, sizeof buf, "%sproduct code #x%08X", s.empty() ? "" : ", ",
                      *sel.product_code);
        s += buf;
      }
      if (sel.revision) {
        std::snprintf(buf, sizeof buf, ", revision #x%08X", *sel.revision);
        s += buf;
      }
      return s.empty() ? std::string("(any)") : s;
    };
    if (matches.empty()) fail(devices ? devices : root, "no <Device> matches " + describe_sel());
    if (matches.size() > 1)
      fail(matches[1], "more than one <Device> matches " + describe_sel() + "; name the revision");
    vendor_ = root.child("Vendor");
    groups_ = root.child("Descriptions").child("Groups");
    catalogue_ = root.child("Descriptions").child("Modules");
    selector_ = &sel;
    return read_device(matches.front());
  }

 private:
  EsiDevice read_device(pugi::xml_node dev) {
    EsiDevice out;
    out.file = file_;
    DeviceDescription& d = out.description;
    d.vendor_id = static_cast<uint32_t>(child_number(vendor_, "Id"));
    d.vendor_name = vendor_.child("Name").text().get();
    auto type = dev.child("Type");
    d.product_code = static_cast<uint32_t>(attr_number(type, "ProductCode", 0));
    d.revision = static_cast<uint32_t>(attr_number(type, "RevisionNo", 0));
    d.order_code = type.text().get();
    d.device_name = dev.child("Name").text().get();
    if (d.device_name.empty()) d.device_name = d.order_code;
    d.group_type = dev.child("GroupType").text().get();
    for (auto g : groups_.children("Group")) {
      if (d.group_type == g.child("Type").text().get()) d.group_name = g.child("Name").text().get();
    }
    if (auto e = dev.child("Electrical").child("EBusCurrent"))
      d.ebus_current_ma = static_cast<int16_t>(number(e, e.text().get(), "EBusCurrent"));

    for (auto f : dev.children("Fmmu")) {
      std::string_view t = f.text().get();
      if (t == "Outputs")
        d.fmmus.push_back(esi::FmmuUsage::Outputs);
      else if (t == "Inputs")
        d.fmmus.push_back(esi::FmmuUsage::Inputs);
      else if (t == "MBoxState")
        d.fmmus.push_back(esi::FmmuUsage::SmStatus);
      else
        fail(f, "unknown <Fmmu> usage \"" + std::string(t) + "\"");
    }
    std::vector<pugi::xml_node> sm_nodes;
    for (auto s : dev.children("Sm")) {
      sm_nodes.push_back(s);
      esi::SyncManagerDescription sm;
      std::string_view t = s.text().get();
      if (t == "MBoxOut")
        sm.type = SmType::MailboxOut;
      else if (t == "MBoxIn")
        sm.type = SmType::MailboxIn;
      else if (t == "Outputs")
        sm.type = SmType::ProcessOut;
      else if (t == "Inputs")
        sm.type = SmType::ProcessIn;
      else
        fail(s, "unknown <Sm> type \"" + std::string(t) + "\"");
      sm.start = static_cast<uint16_t>(attr_number(s, "StartAddress", 0));
      sm.control = static_cast<uint8_t>(attr_number(s, "ControlByte", 0));
      sm.default_size = static_cast<uint16_t>(attr_number(s, "DefaultSize", 0));
      sm.min_size = static_cast<uint16_t>(attr_number(s, "MinSize", 0));
      sm.max_size = static_cast<uint16_t>(attr_number(s, "MaxSize", 0));
      sm.enable = attr_number(s, "Enable", 1) != 0;
      d.sms.push_back(sm);
    }
    remap_process_sms(d, sm_nodes);
    auto mailbox = dev.child("Mailbox");
    auto coe_node = mailbox.child("CoE");
    const bool has_mbx_sm = std::any_of(d.sms.begin(), d.sms.end(),
                                        [](auto& s) { return s.type == SmType::MailboxOut; });
    if (mailbox && !has_mbx_sm) fail(mailbox, "<Mailbox> but no <Sm>MBoxOut</Sm>");
    if (coe_node) {
      out.has_coe = true;
      auto flag = [&](const char* a, bool dflt) {
        auto at = coe_node.attribute(a);
        return at ? at.as_bool() : dflt;
      };
      d.coe.sdo = true;
      d.coe.sdo_info = flag("SdoInfo", false);
      d.coe.pdo_assign = flag("PdoAssign", false);
      d.coe.pdo_config = flag("PdoConfig", false);
      d.coe.upload_at_startup = flag("PdoUpload", false);
      d.coe.complete_access = flag("CompleteAccess", false);
      d.coe.segmented_sdo = flag("SegmentedSdo", true);
    } else {
      d.coe = esi::CoeDetails{false, false, false, false, false, false, false};
      // A mailbox device without CoE may serve FoE (ETG.1000.6 §5.8); nothing else.
      for (auto p : mailbox.children())
        if (std::string_view(p.name()) != "FoE")
          fail(p, std::string("mailbox protocol <") + p.name() +
                      "> is not supported (CoE and FoE only)");
    }
    // FoE is announced in the SII (word 0x1C bit 3) as the ESI says; `rackcat run` serves it
    // from a directory of the device's own (GenericDevice::serve_foe, device/foe_files.hpp).
    d.foe = static_cast<bool>(mailbox.child("FoE"));
    if (auto eeprom = dev.child("Eeprom")) {
      if (auto cd = eeprom.child("ConfigData")) read_config_data(cd, d.config);
      if (auto bs = eeprom.child("BootStrap")) read_bootstrap(bs, d.bootstrap);
    }

    if (out.has_coe) {
      if (auto dict = dev.child("Profile").child("Dictionary"))
        read_dictionary(dict, out.dictionary);
      add_enum_objects(dev, out.dictionary);
    }
    for (auto p : dev.children("RxPdo")) d.rx_pdos.push_back(read_pdo(p, sm_nodes, d, out));
    for (auto p : dev.children("TxPdo")) d.tx_pdos.push_back(read_pdo(p, sm_nodes, d, out));
    if (selector_->modules) apply_module_list(dev, out, *selector_->modules);
    check_sm_sizes(d, sm_nodes, dev);
    for (auto om : dev.child("Dc").children("OpMode")) {
      esi::DcOpModeDescription m;
      m.name = om.child("Name").text().get();
      m.description = om.child("Desc").text().get();
      m.assign_activate = static_cast<uint16_t>(child_number(om, "AssignActivate", 0));
      if (auto c = om.child("CycleTimeSync0")) {
        m.cycle_time_sync0 = static_cast<uint32_t>(number(c, c.text().get(), "CycleTimeSync0"));
        m.cycle_time_sync0_factor = static_cast<int16_t>(attr_number(c, "Factor", 0));
      }
      m.shift_time_sync0 = static_cast<int32_t>(child_number(om, "ShiftTimeSync0", 0));
      if (auto c = om.child("CycleTimeSync1"))
        m.cycle_time_sync1_factor = static_cast<int16_t>(attr_number(c, "Factor", 0));
      m.shift_time_sync1 = static_cast<int32_t>(child_number(om, "ShiftTimeSync1", 0));
      d.dc_modes.push_back(std::move(m));
    }
    if (out.has_coe) complete_dictionary(out, dev);
    return out;
  }

  // Eeprom/BootStrap (ETG.2000): SII words 0x14-0x17 as stored, 8 hex bytes: receive
  // mailbox offset and size, send mailbox offset and size in BOOT (ETG.2010 Table 2).
  void read_bootstrap(pugi::xml_node bs, esi::BootstrapMailbox& m) {
    const std::string hex = bs.text().get();
    if (hex.size() != 16) fail(bs, "<BootStrap> is not 8 hex bytes");
    uint16_t w[4] = {};
    for (size_t i = 0; i < 8; ++i) {
      unsigned v = 0;
      auto [p, ec] = std::from_chars(hex.data() + 2 * i, hex.data() + 2 * i + 2, v, 16);
      if (ec != std::errc{} || p != hex.data() + 2 * i + 2)
        fail(bs, "<BootStrap> is not hex bytes");
      w[i / 2] = static_cast<uint16_t>(w[i / 2] | (v << (8 * (i % 2))));
    }
    m = {w[0], w[1], w[2], w[3]};
  }

  void read_config_data(pugi::xml_node cd, esi::EscConfigArea& c) {
    std::string hex = cd.text().get();
    std::vector<uint8_t> b;
    for (size_t i = 0; i + 1 < hex.size(); i += 2) {
      unsigned v = 0;
      auto [p, ec] = std::from_chars(hex.data() + i, hex.data() + i + 2, v, 16);
      if (ec != std::errc{} || p != hex.data() + i + 2) fail(cd, "<ConfigData> is not hex bytes");
      b.push_back(static_cast<uint8_t>(v));
    }
    auto w = [&](size_t i) -> uint16_t { return i * 2 + 1 < b.size() ? le::get16(&b[2 * i]) : 0; };
    c.pdi_control = w(0);
    c.pdi_config = w(1);
    c.sync_impulse_length = w(2);
    c.extended_pdi_config = w(3);
    c.station_alias = w(4);
  }

  // ---- data types ----------------------------------------------------------------------

  std::optional<TypeInfo> basic_type(std::string_view name) const {
    using coe::DataType;
    static const std::map<std::string_view, std::pair<DataType, uint16_t>> k = {
        {"BOOL", {DataType::Boolean, 1}},
        {"BIT", {DataType::Boolean, 1}},
        {"SINT", {DataType::Integer8, 8}},
        {"INT", {DataType::Integer16, 16}},
        {"DINT", {DataType::Integer32, 32}},
        {"LINT", {DataType::Integer64, 64}},
        {"USINT", {DataType::Unsigned8, 8}},
        {"UINT", {DataType::Unsigned16, 16}},
        {"UDINT", {DataType::Unsigned32, 32}},
        {"ULINT", {DataType::Unsigned64, 64}},
        {"BYTE", {DataType::Unsigned8, 8}},
        {"WORD", {DataType::Unsigned16, 16}},
        {"DWORD", {DataType::Unsigned32, 32}},
        {"REAL", {DataType::Real32, 32}},
        {"LREAL", {DataType::Real64, 64}},
        {"INT24", {DataType::Integer24, 24}},
        {"UINT24", {DataType::Unsigned24, 24}},
        {"BITARR8", {DataType::Unsigned8, 8}},
        {"BITARR16", {DataType::Unsigned16, 16}},
        {"BITARR32", {DataType::Unsigned32, 32}},
        {"BIT1", {DataType::Bit1, 1}},
        {"BIT2", {DataType::Bit2, 2}},
        {"BIT3", {DataType::Bit3, 3}},
        {"BIT4", {DataType::Bit4, 4}},
        {"BIT5", {DataType::Bit5, 5}},
        {"BIT6", {DataType::Bit6, 6}},
        {"BIT7", {DataType::Bit7, 7}},
        {"BIT8", {DataType::Bit8, 8}},
    };
    if (auto it = k.find(name); it != k.end())
      return TypeInfo{static_cast<uint16_t>(it->second.first), it->second.second, {}};
    auto sized = [&](std::string_view prefix, DataType t) -> std::optional<TypeInfo> {
      if (name.substr(0, prefix.size()) != prefix || name.back() != ')') return std::nullopt;
      auto n = parse_hex_dec(name.substr(prefix.size(), name.size() - prefix.size() - 1));
      if (!n || *n <= 0 || *n > 8000) return std::nullopt;
      return TypeInfo{static_cast<uint16_t>(t), static_cast<uint16_t>(*n * 8), {}};
    };
    if (auto t = sized("STRING(", DataType::VisibleString)) return t;
    if (auto t = sized("OCTET_STRING(", DataType::OctetString)) return t;
    if (auto t = sized("ARRAY [0..", DataType::OctetString)) return std::nullopt;
    return std::nullopt;
  }

  // The standard structure a RECORD object of the communication area has, as SDO Information
  // gives its data type (ETG.1000.6 §5.6.7.4.5 complex data types 0x0020..0x002F): 0x1018
  // IDENTITY, PDO mapping objects PDO_MAPPING, 0x1C32/0x1C33 SM_SYNCHRONISATION, ETG.5001
  // 0xF000 MODULAR_DEVICE_PROFILE, command objects 0xF002 and 0xFBF0..0xFBFF COMMAND_PAR. An ESI
  // names only the DataType; 0 = the generic RECORD (0x002A) when SDO Information asks.
  static uint16_t standard_record_type(uint16_t index) {
    namespace rt = coe::record_type;
    if (index == 0x1018) return rt::kIdentity;
    if ((index >= 0x1600 && index <= 0x17FF) || (index >= 0x1A00 && index <= 0x1BFF))
      return rt::kPdoMapping;
    if (index == 0x1C32 || index == 0x1C33) return rt::kSmSynchronisation;
    if (index == 0xF000) return rt::kModularDeviceProfile;
    if (index == 0xF002 || (index >= 0xFBF0 && index <= 0xFBFF)) return rt::kCommandPar;
    return 0;
  }

  // "DT0800EN04" -> 0x0800 (ETG.2000 naming of enumeration DataTypes).
  static std::optional<uint16_t> enum_index(std::string_view name) {
    if (name.size() < 8 || name.substr(0, 2) != "DT" || name.substr(6, 2) != "EN")
      return std::nullopt;
    unsigned v = 0;
    auto [p, ec] = std::from_chars(name.data() + 2, name.data() + 6, v, 16);
    if (ec != std::errc{} || p != name.data() + 6 || !coe::is_enum_type(static_cast<uint16_t>(v)))
      return std::nullopt;
    return static_cast<uint16_t>(v);
  }

  // Every enumeration DataType DTnnnnENxx of the file (device and module dictionaries) becomes
  // the enum type nnnn and its object (ETG.1000.6 §5.6.7.4.4, structure ENUM 0x0028):
  // subindex 0 the number of values, subindex k the value as 32-bit integer followed by its
  // text, as OCTET_STRING named by the text.
  void add_enum_objects(pugi::xml_node any, coe::ObjectDictionary& od) const {
    std::set<uint16_t> done;
    for (const auto& x : any.root().select_nodes("//DataType[EnumInfo]")) {
      const auto n = x.node();
      const std::string name = n.child("Name").text().get();
      const auto index = enum_index(name);
      if (!index || !done.insert(*index).second || od.find(*index)) continue;
      coe::EnumType t;
      t.index = *index;
      t.name = name;
      t.bit_size = static_cast<uint16_t>(child_number(n, "BitSize"));
      coe::Object o(*index, coe::ObjectCode::Record, name, coe::record_type::kEnum);
      size_t count = 0;
      for (auto e : n.children("EnumInfo")) (void)e, ++count;
      if (count > 0xFE) fail(n, "more than 254 EnumInfo values");
      o.add(coe::make_entry(0, "Number of entries", coe::DataType::Unsigned8, 8, coe::access::kRo,
                            {static_cast<uint8_t>(count)}));
      uint8_t sub = 1;
      for (auto e : n.children("EnumInfo")) {
        const auto value = child_number(e, "Enum");
        const std::string text = e.child("Text").text().get();
        t.values.push_back({value, text});
        std::vector<uint8_t> bytes(4 + text.size());
        for (size_t k = 0; k < 4; ++k) bytes[k] = static_cast<uint8_t>(value >> (8 * k));
        std::copy(text.begin(), text.end(), bytes.begin() + 4);
        const auto bits = static_cast<uint16_t>(bytes.size() * 8);
        o.add(coe::make_entry(sub++, text, coe::DataType::OctetString, bits, coe::access::kRo,
                              std::move(bytes)));
      }
      o.finalize();
      od.add_enum(std::move(t));
      od.add(std::move(o));
    }
  }

  TypeInfo resolve_type(pugi::xml_node at, std::string_view name) const {
    if (auto b = basic_type(name)) return *b;
    if (auto it = types_.find(std::string(name)); it != types_.end()) {
      auto n = it->second;
      if (n.child("EnumInfo")) {
        const auto bits = static_cast<uint16_t>(child_number(n, "BitSize"));
        // An enumeration named DTnnnnENxx is the enum data type object nnnn (0x0800..0x0FFF,
        // ETG.1000.6 §5.6.7.4.4; see add_enum_objects); any other is carried as the unsigned
        // type of its size (its value names are not served).
        if (auto index = enum_index(name)) return TypeInfo{*index, bits, {}};
        uint16_t t = bits <= 8 ? 0x0005 : bits <= 16 ? 0x0006 : 0x0007;
        return TypeInfo{t, bits, {}};
      }
      if (!n.child("SubItem") && n.child("BaseType") && !n.child("ArrayInfo"))
        return resolve_type(n.child("BaseType"), n.child("BaseType").text().get());
      return TypeInfo{0, static_cast<uint16_t>(child_number(n, "BitSize")), n};
    }
    fail(at, "unknown data type \"" + std::string(name) + "\"");
  }

  uint16_t read_access(pugi::xml_node flags, uint16_t dflt) const {
    if (!flags) return dflt;
    uint16_t bits = 0;
    auto acc = flags.child("Access");
    if (!acc) return dflt;
    std::string_view a = acc.text().get();
    auto states = [&](const char* attr) -> uint16_t {
      std::string_view r = acc.attribute(attr).value();
      if (r.empty()) return 7;
      if (r == "PreOP") return 1;
      if (r == "SafeOP") return 2;
      if (r == "OP") return 4;
      if (r == "PreOP_SafeOP") return 3;
      if (r == "PreOP_OP") return 5;
      if (r == "SafeOP_OP") return 6;
      fail(acc, std::string(attr) + " \"" + std::string(r) + "\" is not an ETG.2000 state list");
    };
    if (a == "ro")
      bits = states("ReadRestrictions");
    else if (a == "rw")
      bits = states("ReadRestrictions") | (states("WriteRestrictions") << 3);
    else if (a == "wo")
      bits = static_cast<uint16_t>(states("WriteRestrictions") << 3);
    else
      fail(acc, "access \"" + std::string(a) + "\" is not ro, rw or wo");
    if (auto m = flags.child("PdoMapping")) {
      std::string_view p = m.text().get();
      if (p.find('R') != std::string_view::npos || p.find('r') != std::string_view::npos)
        bits |= coe::access::kRxPdoMappable;
      if (p.find('T') != std::string_view::npos || p.find('t') != std::string_view::npos)
        bits |= coe::access::kTxPdoMappable;
    }
    if (flags.child("Backup")) bits |= coe::access::kBackup;
    if (flags.child("Setting")) bits |= coe::access::kSettings;
    return bits;
  }

  // Info/MinData, MaxData (ETG.2000 ObjectInfoType, little-endian like DefaultData): the range
  // a write is checked against and SDO Information reports; signed types sign-extended.
  void read_limits(pugi::xml_node info, coe::Entry& e) const {
    if (!info) return;
    auto limit = [&](const char* name) -> std::optional<int64_t> {
      auto n = info.child(name);
      if (!n) return std::nullopt;
      const std::string hex = n.text().get();
      if (hex.size() % 2 != 0 || hex.size() > 16 || hex.size() / 2 > e.byte_length())
        fail(n, std::string("<") + name + "> is not at most " + std::to_string(e.byte_length()) +
                    " hex bytes");
      uint64_t v = 0;
      for (size_t i = 0; i < hex.size(); i += 2) {
        unsigned b = 0;
        auto [p, ec] = std::from_chars(hex.data() + i, hex.data() + i + 2, b, 16);
        if (ec != std::errc{} || p != hex.data() + i + 2)
          fail(n, std::string("<") + name + "> is not hex bytes");
        v |= static_cast<uint64_t>(b) << (4 * i);
      }
      const size_t bits = hex.size() * 4;
      const bool is_signed =
          e.type() == coe::DataType::Integer8 || e.type() == coe::DataType::Integer16 ||
          e.type() == coe::DataType::Integer32 || e.type() == coe::DataType::Integer64;
      if (is_signed && bits > 0 && bits < 64 && (v >> (bits - 1)) & 1) v |= ~uint64_t{0} << bits;
      return static_cast<int64_t>(v);
    };
    if (auto v = limit("MinData")) e.min = v;
    if (auto v = limit("MaxData")) e.max = v;
  }

  std::vector<uint8_t> read_default(pugi::xml_node info, const coe::Entry& e) const {
    if (!info) return {};
    if (auto dd = info.child("DefaultData")) {
      std::string hex = dd.text().get();
      std::vector<uint8_t> b;
      if (hex.size() % 2) fail(dd, "<DefaultData> has an odd number of hex digits");
      for (size_t i = 0; i < hex.size(); i += 2) {
        unsigned v = 0;
        auto [p, ec] = std::from_chars(hex.data() + i, hex.data() + i + 2, v, 16);
        if (ec != std::errc{} || p != hex.data() + i + 2)
          fail(dd, "<DefaultData> is not hex bytes");
        b.push_back(static_cast<uint8_t>(v));
      }
      if (b.size() > e.byte_length())
        fail(dd, "<DefaultData> has " + std::to_string(b.size()) + " bytes, the entry " +
                     std::to_string(e.byte_length()));
      if (!coe::is_string(e.type())) b.resize(e.byte_length(), 0);
      return b;
    }
    // ETG.2000 Info/DefaultString: a string's default as text.
    if (auto ds = info.child("DefaultString"); ds && coe::is_string(e.type())) {
      const std::string text = ds.text().get();
      if (text.size() > e.byte_length())
        fail(ds, "<DefaultString> is longer than the entry's " + std::to_string(e.byte_length()) +
                     " bytes");
      return {text.begin(), text.end()};
    }
    if (auto dv = info.child("DefaultValue")) {
      std::string text = dv.text().get();
      if (coe::is_string(e.type())) {
        if (text.size() > e.byte_length())
          fail(dv, "<DefaultValue> is longer than the entry's " + std::to_string(e.byte_length()) +
                       " bytes");
        return {text.begin(), text.end()};
      }
      const auto v = static_cast<uint64_t>(number(dv, text.c_str(), "DefaultValue"));
      std::vector<uint8_t> b(e.byte_length());
      for (size_t i = 0; i < b.size() && i < 8; ++i) b[i] = static_cast<uint8_t>(v >> (8 * i));
      return b;
    }
    return {};
  }

  void read_dictionary(pugi::xml_node dict, coe::ObjectDictionary& od) {
    for (auto t : dict.child("DataTypes").children("DataType")) {
      std::string name = t.child("Name").text().get();
      if (name.empty()) fail(t, "<DataType> without <Name>");
      types_[name] = t;
    }
    for (auto o : dict.child("Objects").children("Object")) od.add(read_object(o));
  }

  // Entries (subindex order) of a named record/array type, bit offsets from BitOffs.
  void expand_type(pugi::xml_node at, const TypeInfo& ti, std::vector<coe::Entry>& out,
                   bool& is_array) const {
    for (auto si : ti.node.children("SubItem")) {
      std::string sname = si.child("Name").text().get();
      auto sti = resolve_type(si, si.child("Type").text().get());
      const auto bits = static_cast<uint16_t>(child_number(si, "BitSize"));
      const auto offs = static_cast<uint16_t>(child_number(si, "BitOffs"));
      const uint16_t acc = read_access(si.child("Flags"), coe::access::kRo);
      if (sti.node && sti.node.child("ArrayInfo")) {
        // "Elements": an array type; subindices LBound.. follow.
        is_array = true;
        auto ai = sti.node.child("ArrayInfo");
        const auto lb = child_number(ai, "LBound", 1);
        const auto n = child_number(ai, "Elements");
        auto base = resolve_type(sti.node, sti.node.child("BaseType").text().get());
        if (base.node) fail(sti.node, "array of a structured type is not supported");
        if (n * base.bits != bits)
          fail(si, "<BitSize> " + std::to_string(bits) + " is not " + std::to_string(n) + " x " +
                       std::to_string(base.bits));
        for (int64_t i = 0; i < n; ++i) {
          coe::Entry e =
              coe::make_entry(static_cast<uint8_t>(lb + i), sname + " " + std::to_string(lb + i),
                              static_cast<coe::DataType>(base.coe_type), base.bits, acc);
          e.bit_offset = static_cast<uint16_t>(offs + i * base.bits);
          out.push_back(std::move(e));
        }
        continue;
      }
      if (sti.node)
        fail(si, "nested structured type \"" + std::string(si.child("Type").text().get()) +
                     "\" is not supported");
      if (sti.bits != bits && !coe::is_string(static_cast<coe::DataType>(sti.coe_type)))
        fail(si, "<BitSize> " + std::to_string(bits) + " contradicts type " +
                     si.child("Type").text().get() + " (" + std::to_string(sti.bits) + " bits)");
      const auto sub = child_number(si, "SubIdx", out.empty() ? 0 : out.back().subindex + 1);
      if (sub < 0 || sub > 255) fail(si, "<SubIdx> out of range");
      if (!out.empty() && sub <= out.back().subindex) fail(si, "<SubIdx> not ascending");
      coe::Entry e = coe::make_entry(static_cast<uint8_t>(sub), sname,
                                     static_cast<coe::DataType>(sti.coe_type), bits, acc);
      e.bit_offset = offs;
      out.push_back(std::move(e));
    }
    (void)at;
  }

  // A record DataType may leave a gap between two SubItems (BitOffs jumps) or after the last
  // (BitSize, and SubIndex 0 counting one more): where exactly one subindex is missing, it is
  // that gap, kept as a padding entry (counted in the layout, never addressed by SDO; SDO
  // Information describes it with its bit length, as for the native rack's pad entries).
  static void fill_record_gaps(std::vector<coe::Entry>& entries, uint16_t bits) {
    auto pad = [](size_t sub, size_t offset, size_t length) {
      coe::Entry e = coe::make_entry(static_cast<uint8_t>(sub), "Padding", coe::DataType{},
                                     static_cast<uint16_t>(length), 0);
      e.padding = true;
      e.bit_offset = static_cast<uint16_t>(offset);
      return e;
    };
    std::vector<coe::Entry> out;
    for (size_t i = 0; i < entries.size(); ++i) {
      if (i > 0) {
        const auto& prev = out.back();
        const size_t end = prev.bit_offset + prev.bit_length;
        if (entries[i].subindex == prev.subindex + 2 && entries[i].bit_offset > end && i > 1)
          out.push_back(pad(prev.subindex + 1u, end, entries[i].bit_offset - end));
      }
      out.push_back(std::move(entries[i]));
    }
    const size_t count = out.front().default_value.empty() ? 0 : out.front().default_value[0];
    const auto& last = out.back();
    const size_t end = last.bit_offset + last.bit_length;
    if (out.size() > 1 && count == last.subindex + 1u && bits > end)
      out.push_back(pad(count, end, bits - end));
    entries = std::move(out);
  }

  coe::Object read_object(pugi::xml_node o) {
    auto index = child_number(o, "Index");
    if (o.child("Index").attribute("DependOnSlot").as_bool()) index += index_offset_;
    if (o.child("Index").attribute("DependOnSlotGroup").as_bool()) index += group_index_offset_;
    if (index <= 0 || index > 0xFFFF) fail(o, "object index out of range");
    std::string name = o.child("Name").text().get();
    auto type_node = o.child("Type");
    if (!type_node) fail(o, "<Object> without <Type>");
    auto ti = resolve_type(type_node, type_node.text().get());
    const auto bits = static_cast<uint16_t>(child_number(o, "BitSize"));
    auto info = o.child("Info");
    if (!ti.node) {
      if (bits != ti.bits)
        fail(o.child("BitSize"), "<BitSize> " + std::to_string(bits) + " contradicts type " +
                                     type_node.text().get() + " (" + std::to_string(ti.bits) +
                                     " bits)");
      coe::Object obj(static_cast<uint16_t>(index), coe::ObjectCode::Var, name, ti.coe_type);
      coe::Entry e = coe::make_entry(0, name, static_cast<coe::DataType>(ti.coe_type), bits,
                                     read_access(o.child("Flags"), coe::access::kRo));
      e.default_value = read_default(info, e);
      read_limits(info, e);
      obj.add(std::move(e));
      obj.finalize();
      return obj;
    }
    std::vector<coe::Entry> entries;
    bool is_array = false;
    expand_type(type_node, ti, entries, is_array);
    if (entries.empty() || entries.front().subindex != 0)
      fail(ti.node, "structured type without SubIdx 0");
    // Object-level access flags apply to entries whose SubItem has none (ETG.2000 Object/Flags).
    std::vector<pugi::xml_node> sub_infos;
    for (auto si : info.children("SubItem")) sub_infos.push_back(si);
    if (sub_infos.size() > entries.size())
      fail(sub_infos[entries.size()], "<SubItem> beyond the " + std::to_string(entries.size()) +
                                          " entries of type " + type_node.text().get());
    for (size_t i = 0; i < entries.size(); ++i) {
      if (i < sub_infos.size()) {
        auto sinfo = sub_infos[i].child("Info");
        entries[i].default_value = read_default(sinfo, entries[i]);
        read_limits(sinfo, entries[i]);
        if (auto f = sub_infos[i].child("Flags"))
          entries[i].access = read_access(f, entries[i].access);
      }
      if (i == 0 && entries[0].default_value.empty())
        entries[0].default_value = {static_cast<uint8_t>(entries.back().subindex)};
    }
    if (!is_array) fill_record_gaps(entries, bits);
    coe::Object obj(
        static_cast<uint16_t>(index), is_array ? coe::ObjectCode::Array : coe::ObjectCode::Record,
        name,
        is_array ? entries.back().data_type : standard_record_type(static_cast<uint16_t>(index)));
    try {
      for (auto& e : entries) obj.add(std::move(e));
    } catch (const std::logic_error& err) {
      fail(ti.node, std::string("type layout: ") + err.what());
    }
    obj.finalize();
    if (obj.bit_size() < bits) {
      // the declared BitSize may include a trailing gap; nothing to do
    }
    return obj;
  }

  // ---- PDOs --------------------------------------------------------------------------

  PdoDescription read_pdo(pugi::xml_node p, const std::vector<pugi::xml_node>& sm_nodes,
                          const DeviceDescription& d, EsiDevice& out) {
    PdoDescription pdo;
    auto pdo_index = child_number(p, "Index");
    if (p.child("Index").attribute("DependOnSlot").as_bool()) pdo_index += pdo_offset_;
    if (p.child("Index").attribute("DependOnSlotGroup").as_bool()) pdo_index += group_pdo_offset_;
    if (pdo_index < 0 || pdo_index > 0xFFFF) fail(p, "PDO index out of range");
    pdo.index = static_cast<uint16_t>(pdo_index);
    pdo.name = p.child("Name").text().get();
    pdo.fixed = p.attribute("Fixed").as_bool();
    // ETG.2000 PdoType/@OverwrittenByModule: a device-level PDO a chosen module list replaces.
    pdo.from_module = p.attribute("OverwrittenByModule").as_bool();
    pdo.mandatory = p.attribute("Mandatory").as_bool();
    pdo.assigned = static_cast<bool>(p.attribute("Sm"));
    const bool rx = std::string_view(p.name()) == "RxPdo";
    if (pdo.assigned) {
      const auto esi_sm = attr_number(p, "Sm", 0);
      if (esi_sm < 0 || static_cast<size_t>(esi_sm) >= sm_map_.size())
        fail(p, "Sm=\"" + std::to_string(esi_sm) + "\" names no <Sm> of the device");
      const auto sm = static_cast<int64_t>(sm_map_[static_cast<size_t>(esi_sm)]);
      const auto want = rx ? SmType::ProcessOut : SmType::ProcessIn;
      if (d.sms[static_cast<size_t>(sm)].type != want)
        fail(p, std::string("<") + p.name() + "> assigned to Sm " + std::to_string(sm) +
                    " which is not an " + (rx ? "Outputs" : "Inputs") + " SM");
      pdo.sm = static_cast<uint8_t>(sm);
    } else {
      for (size_t i = 0; i < d.sms.size(); ++i)
        if (d.sms[i].type == (rx ? SmType::ProcessOut : SmType::ProcessIn))
          pdo.sm = static_cast<uint8_t>(i);
    }
    (void)sm_nodes;
    for (auto e : p.children("Entry")) {
      PdoEntryDescription en;
      auto entry_index = child_number(e, "Index");
      if (entry_index != 0 && e.child("Index").attribute("DependOnSlot").as_bool())
        entry_index += index_offset_;
      if (entry_index != 0 && e.child("Index").attribute("DependOnSlotGroup").as_bool())
        entry_index += group_index_offset_;
      if (entry_index < 0 || entry_index > 0xFFFF) fail(e, "PDO entry index out of range");
      en.index = static_cast<uint16_t>(entry_index);
      en.subindex = static_cast<uint8_t>(child_number(e, "SubIndex", 0));
      en.bit_length = static_cast<uint8_t>(child_number(e, "BitLen"));
      en.name = e.child("Name").text().get();
      if (en.index != 0) {
        auto tnode = e.child("DataType");
        if (!tnode) fail(e, "PDO entry without <DataType>");
        auto ti = resolve_type(tnode, tnode.text().get());
        if (ti.node) fail(tnode, "PDO entry of a structured type");
        if (ti.bits != en.bit_length && !coe::is_string(static_cast<coe::DataType>(ti.coe_type)))
          fail(e.child("BitLen"),
               "<BitLen> " + std::to_string(en.bit_length) + " contradicts " + tnode.text().get());
        en.data_type = ti.coe_type;
        if (out.has_coe) check_mapped(e, en, rx, out.dictionary);
      }
      pdo.entries.push_back(std::move(en));
    }
    return pdo;
  }

  // A mapped entry that the Dictionary declares must agree with it (ETG.1000.6 §5.6.7.4.7).
  void check_mapped(pugi::xml_node at, const PdoEntryDescription& en, bool rx,
                    const coe::ObjectDictionary& od) const {
    const auto* obj = od.find(en.index);
    if (!obj) return;  // derived below
    const auto* e = obj->entry(en.subindex);
    if (!e)
      fail(at, "PDO entry maps subindex " + std::to_string(en.subindex) + " that object " +
                   hex4(en.index) + " does not have");
    if (e->bit_length != en.bit_length)
      fail(at, "PDO entry is " + std::to_string(en.bit_length) + " bits, " + hex4(en.index) + ":" +
                   std::to_string(en.subindex) + " is " + std::to_string(e->bit_length));
    const uint16_t need = rx ? coe::access::kRxPdoMappable : coe::access::kTxPdoMappable;
    if (!(e->access & need))
      fail(at, hex4(en.index) + ":" + std::to_string(en.subindex) + " is not " +
                   (rx ? "RxPDO" : "TxPDO") + " mappable in the Dictionary");
  }

  static std::string hex4(uint32_t v) {
    char b[12];
    std::snprintf(b, sizeof b, "0x%04X", v);
    return b;
  }

  // The emulated ESC's ESM checks process data on SM2 (outputs) and SM3 (inputs), the
  // ETG.1000.6 Table 67 default for a device with mailbox (ecat/esm.cpp). A device whose ESI
  // puts process data on SM0/SM1 (no mailbox) gets its SMs renumbered: the SII SyncManager
  // category lists unused SM0/SM1 and the master configures SM2/SM3, as the SII says.
  void remap_process_sms(DeviceDescription& d, std::vector<pugi::xml_node>& nodes) {
    sm_map_.clear();
    for (size_t i = 0; i < d.sms.size(); ++i) sm_map_.push_back(i);
    if (d.sms.empty()) return;
    for (size_t i = 0; i < d.sms.size(); ++i) {
      const auto t = d.sms[i].type;
      const bool mbx = t == SmType::MailboxOut || t == SmType::MailboxIn;
      if (d.sms[i].start < 0x1000)
        fail(nodes[i], "Sm StartAddress below 0x1000 (ESC registers, not process RAM)");
      if (mbx && i > 1) fail(nodes[i], "mailbox SM must be SM0 (MBoxOut) or SM1 (MBoxIn)");
      if (t == SmType::MailboxOut && i != 0) fail(nodes[i], "MBoxOut must be SM0");
      if (t == SmType::MailboxIn && i != 1) fail(nodes[i], "MBoxIn must be SM1");
    }
    std::vector<esi::SyncManagerDescription> out(std::max<size_t>(d.sms.size(), 4));
    std::vector<pugi::xml_node> out_nodes(out.size());
    std::vector<bool> used(out.size(), false);
    for (size_t i = 0; i < d.sms.size(); ++i) {
      const auto t = d.sms[i].type;
      size_t to = i;
      if (t == SmType::ProcessOut && !used[2])
        to = 2;
      else if (t == SmType::ProcessIn && !used[3])
        to = 3;
      else if (t == SmType::ProcessOut || t == SmType::ProcessIn)
        fail(nodes[i], "more than one process-data SM per direction is not supported");
      if (used[to]) fail(nodes[i], "SM numbering collides after placing process data on SM2/SM3");
      used[to] = true;
      out[to] = d.sms[i];
      out_nodes[to] = nodes[i];
      sm_map_[i] = to;
    }
    for (size_t i = 0; i < out.size(); ++i)
      if (!used[i]) {
        out[i] = esi::SyncManagerDescription{};
        out[i].enable = false;
      }
    // Trailing unused SMs beyond SM3 are dropped by the size above; keep at least SM0..SM3.
    d.sms = std::move(out);
    nodes = std::move(out_nodes);
  }

  // SM default sizes follow the assigned PDOs; they must fit MaxSize.
  void check_sm_sizes(DeviceDescription& d, const std::vector<pugi::xml_node>& sm_nodes,
                      pugi::xml_node dev) {
    for (size_t i = 0; i < d.sms.size(); ++i) {
      auto& sm = d.sms[i];
      if (sm.type != SmType::ProcessOut && sm.type != SmType::ProcessIn) continue;
      if (!sm_nodes[i]) continue;
      const auto& pdos = sm.type == SmType::ProcessOut ? d.rx_pdos : d.tx_pdos;
      std::vector<PdoDescription> on_sm;
      for (const auto& p : pdos)
        if (p.assigned && p.sm == i) on_sm.push_back(p);
      const uint16_t bytes = esi::pdo_bytes(on_sm);
      if (sm.max_size != 0 && bytes > sm.max_size)
        fail(sm_nodes[i], "the PDOs assigned to Sm " + std::to_string(i) + " need " +
                              std::to_string(bytes) + " bytes, more than MaxSize " +
                              std::to_string(sm.max_size));
      if (sm.max_size != 0 && bytes > sm.max_size && module_choice_)
        fail_choice(*module_choice_, "with the chosen modules the PDOs of Sm " + std::to_string(i) +
                                         " need " + std::to_string(bytes) +
                                         " bytes, more than its MaxSize " +
                                         std::to_string(sm.max_size));
      // The ESI's DefaultSize describes the default module configuration, not a chosen one.
      if (sm.default_size != 0 && sm.default_size != bytes && !selector_->modules)
        fail(sm_nodes[i], "DefaultSize " + std::to_string(sm.default_size) + " of Sm " +
                              std::to_string(i) + " contradicts its PDOs (" +
                              std::to_string(bytes) + " bytes)");
      sm.default_size = bytes;
    }
    (void)dev;
  }

  // ---- modular devices (ETG.5001, ETG.2000 Slots/Modules) ------------------------------

  [[noreturn]] void fail_choice(const ModuleChoice& c, const std::string& reason) const {
    if (c.file.empty()) fail(catalogue_, "module \"" + c.ref + "\": " + reason);
    throw FileError(c.file, c.line, reason);
  }

  // One <Slot> of the device (ETG.2000 SlotType): how many modules it takes, which, and the
  // increments (the Slot's own attributes, else those of <Slots>).
  struct SlotRule {
    std::string name;
    int64_t min = 0, max = 0;
    int64_t index_increment = 0, pdo_increment = 0;
    std::vector<uint32_t> idents;
    std::vector<std::string> classes;  // ModuleClass/Class: modules whose Type@ModuleClass is one
    int64_t group = -1;                // Slot@SlotGroup, -1 = none
    int64_t group_index_increment = 0, group_pdo_increment = 0;

    bool takes(pugi::xml_node module, uint32_t ident) const {
      if (std::find(idents.begin(), idents.end(), ident) != idents.end()) return true;
      const std::string cls = module.child("Type").attribute("ModuleClass").value();
      return !cls.empty() && std::find(classes.begin(), classes.end(), cls) != classes.end();
    }
    // "0x00000001, 0x00000002, class \"DI\"" for the error a misplaced module gets.
    std::string describe() const {
      std::string s;
      for (auto i : idents) s += (s.empty() ? "" : ", ") + hex8(i);
      for (const auto& c : classes) s += (s.empty() ? "class \"" : ", class \"") + c + "\"";
      return s.empty() ? std::string("no module") : s;
    }
  };

  std::vector<SlotRule> slot_rules(pugi::xml_node slots) const {
    std::vector<SlotRule> rules;
    const auto index_inc = attr_number(slots, "SlotIndexIncrement", 0);
    const auto pdo_inc = attr_number(slots, "SlotPdoIncrement", 0);
    const auto group_index_inc = attr_number(slots, "SlotGroupIndexIncrement", 0);
    const auto group_pdo_inc = attr_number(slots, "SlotGroupPdoIncrement", 0);
    const auto vendor_id = child_number(vendor_, "Id");
    for (auto s : slots.children("Slot")) {
      SlotRule r;
      r.name = s.child("Name").text().get();
      if (r.name.empty()) r.name = "Slot " + std::to_string(rules.size() + 1);
      r.min = attr_number(s, "MinInstances", 0);
      r.max = attr_number(s, "MaxInstances", 0);
      r.index_increment = attr_number(s, "SlotIndexIncrement", index_inc);
      r.pdo_increment = attr_number(s, "SlotPdoIncrement", pdo_inc);
      r.group = attr_number(s, "SlotGroup", -1);
      if (r.group < -1 || r.group > 255) fail(s, "SlotGroup out of range");
      r.group_index_increment = attr_number(s, "SlotGroupIndexIncrement", group_index_inc);
      r.group_pdo_increment = attr_number(s, "SlotGroupPdoIncrement", group_pdo_inc);
      for (auto m : s.children("ModuleIdent"))
        r.idents.push_back(static_cast<uint32_t>(number(m, m.text().get(), "ModuleIdent")));
      // ETG.2000 SlotType ModuleClass: any module whose Type@ModuleClass is the Class; with a
      // VendorId, only that vendor's modules (this file's <Modules> are its <Vendor>'s).
      for (auto c : s.children("ModuleClass")) {
        const std::string cls = c.child("Class").text().get();
        if (cls.empty()) fail(c, "<ModuleClass> without <Class>");
        if (auto v = c.child("VendorId"); v && number(v, v.text().get(), "VendorId") != vendor_id)
          continue;
        r.classes.push_back(cls);
      }
      rules.push_back(std::move(r));
    }
    return rules;
  }

  // The catalogue's <Module> a choice names: by ModuleIdent, by its Type text, or by one of
  // the comma-separated names of its Type.
  pugi::xml_node find_module(const ModuleChoice& c) const {
    const auto ident =
        parse_hex_dec(c.ref.size() > 2 && c.ref[0] == '0' && (c.ref[1] == 'x' || c.ref[1] == 'X')
                          ? "#x" + c.ref.substr(2)
                          : c.ref);
    std::string known;
    for (auto m : catalogue_.children("Module")) {
      auto type = m.child("Type");
      const std::string text = type.text().get();
      if (ident && attr_number(type, "ModuleIdent", -1) == *ident) return m;
      if (text == c.ref) return m;
      for (size_t at = 0; at <= text.size();) {
        size_t end = text.find(',', at);
        if (end == std::string::npos) end = text.size();
        std::string part = text.substr(at, end - at);
        while (!part.empty() && part.front() == ' ') part.erase(part.begin());
        while (!part.empty() && part.back() == ' ') part.pop_back();
        if (!part.empty() && part == c.ref) return m;
        at = end + 1;
      }
      if (known.size() < 200) known += (known.empty() ? "" : ", ") + text;
    }
    fail_choice(c, "unknown module \"" + c.ref + "\": the ESI's <Modules> have " +
                       (known.empty() ? std::string("none") : known));
  }

  // Rewrites an ARRAY of unsigned values (0x1C12/0x1C13, 0xF030/0xF050) to hold `values`,
  // keeping its name, type and access; grows it when its subindices do not suffice.
  static void set_list(coe::ObjectDictionary& od, uint16_t index, const std::string& name,
                       coe::DataType type, uint16_t bits, uint16_t access,
                       const std::vector<uint32_t>& values, size_t capacity,
                       const char* entry_name) {
    const coe::Object* old = od.find(index);
    std::vector<coe::Entry> entries;
    if (old) {
      for (const auto& e : old->entries()) entries.push_back(e);
      capacity = std::max<size_t>(capacity, entries.size() - 1);
    }
    coe::Object o(index, old ? old->code() : coe::ObjectCode::Array, old ? old->name() : name,
                  old ? old->data_type() : static_cast<uint16_t>(type));
    coe::Entry sub0 =
        old && !entries.empty()
            ? entries[0]
            : coe::make_entry(0, "Number of entries", coe::DataType::Unsigned8, 8, access);
    sub0.default_value = {static_cast<uint8_t>(values.size())};
    o.add(std::move(sub0));
    for (size_t i = 1; i <= capacity; ++i) {
      coe::Entry e =
          i < entries.size()
              ? entries[i]
              : (entries.size() > 1 ? entries[1] : coe::make_entry(0, "", type, bits, access));
      e.subindex = static_cast<uint8_t>(i);
      if (i >= entries.size()) {
        char buf[32];
        std::snprintf(buf, sizeof buf, entry_name, static_cast<unsigned>(i));
        e.name = buf;
        e.bit_offset = 0;
      }
      const uint32_t v = i <= values.size() ? values[i - 1] : 0;
      e.default_value.assign(e.byte_length(), 0);
      for (size_t k = 0; k < e.default_value.size() && k < 4; ++k)
        e.default_value[k] = static_cast<uint8_t>(v >> (8 * k));
      o.add(std::move(e));
    }
    o.finalize();
    od.remove(index);
    od.add(std::move(o));
  }

  // A chosen module list (docs/LINE.md "Modular devices"): the device-level PDOs marked
  // OverwrittenByModule and the device-level objects at any slot's module indices give way;
  // each chosen module, at slot position k (0-based), adds its Dictionary objects and its
  // RxPdo/TxPdo, a DependOnSlot index moved by k x SlotIndexIncrement (objects, PDO entries)
  // or k x SlotPdoIncrement (PDOs) (ETG.2000 SlotType, ETG.5001.1 §4 index distance). The
  // assignment 0x1C12/0x1C13 and the module ident lists 0xF030 (configured) / 0xF050
  // (detected) then name the chosen modules (ETG.5001.1 §5.3).
  void apply_module_list(pugi::xml_node dev, EsiDevice& out,
                         const std::vector<ModuleChoice>& choices) {
    auto& d = out.description;
    auto& od = out.dictionary;
    auto slots = dev.child("Slots");
    if (!slots) {
      if (!choices.empty()) fail_choice(choices.front(), "the device has no <Slots> (ETG.5001)");
      fail(dev, "a module list for a device without <Slots>");
    }
    const auto rules = slot_rules(slots);
    int64_t max_slots = attr_number(slots, "MaxSlotCount", 0);
    if (max_slots == 0)
      for (const auto& r : rules) max_slots += r.max;
    max_slots = std::min<int64_t>(max_slots, 255);

    // Place every choice: slots are filled in order, each up to MaxInstances; a module a slot
    // does not take moves on to the next slot once this one has its MinInstances.
    struct Placed {
      pugi::xml_node module;
      const ModuleChoice* choice;
      int64_t index_offset, pdo_offset;              // DependOnSlot
      int64_t group_index_offset, group_pdo_offset;  // DependOnSlotGroup
    };
    std::vector<Placed> placed;
    std::map<int64_t, int64_t> in_group;  // modules placed so far per SlotGroup
    size_t rule = 0;
    int64_t in_rule = 0;
    for (size_t k = 0; k < choices.size(); ++k) {
      const auto& c = choices[k];
      const auto module = find_module(c);
      const auto ident = static_cast<uint32_t>(attr_number(module.child("Type"), "ModuleIdent", 0));
      if (static_cast<int64_t>(k) >= max_slots)
        fail_choice(c, "module " + std::to_string(k + 1) + " is more than the device's " +
                           std::to_string(max_slots) + " slots (MaxSlotCount)");
      const std::string what = "module " + hex8(ident) + " (" + module.child("Type").text().get() +
                               ") is not allowed in slot position " + std::to_string(k + 1);
      const size_t first_rule = rule;
      const int64_t first_in_rule = in_rule;
      for (;;) {
        if (rule >= rules.size()) {
          // Every slot it could still have gone to, from where it started.
          std::string slots_left;
          for (size_t i = first_rule; i < rules.size(); ++i) {
            slots_left += std::string(slots_left.empty() ? ": " : "; ") + "slot \"" +
                          rules[i].name + "\" takes " + rules[i].describe();
            if (i == first_rule && first_in_rule >= rules[i].max)
              slots_left += " (full: MaxInstances " + std::to_string(rules[i].max) + ")";
          }
          fail_choice(c, what + (slots_left.empty() ? ": <Slots> has no <Slot>" : slots_left));
        }
        const auto& r = rules[rule];
        if (r.takes(module, ident) && in_rule < r.max) break;
        if (in_rule < r.min)
          fail_choice(c, what + ": slot \"" + r.name + "\" takes " + r.describe() + " and needs " +
                             std::to_string(r.min) + " module(s)");
        ++rule;
        in_rule = 0;
      }
      const auto& r = rules[rule];
      ++in_rule;
      // A slot of a SlotGroup counts its position within the group; the group's number moves
      // DependOnSlotGroup indices (ETG.2000 SlotType SlotGroup/SlotGroupIndexIncrement).
      const auto pos = r.group >= 0 ? in_group[r.group]++ : static_cast<int64_t>(k);
      const int64_t g = std::max<int64_t>(r.group, 0);
      placed.push_back({module, &c, pos * r.index_increment, pos * r.pdo_increment,
                        g * r.group_index_increment, g * r.group_pdo_increment});
      out.module_idents.push_back(ident);
    }
    for (size_t r = rule; r < rules.size(); ++r) {
      const int64_t have = r == rule ? in_rule : 0;
      if (have < rules[r].min) {
        const std::string reason = "slot \"" + rules[r].name + "\" needs at least " +
                                   std::to_string(rules[r].min) + " module(s), the list gives " +
                                   std::to_string(have);
        if (!choices.empty()) fail_choice(choices.back(), reason);
        fail(slots, reason);
      }
    }

    // The device-level description of the default configuration gives way: PDOs marked
    // OverwrittenByModule (their mapping objects kept aside: a module PDO with the same index
    // and entries reuses the device's description of it) and objects at any module's slot
    // indices.
    std::map<uint16_t, coe::Object> mapping_aside;
    for (auto* pdos : {&d.rx_pdos, &d.tx_pdos}) {
      for (const auto& p : *pdos) {
        if (!p.from_module) continue;
        if (const auto* o = od.find(p.index)) {
          mapping_aside.emplace(p.index, *o);
          od.remove(p.index);
        }
      }
      pdos->erase(std::remove_if(pdos->begin(), pdos->end(),
                                 [](const PdoDescription& p) { return p.from_module; }),
                  pdos->end());
    }
    for (auto m : catalogue_.children("Module"))
      for (auto o : m.child("Profile").child("Dictionary").child("Objects").children("Object")) {
        auto idx = o.child("Index");
        const bool by_slot = idx.attribute("DependOnSlot").as_bool();
        const bool by_group = idx.attribute("DependOnSlotGroup").as_bool();
        if (!by_slot && !by_group) continue;
        const auto base = number(idx, idx.text().get(), "Index");
        for (const auto& r : rules) {
          const int64_t g = by_group ? std::max<int64_t>(r.group, 0) * r.group_index_increment : 0;
          const int64_t inc = by_slot ? r.index_increment : 0;
          for (int64_t k = 0; k < max_slots && (inc != 0 || k == 0); ++k)
            if (base + g + k * inc <= 0xFFFF) od.remove(static_cast<uint16_t>(base + g + k * inc));
        }
      }

    std::set<uint16_t> from_modules;
    const auto saved_types = types_;
    for (const auto& p : placed) {
      index_offset_ = p.index_offset;
      pdo_offset_ = p.pdo_offset;
      group_index_offset_ = p.group_index_offset;
      group_pdo_offset_ = p.group_pdo_offset;
      module_choice_ = p.choice;
      types_ = saved_types;  // a module's DataTypes are its own (names repeat across modules)
      auto dict = p.module.child("Profile").child("Dictionary");
      for (auto t : dict.child("DataTypes").children("DataType")) {
        const std::string name = t.child("Name").text().get();
        if (name.empty()) fail(t, "<DataType> without <Name>");
        types_[name] = t;
      }
      if (out.has_coe) {
        for (auto o : dict.child("Objects").children("Object")) {
          coe::Object obj = read_object(o);
          const uint16_t index = obj.index();
          if (from_modules.count(index)) {
            if (o.child("Index").attribute("DependOnSlot").as_bool() ||
                o.child("Index").attribute("DependOnSlotGroup").as_bool())
              fail_choice(*p.choice, "module object " + hex4(index) +
                                         " collides with an earlier module's (SlotIndexIncrement "
                                         "too small for the module)");
            continue;  // a module-independent object several modules declare: once
          }
          od.remove(index);  // the module defines what the device level described
          od.add(std::move(obj));
          from_modules.insert(index);
        }
      }
      for (const char* kind : {"RxPdo", "TxPdo"}) {
        const bool rx = kind[0] == 'R';
        auto& pdos = rx ? d.rx_pdos : d.tx_pdos;
        for (auto x : p.module.children(kind)) {
          PdoDescription pdo = read_pdo(x, {}, d, out);
          pdo.from_module = true;
          for (const auto& q : pdos)
            if (q.index == pdo.index)
              fail_choice(*p.choice, std::string(kind) + " " + hex4(pdo.index) +
                                         " of this module collides with another PDO "
                                         "(SlotPdoIncrement too small for the module)");
          if (auto it = mapping_aside.find(pdo.index);
              it != mapping_aside.end() && !od.find(pdo.index)) {
            const coe::Object& o = it->second;
            bool same = o.sub0() == pdo.entries.size();
            for (size_t i = 0; same && i < pdo.entries.size(); ++i) {
              const auto& e = pdo.entries[i];
              same = o.get_u(static_cast<uint8_t>(i + 1)) ==
                     ((uint64_t{e.index} << 16) | (uint64_t{e.subindex} << 8) | e.bit_length);
            }
            if (same) od.add(it->second);
          }
          pdos.push_back(std::move(pdo));
        }
      }
    }
    types_ = saved_types;
    index_offset_ = pdo_offset_ = group_index_offset_ = group_pdo_offset_ = 0;

    if (!out.has_coe) return;
    std::vector<pugi::xml_node> modules;
    modules.reserve(placed.size());
    for (const auto& p : placed) modules.push_back(p.module);
    follow_slot_lists(od, out.module_idents, modules);
    namespace acc = coe::access;
    for (uint16_t assign : {uint16_t{0x1C12}, uint16_t{0x1C13}}) {
      if (!od.find(assign)) continue;  // derived from the PDOs in complete_dictionary
      std::vector<uint32_t> v;
      for (const auto& q : assign == 0x1C12 ? d.rx_pdos : d.tx_pdos)
        if (q.assigned) v.push_back(q.index);
      set_list(od, assign, "", coe::DataType::Unsigned16, 16, acc::kRo, v, v.size(),
               "SubIndex %03u");
    }
    set_list(od, 0xF030, "Configured Module Ident List", coe::DataType::Unsigned32, 32,
             acc::kRoWrPreOp, out.module_idents, static_cast<size_t>(max_slots), "Module %u");
    set_list(od, 0xF050, "Detected Module Ident List", coe::DataType::Unsigned32, 32, acc::kRo,
             out.module_idents, out.module_idents.size(), "Module %u");
  }

  // Device-level lists with one entry per slot follow the chosen modules (ETG.5001.1 §5.3):
  // - a module ident list: an ARRAY of 32-bit entries that holds, in the ESI, exactly the
  //   default module configuration (the device level's 0xF050 detected list, else its 0xF030),
  //   e.g. the rack's 0x3000 Module Ident Map, or a 0xF010 that lists idents as the Fusion.IO
  //   guide's does: it gets the chosen idents;
  // - otherwise 0xF010 Module Profile List: entry n = the profile number of the module in slot n
  //   (its <Profile><ProfileNo>; 0 for a module without one).
  // Each keeps its name, type and access; subindex 0 = the number of modules.
  static void follow_slot_lists(coe::ObjectDictionary& od, const std::vector<uint32_t>& idents,
                                const std::vector<pugi::xml_node>& modules) {
    std::vector<uint64_t> defaults;
    for (uint16_t index : {uint16_t{0xF050}, uint16_t{0xF030}}) {
      const coe::Object* o = od.find(index);
      if (!o || o->sub0() == 0 || !defaults.empty()) continue;
      for (uint8_t i = 1; i <= o->sub0() && o->entry(i); ++i) defaults.push_back(o->get_u(i));
    }
    std::vector<uint16_t> ident_lists;
    od.for_each([&](const coe::Object& o) {
      const uint16_t i = o.index();
      if (i == 0xF030 || i == 0xF050 || i == 0x1C12 || i == 0x1C13 || defaults.empty()) return;
      if (o.code() != coe::ObjectCode::Array || o.sub0() != defaults.size()) return;
      for (uint8_t k = 1; k <= o.sub0(); ++k)
        if (!o.entry(k) || o.entry(k)->bit_length != 32 || o.get_u(k) != defaults[k - 1u]) return;
      ident_lists.push_back(i);
    });
    for (uint16_t i : ident_lists)
      set_list(od, i, "", coe::DataType::Unsigned32, 32, coe::access::kRo, idents, idents.size(),
               "Module %u");
    if (od.find(0xF010) &&
        std::find(ident_lists.begin(), ident_lists.end(), 0xF010) == ident_lists.end()) {
      std::vector<uint32_t> profiles;
      for (auto m : modules) {
        const auto no = parse_hex_dec(m.child("Profile").child("ProfileNo").text().get());
        profiles.push_back(static_cast<uint32_t>(no.value_or(0)));
      }
      set_list(od, 0xF010, "", coe::DataType::Unsigned32, 32, coe::access::kRo, profiles,
               profiles.size(), "Module %u");
    }
  }

  static std::string hex8(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08X", v);
    return b;
  }

  // Adds what a CoE master reads that the Dictionary may leave out: 0x1000, 0x1008, 0x1018,
  // 0x1C00, mapping objects, 0x1C12/0x1C13, and the mapped application objects.
  void complete_dictionary(EsiDevice& out, pugi::xml_node dev) {
    namespace acc = coe::access;
    using coe::DataType;
    auto& od = out.dictionary;
    const auto& d = out.description;
    auto le = [](uint64_t v, size_t n) {
      std::vector<uint8_t> b(n);
      for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(v >> (8 * i));
      return b;
    };
    auto var = [&](uint16_t index, const std::string& name, DataType t, uint16_t bits,
                   uint16_t access, std::vector<uint8_t> v) {
      coe::Object o(index, coe::ObjectCode::Var, name, static_cast<uint16_t>(t));
      o.add(coe::make_entry(0, name, t, bits, access, std::move(v)));
      o.finalize();
      od.add(std::move(o));
    };
    auto list = [&](uint16_t index, const std::string& name, coe::ObjectCode code, DataType t,
                    uint16_t bits, const std::vector<uint64_t>& values, uint8_t capacity,
                    uint16_t access) {
      coe::Object o(index, code, name, static_cast<uint16_t>(t));
      o.add(coe::make_entry(0, "Number of entries", DataType::Unsigned8, 8, access,
                            {static_cast<uint8_t>(values.size())}));
      for (size_t i = 0; i < capacity; ++i)
        o.add(coe::make_entry(static_cast<uint8_t>(i + 1), "SubIndex " + std::to_string(i + 1), t,
                              bits, access, le(i < values.size() ? values[i] : 0, bits / 8)));
      o.finalize();
      od.add(std::move(o));
    };
    if (!od.find(0x1000)) var(0x1000, "Device type", DataType::Unsigned32, 32, acc::kRo, le(0, 4));
    if (!od.find(0x1008))
      var(0x1008, "Device name", DataType::VisibleString,
          static_cast<uint16_t>(8 * std::max<size_t>(1, d.device_name.size())), acc::kRo,
          {d.device_name.begin(), d.device_name.end()});
    if (!od.find(0x1018)) {
      coe::Object o(0x1018, coe::ObjectCode::Record, "Identity", coe::record_type::kIdentity);
      o.add(coe::make_entry(0, "Number of entries", DataType::Unsigned8, 8, acc::kRo, {4}));
      const char* names[] = {"Vendor ID", "Product code", "Revision", "Serial number"};
      const uint32_t vals[] = {d.vendor_id, d.product_code, d.revision, d.serial};
      for (uint8_t i = 0; i < 4; ++i)
        o.add(coe::make_entry(static_cast<uint8_t>(i + 1), names[i], DataType::Unsigned32, 32,
                              acc::kRo, le(vals[i], 4)));
      o.finalize();
      od.add(std::move(o));
    } else {
      const auto* id = od.find(0x1018);
      auto check = [&](uint8_t sub, uint32_t want, const char* what) {
        if (id->entry(sub) && id->get_u(sub) != want && id->entry(sub)->default_value.size())
          fail(dev.child("Type"), std::string("0x1018:0") + std::to_string(sub) + " default " +
                                      what + " contradicts the <Type>/<Vendor> identity");
      };
      check(1, d.vendor_id, "vendor ID");
      check(2, d.product_code, "product code");
    }
    if (!od.find(0x1C00)) {
      std::vector<uint64_t> types;
      for (const auto& sm : d.sms) types.push_back(static_cast<uint8_t>(sm.type));
      list(0x1C00, "Sync manager type", coe::ObjectCode::Array, DataType::Unsigned8, 8, types,
           static_cast<uint8_t>(types.size()), acc::kRo);
    }
    // Mapped application objects the Dictionary does not declare.
    for (const auto* pdos : {&d.rx_pdos, &d.tx_pdos}) {
      const bool rx = pdos == &d.rx_pdos;
      for (const auto& p : *pdos)
        for (const auto& e : p.entries) {
          if (e.index == 0) continue;
          auto* obj = od.find(e.index);
          const uint16_t a =
              rx ? (acc::kRw | acc::kRxPdoMappable) : (acc::kRo | acc::kTxPdoMappable);
          if (!obj) {
            if (e.subindex == 0) {
              var(e.index, e.name, static_cast<DataType>(e.data_type), e.bit_length, a, {});
            } else {
              coe::Object o(e.index, coe::ObjectCode::Record, e.name,
                            standard_record_type(e.index));
              o.add(coe::make_entry(0, "Number of entries", DataType::Unsigned8, 8, acc::kRo,
                                    {e.subindex}));
              od.add(std::move(o));
              obj = od.find(e.index);
            }
          }
          if (obj && !obj->entry(e.subindex)) {
            // fill the record up to this subindex
            coe::Object o = *obj;
            for (uint8_t s = static_cast<uint8_t>(o.max_subindex() + 1); s < e.subindex; ++s)
              o.add(coe::make_entry(s, "SubIndex " + std::to_string(s), DataType::Unsigned8, 8,
                                    acc::kRo, {}));
            o.add(coe::make_entry(e.subindex, e.name, static_cast<DataType>(e.data_type),
                                  e.bit_length, a, {}));
            o.set_packed(true);
            o.finalize();
            o.set_u(0, e.subindex);
            od.remove(e.index);
            od.add(std::move(o));
          }
        }
    }
    // Mapping objects (ETG.1000.6 §5.6.7.4.7) and assignment (§5.6.7.4.9).
    for (const auto* pdos : {&d.rx_pdos, &d.tx_pdos}) {
      for (const auto& p : *pdos) {
        if (od.find(p.index)) continue;
        std::vector<uint64_t> map;
        for (const auto& e : p.entries)
          map.push_back((uint64_t{e.index} << 16) | (uint64_t{e.subindex} << 8) | e.bit_length);
        const uint16_t a = p.fixed || !d.coe.pdo_config ? acc::kRo : acc::kRoWrPreOp;
        list(p.index, p.name, coe::ObjectCode::Record, DataType::Unsigned32, 32, map,
             static_cast<uint8_t>(map.size()), a);
      }
    }
    for (uint16_t assign : {uint16_t{0x1C12}, uint16_t{0x1C13}}) {
      if (od.find(assign)) continue;
      const auto& pdos = assign == 0x1C12 ? d.rx_pdos : d.tx_pdos;
      std::vector<uint64_t> v;
      for (const auto& p : pdos)
        if (p.assigned) v.push_back(p.index);
      const uint16_t a = d.coe.pdo_assign ? acc::kRoWrPreOp : acc::kRo;
      list(assign, assign == 0x1C12 ? "RxPDO assign" : "TxPDO assign", coe::ObjectCode::Array,
           DataType::Unsigned16, 16, v, static_cast<uint8_t>(std::max(v.size(), pdos.size())), a);
    }
  }

  std::string_view xml_;
  std::string file_;
  pugi::xml_node vendor_, groups_;
  std::map<std::string, pugi::xml_node> types_;
  std::vector<size_t> sm_map_;  // ESI Sm number -> emulated SM number
  pugi::xml_node catalogue_;    // Descriptions/Modules
  const DeviceSelector* selector_ = nullptr;
  // While a chosen module is read: what its DependOnSlot indices move by (ETG.2000 Slots).
  int64_t index_offset_ = 0;
  int64_t pdo_offset_ = 0;
  int64_t group_index_offset_ = 0;  // DependOnSlotGroup: SlotGroup x SlotGroupIndexIncrement
  int64_t group_pdo_offset_ = 0;    // and SlotGroup x SlotGroupPdoIncrement
  const ModuleChoice* module_choice_ = nullptr;  // the last module placed (for SM size errors)
};

}  // namespace

EsiDevice parse_esi_device(std::string_view xml, const std::string& file,
                           const DeviceSelector& selector) {
  return Reader(xml, file).read(selector);
}

EsiDevice load_esi_device(const std::string& file, const DeviceSelector& selector) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw FileError(file, 0, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw FileError(file, 0, "not a regular file");
  }
  constexpr size_t kMaxBytes = 64u << 20;
  if (static_cast<uint64_t>(st.st_size) > kMaxBytes) {
    ::close(fd);
    throw FileError(file, 0, "larger than 64 MiB");
  }
  std::string text(static_cast<size_t>(st.st_size), '\0');
  const ssize_t n = base::read_fully(fd, text.data(), text.size());
  const int err = errno;
  ::close(fd);
  if (n < 0) throw FileError(file, 0, std::string("cannot read: ") + std::strerror(err));
  text.resize(static_cast<size_t>(n));
  return parse_esi_device(text, file, selector);
}

}  // namespace rackcat::device
