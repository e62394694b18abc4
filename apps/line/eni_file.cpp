// ENI reader (see eni_file.hpp; ETG.2100 EtherCATConfig).
#include "apps/line/eni_file.hpp"

#include "apps/line/init_cmd_replay.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <pugixml.hpp>
#include <set>

#include "coe/access.hpp"
#include "device/esi_error.hpp"
#include "esi/describe_dictionary.hpp"
#include "mdp/file_root.hpp"

namespace rackcat::apps {
namespace {

constexpr size_t kMaxFileBytes = 64u << 20;

std::string hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "#x%08X", v);
  return buf;
}

std::string hex16(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "#x%04X", v);
  return buf;
}

// One candidate of the ESI directory: a <Device> of an ESI file or a rack file.
struct Candidate {
  std::string file;  // name below the directory
  bool rack = false;
  uint32_t vendor = 0, product = 0, revision = 0;
};

class EniReader {
 public:
  EniReader(std::string_view xml, std::string file, std::string esi_dir)
      : xml_(xml), file_(std::move(file)), esi_dir_(std::move(esi_dir)) {}

  [[noreturn]] void fail(pugi::xml_node at, const std::string& reason) const {
    throw device::FileError(file_, line_of(at), reason);
  }

  size_t line_of(pugi::xml_node at) const {
    size_t line = 1;
    const ptrdiff_t off = at ? at.offset_debug() : -1;
    if (off > 0) {
      line += static_cast<size_t>(
          std::count(xml_.begin(), xml_.begin() + std::min<ptrdiff_t>(off, xml_.size()), '\n'));
    }
    return line;
  }

  // ENI numbers are xs:int/xs:unsignedInt in decimal, or ETG.2000 HexDecValue "#x..".
  int64_t number(pugi::xml_node at, std::string_view text, const std::string& what) const {
    auto v = device::parse_hex_dec(text);
    if (!v) fail(at, what + " \"" + std::string(text) + "\" is not a number (#x.. or decimal)");
    return *v;
  }
  int64_t child_number(pugi::xml_node n, const char* child) const {
    auto c = n.child(child);
    if (!c) fail(n, std::string("<") + n.name() + "> has no <" + child + ">");
    return number(c, c.text().get(), child);
  }

  LineFile read() {
    pugi::xml_document doc;
    auto res = doc.load_buffer(xml_.data(), xml_.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!res) {
      const size_t line =
          1 + static_cast<size_t>(std::count(
                  xml_.begin(), xml_.begin() + std::min<ptrdiff_t>(res.offset, xml_.size()), '\n'));
      throw device::FileError(file_, line,
                              std::string("not well-formed XML: ") + res.description());
    }
    auto root = doc.child("EtherCATConfig");
    if (!root) fail(doc.first_child(), "root element is not <EtherCATConfig> (ETG.2100)");
    auto config = root.child("Config");
    if (!config) fail(root, "<EtherCATConfig> has no <Config>");
    try {
      esi_root_ = mdp::FileRoot::open(esi_dir_);
    } catch (const std::exception& e) {
      fail(config, std::string("--esi-dir: ") + e.what());
    }
    scan_esi_dir(config);
    LineFile out;
    out.file = file_;
    for (auto slave : config.children("Slave")) out.devices.push_back(read_slave(slave));
    if (out.devices.empty()) fail(config, "<Config> has no <Slave>");
    return out;
  }

