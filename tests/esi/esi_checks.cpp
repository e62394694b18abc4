#include "tests/esi/esi_checks.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "esi/esi_writer.hpp"
#include "tests/support/shell_quote.hpp"

namespace rackcat::esi::testing {
namespace {

uint32_t hexdec(const char* text) {
  std::string s(text);
  if (s.rfind("#x", 0) == 0) return static_cast<uint32_t>(std::stoul(s.substr(2), nullptr, 16));
  return static_cast<uint32_t>(std::stoul(s));
}

void expect_flags(const pugi::xml_node& flags, uint16_t access, const std::string& where,
                  bool with_pdo) {
  auto expected = esi_access(access);
  auto a = flags.child("Access");
  EXPECT_EQ(std::string(a.text().get()), expected.access) << where;
  EXPECT_EQ(std::string(a.attribute("ReadRestrictions").value()), expected.read_restrictions)
      << where;
  EXPECT_EQ(std::string(a.attribute("WriteRestrictions").value()), expected.write_restrictions)
      << where;
  if (with_pdo) {
    EXPECT_EQ(std::string(flags.child("PdoMapping").text().get()), esi_pdo_mapping(access))
        << where;
  }
}

}  // namespace

std::string schema_dir() {
  std::string dir = RACKCAT_ESI_SCHEMA_DIR;
  return std::filesystem::exists(dir + "/EtherCATInfo.xsd") ? dir : "";
}

std::string validate_with_xmllint(const std::string& xml, const std::string& name) {
  auto path = std::filesystem::temp_directory_path() /
              fmt::format("rackcat-esi-{}-{}.xml", name, static_cast<long>(::getpid()));
  {
    std::ofstream out(path);
    out << xml;
  }
  const std::string cmd =
      fmt::format("xmllint --noout --schema {} {} 2>&1",
                  rackcat::testing::shell_quote(schema_dir() + "/EtherCATInfo.xsd"),
                  rackcat::testing::shell_quote(path.string()));
  std::string output;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return "cannot run xmllint";
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) output.append(buf, n);
  int status = ::pclose(p);
  std::filesystem::remove(path);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "ok";
  // Keep the report short: the first lines say what is wrong.
  if (output.size() > 4000) output.resize(4000);
  return fmt::format("xmllint exit {}: {}", WEXITSTATUS(status), output);
}

void expect_dictionary_matches(const pugi::xml_node& device, const coe::ObjectDictionary& od,
                               const std::set<uint16_t>& in_modules) {
  auto dict = device.child("Profile").child("Dictionary");
  ASSERT_TRUE(dict) << "no Device/Profile/Dictionary";
  std::map<std::string, pugi::xml_node> types;
  for (auto dt : dict.child("DataTypes").children("DataType")) types[dt.child_value("Name")] = dt;

  std::set<uint16_t> in_esi;
  for (auto o : dict.child("Objects").children("Object")) {
    auto index = static_cast<uint16_t>(hexdec(o.child_value("Index")));
    EXPECT_TRUE(in_esi.insert(index).second) << fmt::format("0x{:04X} twice", index);
    const auto* obj = od.find(index);
    if (!obj) {
      ADD_FAILURE() << fmt::format("ESI object 0x{:04X} is not in the dictionary", index);
      continue;
    }
    std::string where = fmt::format("object 0x{:04X}", index);
    EXPECT_EQ(std::string(o.child_value("Name")), obj->name()) << where;
    std::string type = o.child_value("Type");
    ASSERT_TRUE(types.count(type)) << where << ": type " << type << " not in DataTypes";
    if (obj->code() == coe::ObjectCode::Var) {
      const auto& e = obj->entries().front();
      EXPECT_EQ(type, esi_type_name(od, e)) << where;
      EXPECT_EQ(o.child("BitSize").text().as_uint(), e.bit_length) << where;
      expect_flags(o.child("Flags"), e.access, where, true);
      continue;
    }
    EXPECT_EQ(o.child("BitSize").text().as_uint(), obj->bit_size()) << where;
    auto dt = types[type];
    EXPECT_EQ(dt.child("BitSize").text().as_uint(), obj->bit_size()) << where;
    // Expand the DataType into (subindex -> type, bits, offset, flags).
    struct Sub {
      std::string type;
      unsigned bits, offset;
      pugi::xml_node flags;
      std::string name;  // empty for the elements of an array type
    };
    std::map<unsigned, Sub> subs;
    for (auto si : dt.children("SubItem")) {
      std::string sit = si.child_value("Type");
      if (!si.child("SubIdx")) {  // the "Elements" of an array type
        auto arr = types[sit];
        ASSERT_TRUE(arr) << where << ": array type " << sit << " missing";
        unsigned n = arr.child("ArrayInfo").child("Elements").text().as_uint();
        unsigned lbound = arr.child("ArrayInfo").child("LBound").text().as_uint();
        unsigned bits = arr.child("BitSize").text().as_uint() / n;
        unsigned offs = si.child("BitOffs").text().as_uint();
        for (unsigned k = 0; k < n; ++k)
          subs[lbound + k] = {arr.child_value("BaseType"), bits, offs + k * bits, si.child("Flags"),
                              ""};
        continue;
      }
      subs[si.child("SubIdx").text().as_uint()] = {sit, si.child("BitSize").text().as_uint(),
                                                   si.child("BitOffs").text().as_uint(),
                                                   si.child("Flags"), si.child_value("Name")};
    }
    size_t addressable = 0;
    for (const auto& e : obj->entries()) {
      if (e.padding) continue;
      ++addressable;
      std::string ewhere = fmt::format("{}:{:02X}", where, e.subindex);
      auto it = subs.find(e.subindex);
      if (it == subs.end()) {
        ADD_FAILURE() << ewhere << " missing in the ESI data type";
        continue;
      }
      EXPECT_EQ(it->second.type, esi_type_name(od, e)) << ewhere;
      EXPECT_EQ(it->second.bits, e.bit_length) << ewhere;
      EXPECT_EQ(it->second.offset, e.bit_offset) << ewhere;
      // Issue 15 item 10: the name SDO Information gives (subindex 0 included), made unique
      // with " (SubIndex nnn)" where the schema's SubItemKey needs it.
      if (!it->second.name.empty() && it->second.name != e.name) {
        EXPECT_EQ(it->second.name.rfind(e.name.empty() ? "Entry" : e.name, 0), 0u) << ewhere;
        EXPECT_NE(it->second.name.find(fmt::format("(SubIndex {:03d})", e.subindex)),
                  std::string::npos)
            << ewhere << ": " << it->second.name;
      }
      expect_flags(it->second.flags, e.access, ewhere, true);
    }
    EXPECT_EQ(subs.size(), addressable) << where << ": ESI has other subindices";
  }
  od.for_each([&](const coe::Object& obj) {
    // Enumeration objects (0x0800..0x0FFF) are data types in the ESI, declared with EnumInfo
    // where an entry uses them (ETG.2000 §5.4.3), not Objects.
    if (coe::is_enum_type(obj.index())) return;
    if (in_modules.count(obj.index()) != 0) {
      EXPECT_FALSE(in_esi.count(obj.index()))
          << fmt::format("module object 0x{:04X} also at device level", obj.index());
      return;
    }
    EXPECT_TRUE(in_esi.count(obj.index()))
        << fmt::format("dictionary object 0x{:04X} missing in the ESI", obj.index());
  });
}