 private:
  // Every <Device> identity of the *.xml files and every rack identity of the *.yaml files
  // directly in the directory (regular files; read through FileRoot, so never a link out).
  void scan_esi_dir(pugi::xml_node at) {
    namespace fs = std::filesystem;
    std::vector<std::string> names;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(esi_dir_, ec)) {
      if (!e.is_regular_file(ec) || e.is_symlink(ec)) continue;
      names.push_back(e.path().filename().string());
    }
    if (ec) fail(at, "--esi-dir " + esi_dir_ + ": " + ec.message());
    std::sort(names.begin(), names.end());
    for (const auto& name : names) {
      const auto ext = fs::path(name).extension().string();
      if (ext == ".xml") {
        std::string text;
        try {
          text = esi_root_->read(name, kMaxFileBytes);
        } catch (const std::exception& e) {
          fail(at, std::string("--esi-dir: ") + e.what());
        }
        pugi::xml_document d;
        if (!d.load_buffer(text.data(), text.size())) continue;  // not XML: not an ESI
        auto info = d.child("EtherCATInfo");
        if (!info) continue;
        auto vendor = device::parse_hex_dec(info.child("Vendor").child("Id").text().get());
        for (auto dev : info.child("Descriptions").child("Devices").children("Device")) {
          auto type = dev.child("Type");
          auto pc = device::parse_hex_dec(type.attribute("ProductCode").value());
          auto rev = device::parse_hex_dec(type.attribute("RevisionNo").value());
          if (!vendor || !pc) continue;
          candidates_.push_back({name, false, static_cast<uint32_t>(*vendor),
                                 static_cast<uint32_t>(*pc),
                                 static_cast<uint32_t>(rev.value_or(0))});
        }
      } else if (ext == ".yaml" || ext == ".yml") {
        try {
          auto cfg = mdp::parse_rack_config(esi_root_->read(name, kMaxFileBytes),
                                            (fs::path(esi_dir_) / name).string());
          candidates_.push_back(
              {name, true, cfg.control.vendor_id, cfg.control.product_code, cfg.control.revision});
          racks_.emplace(name, std::move(cfg));
        } catch (const std::exception&) {
          // Not a rack file (or a bad one): never chosen; `rackcat check` names its error.
        }
      }
    }
  }

  LineDevice read_slave(pugi::xml_node slave) {
    auto info = slave.child("Info");
    if (!info) fail(slave, "<Slave> has no <Info>");
    const auto vendor = static_cast<uint32_t>(child_number(info, "VendorId"));
    const auto product = static_cast<uint32_t>(child_number(info, "ProductCode"));
    const auto revision = static_cast<uint32_t>(child_number(info, "RevisionNo"));
    const std::string name = info.child("Name").text().get();
    LineDevice ld;
    ld.line = line_of(slave);
    ld.name = name;
    const Candidate* found = nullptr;
    std::string near;
    for (const auto& c : candidates_) {
      if (c.vendor == vendor && c.product == product && c.revision == revision) {
        found = &c;
        break;
      }
      if (c.vendor == vendor && c.product == product)
        near += " (" + c.file + " has revision " + hex32(c.revision) + ")";
    }
    if (!found)
      fail(info, "no ESI device or rack file in " + esi_dir_ + " has vendor " + hex32(vendor) +
                     ", product code " + hex32(product) + ", revision " + hex32(revision) +
                     (name.empty() ? "" : " (\"" + name + "\")") + near);
    const std::string path = (std::filesystem::path(esi_dir_) / found->file).string();
    if (found->rack) {
      // A rack's process data follows its modules (rack file) and its dictionary checks what
      // the master writes: the ENI's PDOs and init commands are not compared for a rack.
      ld.rack = std::make_unique<mdp::RackConfig>(racks_.at(found->file));
      return ld;
    }
    std::string esi_text;
    try {
      esi_text = esi_root_->read(found->file, kMaxFileBytes);
    } catch (const std::exception& e) {
      fail(info, e.what());
    }
    // The ESI's own errors name the ESI file and line.
    auto selector = device::DeviceSelector::by_code(product, revision);
    selector.modules = module_list(slave);
    ld.esi =
        std::make_unique<device::EsiDevice>(device::parse_esi_device(esi_text, path, selector));
    if (ld.esi->description.vendor_id != vendor)
      fail(info, "the ESI device for product " + hex32(product) + " in " + path +
                     " has another vendor (" + hex32(ld.esi->description.vendor_id) + ")");
    if (auto alias = station_alias(info)) ld.esi->description.config.station_alias = *alias;
    if (auto serial = info.child("SerialNo"))
      ld.esi->description.serial =
          static_cast<uint32_t>(number(serial, serial.text().get(), "SerialNo"));
    const auto pd = slave.child("ProcessData");
    if (pd) apply_process_data(pd, *ld.esi);
    check_init_cmds(slave, *ld.esi);
    if (ld.esi->has_coe) replay_init_cmds(slave, *ld.esi, pd.child("RxPdo") || pd.child("TxPdo"));
    return ld;
  }

  // Info/Identification (ETG.2100): the master identifies the slave by the value of the ESC
  // register `Ado`; for 0x0012, the configured station alias, the ESC loads it from SII word 4
  // (ETG.2010 Table 2), so the emulated device's SII carries `Value` there. Another register
  // (0x0134 Explicit Device ID: an ID selector the emulated ESC has not) is refused.
  std::optional<uint16_t> station_alias(pugi::xml_node info) const {
    auto id = info.child("Identification");
    if (!id) return std::nullopt;
    const auto ado = child_number(id, "Ado");
    if (ado != 0x0012)
      fail(id.child("Ado"), "identification by ADO " + hex16(static_cast<uint16_t>(ado)) +
                                " is not emulated; only the configured station alias 0x0012");
    const auto value = child_number(id, "Value");
    if (value < 0 || value > 0xFFFF) fail(id.child("Value"), "station alias is 0..0xFFFF");
    return static_cast<uint16_t>(value);
  }

  // ETG.2100 has no element for a modular device's modules: a configurator downloads the
  // configured module ident list 0xF030 (ETG.5001.1 §5.3) as CoE init commands, by complete
  // access (subindex 0 with the count, one padding byte, then 4 bytes per module) or entry by
  // entry (subindices 1..n, then subindex 0 = n). That list, when present, chooses the ESI
  // device's modules (device::ModuleChoice naming the init command's line).
  std::optional<std::vector<device::ModuleChoice>> module_list(pugi::xml_node slave) const {
    std::map<uint8_t, std::pair<uint32_t, size_t>> entries;  // subindex -> (ident, line)
    std::optional<size_t> count;
    size_t count_line = 0;
    for (auto c : slave.child("Mailbox").child("CoE").child("InitCmds").children("InitCmd")) {
      if (child_number(c, "Index") != 0xF030) continue;
      if (auto ccs = c.child("Ccs"); ccs && number(ccs, ccs.text().get(), "Ccs") != 1) continue;
      const auto sub = child_number(c, "SubIndex");
      const bool ca = std::string_view(c.attribute("CompleteAccess").value()) == "true" ||
                      std::string_view(c.attribute("CompleteAccess").value()) == "1";
      const std::string hex = c.child("Data").text().get();
      std::vector<uint8_t> data;
      for (size_t i = 0; i + 1 < hex.size(); i += 2) {
        const auto b = parse_hex_byte(hex[i], hex[i + 1]);
        if (!b) fail(c.child("Data") ? c.child("Data") : c, "<Data> is not hexBinary");
        data.push_back(*b);
      }
      const size_t line = line_of(c);
      if (ca && sub == 0) {
        if (data.empty() || data.size() != 2 + 4 * size_t{data[0]})
          fail(c, "0xF030 complete access: " + std::to_string(data.size()) +
                      " bytes, not 2 + 4 x the count in its first byte");
        entries.clear();
        for (size_t k = 1; k <= data[0]; ++k) {
          const size_t at = 2 + 4 * (k - 1);
          entries[static_cast<uint8_t>(k)] = {
              static_cast<uint32_t>(data[at] | (data[at + 1] << 8) | (data[at + 2] << 16) |
                                    (static_cast<uint32_t>(data[at + 3]) << 24)),
              line};
        }
        count = data[0];
        count_line = line;
      } else if (!ca && sub == 0 && data.size() == 1) {
        count = data[0];
        count_line = line;
      } else if (!ca && sub >= 1 && sub <= 255 && data.size() == 4) {
        entries[static_cast<uint8_t>(sub)] = {
            static_cast<uint32_t>(data[0] | (data[1] << 8) | (data[2] << 16) |
                                  (static_cast<uint32_t>(data[3]) << 24)),
            line};
      } else {
        fail(c,
             "0xF030 init command is neither complete access from subindex 0 nor one "
             "entry (4 bytes) or the count (1 byte)");
      }
    }
    if (!count) {
      if (!entries.empty()) fail(slave, "0xF030 init commands without the count (subindex 0)");
      return std::nullopt;
    }
    std::vector<device::ModuleChoice> out;
    for (size_t k = 1; k <= *count; ++k) {
      auto it = entries.find(static_cast<uint8_t>(k));
      if (it == entries.end())
        throw device::FileError(file_, count_line,
                                "0xF030 lists " + std::to_string(*count) +
                                    " modules but no init command sets subindex " +
                                    std::to_string(k));
      char ref[16];
      std::snprintf(ref, sizeof ref, "#x%08X", it->second.first);
      out.push_back({ref, file_, it->second.second});
    }
    return out;
  }

  static std::optional<uint8_t> parse_hex_byte(char hi, char lo) {
    auto nib = [](char c) -> int {
      if (c >= '0' && c <= '9') return c - '0';
      if (c >= 'a' && c <= 'f') return c - 'a' + 10;
      if (c >= 'A' && c <= 'F') return c - 'A' + 10;
      return -1;
    };
    const int h = nib(hi), l = nib(lo);
    if (h < 0 || l < 0) return std::nullopt;
    return static_cast<uint8_t>(h * 16 + l);
  }

  // ProcessData/RxPdo and TxPdo: the same PDOs as the ESI, those with Sm assigned.
  void apply_process_data(pugi::xml_node pd, device::EsiDevice& dev) const {
    auto& d = dev.description;
    const bool has_pdos = pd.child("RxPdo") || pd.child("TxPdo");
    if (!has_pdos) return;
    std::set<uint16_t> assigned;
    for (const char* kind : {"RxPdo", "TxPdo"}) {
      const bool rx = std::string_view(kind) == "RxPdo";
      auto& list = rx ? d.rx_pdos : d.tx_pdos;
      for (auto p : pd.children(kind)) {
        const auto index = static_cast<uint16_t>(child_number(p, "Index"));
        auto it = std::find_if(list.begin(), list.end(),
                               [&](const esi::PdoDescription& x) { return x.index == index; });
        if (it == list.end())
          fail(p, std::string(kind) + " " + hex16(index) + " is not a PDO of " + d.order_code +
                      " in " + dev.file);
        size_t k = 0;
        for (auto e : p.children("Entry")) {
          if (k >= it->entries.size())
            fail(e, std::string(kind) + " " + hex16(index) + " has more entries than the ESI's " +
                        "(remapping a PDO is not supported)");
          const auto& want = it->entries[k++];
          const auto ei = static_cast<uint16_t>(child_number(e, "Index"));
          const auto es =
              e.child("SubIndex") ? static_cast<uint8_t>(child_number(e, "SubIndex")) : uint8_t{0};
          const auto bits = static_cast<uint8_t>(child_number(e, "BitLen"));
          if (ei != want.index || (ei != 0 && es != want.subindex) || bits != want.bit_length)
            fail(e, std::string(kind) + " " + hex16(index) + " entry " + std::to_string(k) +
                        " differs from the ESI's (" + hex16(want.index) + ":" +
                        std::to_string(want.subindex) + ", " + std::to_string(want.bit_length) +
                        " bit); remapping a PDO is not supported");
        }
        if (k != it->entries.size())
          fail(p, std::string(kind) + " " + hex16(index) + " has " + std::to_string(k) +
                      " entries, the ESI's " + std::to_string(it->entries.size()));
        if (p.attribute("Sm")) assigned.insert(index);
      }
    }
    // The assignment of each direction, its size against the SM and Send/Recv.
    for (const bool rx : {true, false}) {
      auto& list = rx ? d.rx_pdos : d.tx_pdos;
      std::vector<esi::PdoDescription> on;
      size_t bits = 0;
      for (auto& p : list) {
        const bool now = assigned.count(p.index) != 0;
        if (now != p.assigned && p.mandatory && !now)
          fail(pd, std::string(rx ? "RxPdo " : "TxPdo ") + hex16(p.index) +
                       " is mandatory in the ESI but not assigned");
        p.assigned = now;
        if (!now) continue;
        on.push_back(p);
        for (const auto& e : p.entries) bits += e.bit_length;
      }
      const auto type = rx ? esi::SmType::ProcessOut : esi::SmType::ProcessIn;
      for (size_t n = 0; n < d.sms.size(); ++n) {
        const auto& sm = d.sms[n];
        if (sm.type != type || sm.max_size == 0) continue;
        if (esi::pdo_bytes(on) > sm.max_size)
          fail(pd, std::string("the assigned ") + (rx ? "RxPDOs" : "TxPDOs") + " need " +
                       std::to_string(esi::pdo_bytes(on)) + " bytes but SM" + std::to_string(n) +
                       " of " + d.order_code + " holds at most " + std::to_string(sm.max_size) +
                       " (MaxSize)");
      }
      // Send = the master's outputs (RxPDOs), Recv = its inputs (ETG.2100 ProcessData).
      if (auto io = pd.child(rx ? "Send" : "Recv")) {
        const auto length = static_cast<size_t>(child_number(io, "BitLength"));
        if (length != bits)
          fail(io, std::string("<") + (rx ? "Send" : "Recv") + "> BitLength " +
                       std::to_string(length) + " but the assigned " + (rx ? "RxPDOs" : "TxPDOs") +
                       " have " + std::to_string(bits) + " bits");
      }
      if (dev.has_coe) set_assignment(dev, rx ? 0x1C12 : 0x1C13, on, pd);
    }
  }

  // The start-up value of 0x1C12/0x1C13 follows the ENI's assignment.
  void set_assignment(device::EsiDevice& dev, uint16_t index,
                      const std::vector<esi::PdoDescription>& on, pugi::xml_node at) const {
    coe::Object* obj = dev.dictionary.find(index);
    if (!obj) return;
    if (on.size() > obj->max_subindex())
      fail(at, "the ENI assigns " + std::to_string(on.size()) + " PDOs but " + hex16(index) +
                   " of " + dev.description.order_code + " has room for " +
                   std::to_string(obj->max_subindex()));
    for (size_t i = 0; i < on.size(); ++i) obj->set_u(static_cast<uint8_t>(i + 1), on[i].index);
    for (size_t i = on.size(); i < obj->max_subindex(); ++i)
      obj->set_u(static_cast<uint8_t>(i + 1), 0);
    obj->set_u(0, on.size());
  }

  // Mailbox/CoE/InitCmds: SDO downloads the master sends on a transition (ETG.2100 "CoE
  // init commands"; Ccs 1 = download, ETG.1000.6 §5.6.2.1).
  void check_init_cmds(pugi::xml_node slave, const device::EsiDevice& dev) const {
    auto cmds = slave.child("Mailbox").child("CoE").child("InitCmds");
    if (!cmds) return;
    if (!dev.has_coe && cmds.child("InitCmd"))
      fail(cmds, dev.description.order_code + " in " + dev.file +
                     " has no CoE mailbox, but the ENI has CoE init commands for it");
    for (auto c : cmds.children("InitCmd")) {
      const auto index = static_cast<uint16_t>(child_number(c, "Index"));
      const auto sub = static_cast<uint8_t>(child_number(c, "SubIndex"));
      const bool ca = std::string_view(c.attribute("CompleteAccess").value()) == "true" ||
                      std::string_view(c.attribute("CompleteAccess").value()) == "1";
      if (auto ccs = c.child("Ccs"); ccs && number(ccs, ccs.text().get(), "Ccs") != 1) {
        continue;  // an upload: nothing is written
      }
      const std::string data = c.child("Data").text().get();
      if (data.size() % 2 != 0 ||
          data.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
        fail(c.child("Data") ? c.child("Data") : c, "<Data> is not hexBinary");
      const size_t bytes = data.size() / 2;
      const coe::Object* obj = dev.dictionary.find(index);
      const std::string what = hex16(index) + ":" + std::to_string(sub);
      if (!obj)
        fail(c, "InitCmd writes " + what + " but the dictionary of " + dev.description.order_code +
                    " (" + dev.file + ") has no object " + hex16(index));
      if (ca) continue;  // complete access: the device checks the whole object when written
      const coe::Entry* e = obj->entry(sub);
      if (!e)
        fail(c, "InitCmd writes " + what + " but object " + hex16(index) + " of " +
                    dev.description.order_code + " has no subindex " + std::to_string(sub));
      // The state the command is sent in: PREOP for IP and PS, SAFEOP for SO and SP, ...
      EsmState state = EsmState::PreOp;
      for (auto t : c.children("Transition")) {
        const std::string_view tr = t.text().get();
        if (tr == "IP" || tr.starts_with("P"))
          state = EsmState::PreOp;
        else if (tr.starts_with("S"))
          state = EsmState::SafeOp;
        else if (tr.starts_with("O"))
          state = EsmState::Op;
        if (!coe::access::can_write(e->access, state))
          fail(t, "InitCmd writes " + what + " (" + e->name + ") on transition " + std::string(tr) +
                      " but the ESI makes it not writable then");
      }
      const bool text =
          e->type() == coe::DataType::VisibleString || e->type() == coe::DataType::OctetString;
      if (text ? bytes > e->byte_length() : bytes != e->byte_length())
        fail(c, "InitCmd writes " + std::to_string(bytes) + " byte(s) to " + what + " (" + e->name +
                    ") which has " + std::to_string(e->byte_length()));
    }
  }

  // The CoE init commands the master sends on its way to OP (transitions IP and PS in PREOP,
  // SO in SAFEOP; file order within one) replayed through the device's SDO server
  // (init_cmd_replay.hpp): an SDO abort is the error at that command. The PDO assignment they
  // leave (0x1C12/0x1C13) must be the ENI's ProcessData assignment when that gives one;
  // otherwise it becomes the device's start-up assignment (SII PDOs, SM sizes, 0x1C12/0x1C13),
  // so what the master reads before configuring equals what it configures.
  void replay_init_cmds(pugi::xml_node slave, device::EsiDevice& dev, bool pd_assigned) const {
    std::vector<SdoWrite> writes;
    std::map<uint16_t, size_t> last_line;  // per object: the last command writing it
    const auto cmds = slave.child("Mailbox").child("CoE").child("InitCmds");
    for (const char* tr : {"IP", "PS", "SO"}) {
      for (auto c : cmds.children("InitCmd")) {
        if (auto ccs = c.child("Ccs"); ccs && number(ccs, ccs.text().get(), "Ccs") != 1) continue;
        bool on = false;
        for (auto t : c.children("Transition")) on = on || std::string_view(t.text().get()) == tr;
        if (!on) continue;
        SdoWrite w;
        w.line = line_of(c);
        w.state = tr[0] == 'S' ? EsmState::SafeOp : EsmState::PreOp;
        w.index = static_cast<uint16_t>(child_number(c, "Index"));
        w.subindex = static_cast<uint8_t>(child_number(c, "SubIndex"));
        const std::string_view ca = c.attribute("CompleteAccess").value();
        w.complete_access = ca == "true" || ca == "1";
        const std::string hex = c.child("Data").text().get();
        for (size_t i = 0; i + 1 < hex.size(); i += 2)
          w.data.push_back(parse_hex_byte(hex[i], hex[i + 1]).value_or(0));
        last_line[w.index] = w.line;
        writes.push_back(std::move(w));
      }
    }
    if (writes.empty()) return;
    const coe::ObjectDictionary after = replay_sdo_writes(dev, writes, file_);
    auto& d = dev.description;
    for (const bool rx : {true, false}) {
      const uint16_t index = rx ? 0x1C12 : 0x1C13;
      const coe::Object* now = after.find(index);
      const coe::Object* before = dev.dictionary.find(index);
      if (!now || !before || !last_line.count(index)) continue;
      std::vector<uint16_t> want, got;
      for (uint8_t i = 1; i <= before->sub0(); ++i)
        want.push_back(static_cast<uint16_t>(before->get_u(i)));
      for (uint8_t i = 1; i <= now->sub0(); ++i)
        got.push_back(static_cast<uint16_t>(now->get_u(i)));
      if (got == want) continue;
      auto list = [](const std::vector<uint16_t>& v) {
        std::string t;
        for (auto i : v) t += (t.empty() ? "" : ", ") + hex16(i);
        return t.empty() ? std::string("none") : t;
      };
      if (pd_assigned)
        throw device::FileError(file_, last_line[index],
                                "the init commands leave " + hex16(index) + " = " + list(got) +
                                    " but ProcessData assigns " + list(want));
      auto& pdos = rx ? d.rx_pdos : d.tx_pdos;
      std::vector<esi::PdoDescription> on;
      for (auto& p : pdos) {
        p.assigned = std::find(got.begin(), got.end(), p.index) != got.end();
        if (p.assigned) on.push_back(p);
      }
      for (auto g : got)
        if (std::none_of(on.begin(), on.end(), [&](const auto& p) { return p.index == g; }))
          throw device::FileError(file_, last_line[index],
                                  "the init commands assign " + hex16(g) + " in " + hex16(index) +
                                      " but " + d.order_code + " (" + dev.file +
                                      ") describes no such PDO");
      // The SII lists the PDOs in assignment order.
      std::stable_sort(pdos.begin(), pdos.end(), [&](const auto& a, const auto& b) {
        auto pos = [&](uint16_t i) { return std::find(got.begin(), got.end(), i) - got.begin(); };
        return pos(a.index) < pos(b.index);
      });
      for (auto& sm : d.sms)
        if (sm.type == (rx ? esi::SmType::ProcessOut : esi::SmType::ProcessIn))
          sm.default_size = esi::pdo_bytes(on);
      set_assignment(dev, index, on, slave);
    }
  }

  std::string_view xml_;
  std::string file_;
  std::string esi_dir_;
  std::shared_ptr<const mdp::FileRoot> esi_root_;
  std::vector<Candidate> candidates_;
  std::map<std::string, mdp::RackConfig> racks_;
};

}  // namespace

LineFile parse_eni_file(const std::string& xml_text, const std::string& eni_path,
                        const std::string& esi_dir) {
  EniReader r(xml_text, eni_path, esi_dir);
  return r.read();
}

LineFile load_eni_file(const std::string& eni_path, const std::string& esi_dir) {
  const auto p = std::filesystem::path(eni_path);
  const auto dir = p.parent_path().empty() ? std::filesystem::path(".") : p.parent_path();
  std::string text;
  try {
    text = mdp::FileRoot::open(dir.string())->read(p.filename().string(), kMaxFileBytes);
  } catch (const std::exception& e) {
    throw device::FileError(eni_path, 0, e.what());
  }
  return parse_eni_file(text, eni_path, esi_dir);
}

}  // namespace rackcat::apps