void expect_pdos_and_sms_match(const pugi::xml_node& device, const DeviceDescription& d) {
  auto check = [&](const char* element, const std::vector<PdoDescription>& pdos) {
    std::vector<pugi::xml_node> nodes;
    for (auto p : device.children(element)) nodes.push_back(p);
    ASSERT_EQ(nodes.size(), pdos.size()) << element;
    for (size_t i = 0; i < pdos.size(); ++i) {
      const auto& p = pdos[i];
      auto n = nodes[i];
      std::string where = fmt::format("{} 0x{:04X}", element, p.index);
      EXPECT_EQ(hexdec(n.child_value("Index")), p.index) << where;
      EXPECT_EQ(std::string(n.child_value("Name")), p.name) << where;
      if (p.assigned) {
        EXPECT_EQ(n.attribute("Sm").as_int(-1), p.sm) << where;
      } else {
        EXPECT_FALSE(n.attribute("Sm")) << where;
      }
      std::vector<pugi::xml_node> entries;
      for (auto e : n.children("Entry")) entries.push_back(e);
      ASSERT_EQ(entries.size(), p.entries.size()) << where;
      for (size_t k = 0; k < entries.size(); ++k) {
        EXPECT_EQ(hexdec(entries[k].child_value("Index")), p.entries[k].index) << where;
        if (p.entries[k].index != 0) {
          EXPECT_EQ(hexdec(entries[k].child_value("SubIndex")), p.entries[k].subindex) << where;
        }
        EXPECT_EQ(entries[k].child("BitLen").text().as_uint(), p.entries[k].bit_length) << where;
      }
    }
  };
  check("RxPdo", d.rx_pdos);
  check("TxPdo", d.tx_pdos);
  std::vector<pugi::xml_node> sms;
  for (auto s : device.children("Sm")) sms.push_back(s);
  ASSERT_EQ(sms.size(), d.sms.size());
  for (size_t i = 0; i < sms.size(); ++i) {
    std::string where = fmt::format("Sm {}", i);
    EXPECT_EQ(hexdec(sms[i].attribute("StartAddress").value()), d.sms[i].start) << where;
    EXPECT_EQ(hexdec(sms[i].attribute("DefaultSize").value()), d.sms[i].default_size) << where;
    EXPECT_EQ(hexdec(sms[i].attribute("ControlByte").value()), d.sms[i].control) << where;
    EXPECT_EQ(hexdec(sms[i].attribute("Enable").value()), d.sms[i].enable ? 1u : 0u) << where;
  }
}

}  // namespace rackcat::esi::testing
