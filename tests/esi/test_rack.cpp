// The SII and ESI of real racks built by mdp: the tiny test rack, the default rack and a
// generated 120-module rack (5 x 24 slots). Each ESI validates against the ETG.2000 schema and
// agrees with the device's live dictionary; the SII agrees with both.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <map>
#include <pugixml.hpp>
#include <set>

#include "esi/rack.hpp"
#include "esi/sii_image.hpp"
#include "esi/sii_parser.hpp"
#include "mdp/card_catalogue.hpp"
#include "mdp/device.hpp"
#include "mdp/diagnosis_catalogue.hpp"
#include "mdp/rack_config.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "tests/esi/esi_checks.hpp"
#include "tests/esi/rack_files.hpp"

namespace rackcat::esi {
namespace {

mdp::DeviceOptions no_state() {
  mdp::DeviceOptions o;
  o.load_stored_parameters = false;
  return o;
}

mdp::RackConfig rack(const std::string& which) {
  if (which == "tiny") return mdp::load_rack_config(RACKCAT_ESI_TEST_DATA "/tiny-rack.yaml");
  if (which == "default") return mdp::default_rack();
  return mdp::parse_rack_config(testing::rack_120_yaml(), "<120 modules>");
}

class RackEsi : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { device = std::make_unique<mdp::Device>(rack(GetParam()), no_state()); }
  std::unique_ptr<mdp::Device> device;
};

TEST_P(RackEsi, ValidatesAgainstTheEtg2000Schema) {
  if (testing::schema_dir().empty())
    GTEST_SKIP() << "ESI schema not found at " RACKCAT_ESI_SCHEMA_DIR;
  EXPECT_EQ(testing::validate_with_xmllint(write_esi(*device), GetParam()), "ok");
}

TEST_P(RackEsi, DictionaryPdosAndSmsMatchTheLiveDevice) {
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  auto dev = doc.select_node("/EtherCATInfo/Descriptions/Devices/Device").node();
  // The slots' objects (0x3nn1.., 0x4nnX..0x9nnX of module nn+1; docs/MDP.md) are defined in
  // their <Module> only.
  std::set<uint16_t> in_modules;
  for (const auto& m : device->modules()) {
    device->dictionary().for_each([&](const coe::Object& o) {
      const uint16_t i = o.index();
      if (i > 0x3000 && i <= 0x9FFF && ((i >> 4) & 0xFF) == m.nn() && (i & 0xF) != 0)
        in_modules.insert(i);
      if (i > 0x3FFF && i <= 0x9FFF && ((i >> 4) & 0xFF) == m.nn()) in_modules.insert(i);
    });
  }
  EXPECT_FALSE(in_modules.empty());
  testing::expect_dictionary_matches(dev, device->dictionary(), in_modules);
  testing::expect_pdos_and_sms_match(dev, describe_device(*device));
}

// ETG.1020 ch. 13 / ETG.2000 DiagnosticsType: the device Profile carries a DiagMessage for every
// text ID the device can put into 0x10F3, and Mailbox/CoE announces the history.
TEST_P(RackEsi, DiagMessagesCarryEveryTextOfTheHistory) {
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  auto dev = doc.select_node("/EtherCATInfo/Descriptions/Devices/Device").node();
  EXPECT_STREQ(dev.child("Mailbox").child("CoE").attribute("DiagHistory").value(), "true");
  std::map<std::string, std::pair<std::string, std::string>> esi;
  for (auto m : dev.child("Profile").child("DiagMessages").children("DiagMessage")) {
    esi[m.child_value("TextId")] = {m.child_value("MessageText"),
                                    m.child("Flags").child_value("DiagClass")};
  }
  ASSERT_EQ(esi.size(), mdp::diag::catalogue().size());
  for (const auto& t : mdp::diag::catalogue()) {
    const auto it = esi.find(fmt::format("#x{:04X}", t.text_id));
    ASSERT_NE(it, esi.end()) << std::hex << t.text_id;
    EXPECT_EQ(it->second.first, t.text);
    const char* cls = (t.text_id >> 12) == 0x8   ? "error"
                      : (t.text_id >> 12) == 0x4 ? "warning"
                                                 : "information";
    EXPECT_EQ(it->second.second, cls) << std::hex << t.text_id;
  }
}

// What a configurator reads (compared with vendor modular devices): slot PDOs at device level
// marked OverwrittenByModule, the user PDOs editable, <Info> timeouts that grow with the rack,
// enumerations with a BaseType, and a module name true for every card that shares its ident.
TEST_P(RackEsi, ConfiguratorsSeeOverwritableSlotPdosTimeoutsEnumsAndSharedModuleNames) {
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  auto dev = doc.select_node("/EtherCATInfo/Descriptions/Devices/Device").node();
  size_t user = 0;
  for (const char* element : {"RxPdo", "TxPdo"}) {
    for (auto p : dev.children(element)) {
      const auto index = std::stoul(p.child_value("Index") + 2, nullptr, 16);
      const bool is_user = index == mdp::sm::kUserRxPdo || index == mdp::sm::kUserTxPdo;
      const bool slot =
          (index >= 0x1600 && index <= 0x16FE) || (index >= 0x1A00 && index <= 0x1AFE);
      user += is_user;
      EXPECT_EQ(p.attribute("OverwrittenByModule").as_bool(), slot) << index;
      if (is_user || slot) {
        EXPECT_EQ(p.attribute("Fixed").as_bool(), slot) << index;
      }
    }
  }
  EXPECT_EQ(user, 2u);
  auto timeout = dev.child("Info").child("StateMachine").child("Timeout");
  const int modules = static_cast<int>(device->modules().size());
  EXPECT_EQ(timeout.child("SafeopOpTimeout").text().as_int(), 10000 + 50 * modules);
  EXPECT_GE(
      dev.child("Info").child("Mailbox").child("Timeout").child("ResponseTimeout").text().as_int(),
      2000);
  // Enumeration types: BaseType before BitSize, never an Object of their own.
  auto baud = doc.select_node("//DataType[Name='DT0800EN04']").node();
  ASSERT_TRUE(baud);
  EXPECT_STREQ(baud.child_value("BaseType"), "BIT4");
  EXPECT_FALSE(doc.select_node("//Device/Profile/Dictionary/Objects/Object[Index='#x0800']"));
  // 0x0064D116 is CDI-10, CDI-11 and CDI-12 (guide Table 5).
  auto din16 = doc.select_node("//Modules/Module[Type/@ModuleIdent='#x0064D116']/Name").node();
  ASSERT_TRUE(din16);
  const std::string name = din16.child_value();
  for (const char* card : {"CDI-10", "CDI-11", "CDI-12"})
    EXPECT_NE(name.find(card), std::string::npos) << name;
  EXPECT_EQ(name.find("Inverted"), std::string::npos) << name;
}

// ETG.2000 ObjectInfoType/Unit: the entries whose unit the guide states carry the ETG.1004 code
// (prefix << 24 | numerator << 16 | denominator << 8, CiA 303-2 notation indices: volt 0x26,
// ohm 0x28, degree Celsius 0x2D, revolution 0xB4, minute 0x47), and every Dictionary declares
// the notation indices its Units use in UnitTypes.
TEST_P(RackEsi, UnitsAreEtg1004CodesDeclaredInTheDictionarysUnitTypes) {
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  auto unit_of = [&](const char* object, const char* sub) {
    const auto xpath =
        fmt::format("//Object[Name='{}']/Info/SubItem[Name='{}']/Info/Unit", object, sub);
    return std::string(doc.select_node(xpath.c_str()).node().child_value());
  };
  EXPECT_EQ(unit_of("Device Information", "Temperature (CPU Zone)"), "#x002D0000");  // °C
  EXPECT_EQ(unit_of("Device Information", "Fan RPM (CPU Zone)"), "#x00B44700");      // rev/min
  EXPECT_EQ(unit_of("Device Information", "Fan Status (CPU Zone)"), "");  // percent: no code known
  EXPECT_EQ(unit_of("Module Information", "Max Voltage"), "#x00260000");  // V
  if (GetParam() == "default") {
    EXPECT_EQ(unit_of("Thermocouple Info", "SubIndex 001"), "#x00280000");        // Ω
    EXPECT_EQ(unit_of("Thermocouplex8 (inputs)", "SubIndex 001"), "#xFF2D0000");  // 0.1 °C
    EXPECT_EQ(unit_of("AINx8 (inputs)", "SubIndex 001"), "");  // full-scale fraction
  }
  size_t units = 0;
  for (auto d : doc.select_nodes("//Dictionary")) {
    std::set<unsigned long> declared;
    for (auto t : d.node().child("UnitTypes").children("UnitType")) {
      declared.insert(std::stoul(t.child_value("NotationIndex") + 2, nullptr, 16));
      EXPECT_STRNE(t.child_value("Symbol"), "");
    }
    for (auto u : d.node().select_nodes(".//Unit")) {
      const auto code = std::stoul(u.node().child_value() + 2, nullptr, 16);
      ++units;
      for (unsigned long index : {(code >> 16) & 0xFF, (code >> 8) & 0xFF}) {
        if (index != 0) {
          EXPECT_TRUE(declared.count(index)) << std::hex << code;
        }
      }
    }
  }
  EXPECT_GT(units, 0u);
}

// Octet arrays (the guide's "ARRAY [0..n] OF BYTE" command entries and sample arrays) are
// OCTET_STRING(n) in the ESI, as SDO Information describes them (data type 0x000A, 8n bits):
// the DataType's BitSize is 8n and a DefaultData holds exactly n bytes.
TEST_P(RackEsi, OctetArraysAgreeWithSdoInformation) {
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  size_t strings = 0, defaults = 0;
  for (auto d : doc.select_nodes("//Dictionary")) {
    std::map<std::string, pugi::xml_node> types;
    for (auto t : d.node().child("DataTypes").children("DataType"))
      types[t.child_value("Name")] = t;
    auto octets = [](const std::string& type) -> unsigned {
      if (type.rfind("OCTET_STRING(", 0) != 0) return 0;
      return static_cast<unsigned>(std::stoul(type.substr(13)));
    };
    for (const auto& [name, t] : types) {
      if (const unsigned n = octets(name)) {
        ++strings;
        EXPECT_EQ(t.child("BitSize").text().as_uint(), 8 * n) << name;
      }
    }
    for (auto o : d.node().child("Objects").children("Object")) {
      const std::string type = o.child_value("Type");
      if (const unsigned n = octets(type)) {  // a VAR object
        if (o.child("Info").child("DefaultData")) {
          ++defaults;
          EXPECT_EQ(std::string(o.child("Info").child_value("DefaultData")).size(), 2u * n);
        }
        continue;
      }
      auto dt = types[type];
      for (auto si : o.child("Info").children("SubItem")) {
        std::string sub_type;
        for (auto s : dt.children("SubItem")) {
          if (std::string(s.child_value("Name")) == si.child_value("Name"))
            sub_type = s.child_value("Type");
        }
        const unsigned n = octets(sub_type);
        if (n == 0 || !si.child("Info").child("DefaultData")) continue;
        ++defaults;
        EXPECT_EQ(std::string(si.child("Info").child_value("DefaultData")).size(), 2u * n)
            << o.child_value("Index") << " " << si.child_value("Name");
      }
    }
  }
  EXPECT_GT(strings, 0u);
  EXPECT_GT(defaults, 0u);
}

TEST_P(RackEsi, SiiIdentityEqualsIdentityObjectAndEsiType) {
  auto info = parse_sii(build_sii(*device).span());
  const auto* identity = device->dictionary().find(0x1018);
  ASSERT_NE(identity, nullptr);
  EXPECT_EQ(info.vendor_id, identity->get_u(1));
  EXPECT_EQ(info.product_code, identity->get_u(2));
  EXPECT_EQ(info.revision, identity->get_u(3));
  EXPECT_EQ(info.serial, identity->get_u(4));
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  auto type = doc.select_node("//Devices/Device/Type").node();
  EXPECT_EQ(std::stoul(type.attribute("ProductCode").value() + 2, nullptr, 16), info.product_code);
  EXPECT_EQ(std::stoul(type.attribute("RevisionNo").value() + 2, nullptr, 16), info.revision);
  EXPECT_EQ(std::stoul(doc.select_node("//Vendor/Id").node().text().get() + 2, nullptr, 16),
            info.vendor_id);
}

TEST_P(RackEsi, SiiMailboxAndSmsEqualEsiSmAndTheEsmChecks) {
  auto img = build_sii(*device);
  auto info = parse_sii(img.span());
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(*device).c_str()));
  std::vector<pugi::xml_node> sms;
  for (auto s : doc.select_node("//Devices/Device").node().children("Sm")) sms.push_back(s);
  ASSERT_EQ(sms.size(), 4u);
  auto hex = [](const char* v) { return std::stoul(std::string(v).substr(2), nullptr, 16); };
  EXPECT_EQ(info.standard_receive_offset, hex(sms[0].attribute("StartAddress").value()));
  EXPECT_EQ(info.standard_receive_size, sms[0].attribute("DefaultSize").as_uint());
  EXPECT_EQ(info.standard_send_offset, hex(sms[1].attribute("StartAddress").value()));
  EXPECT_EQ(info.standard_send_size, sms[1].attribute("DefaultSize").as_uint());
  EXPECT_EQ(info.standard_receive_offset, mdp::sm::kMailboxOutStart);
  EXPECT_EQ(info.standard_receive_size, mdp::sm::kMailboxOutSize);
  EXPECT_EQ(info.standard_send_offset, mdp::sm::kMailboxInStart);
  EXPECT_EQ(info.standard_send_size, mdp::sm::kMailboxInSize);
  ASSERT_EQ(info.sms.size(), 4u);
  // The process-data SM lengths are what the device expects at PREOP->SAFEOP.
  EXPECT_EQ(info.sms[2].length, device->output_bytes());
  EXPECT_EQ(info.sms[3].length, device->input_bytes());
  EXPECT_EQ(info.sms[2].length, sms[2].attribute("DefaultSize").as_uint());
  EXPECT_EQ(info.sms[3].length, sms[3].attribute("DefaultSize").as_uint());
  // ESI Eeprom = the image.
  auto eeprom = doc.select_node("//Devices/Device/Eeprom").node();
  EXPECT_EQ(eeprom.child("ByteSize").text().as_ullong(), img.bytes.size());
  std::string config = eeprom.child_value("ConfigData");
  ASSERT_EQ(config.size(), 32u);
  for (size_t i = 0; i < 16; ++i)
    EXPECT_EQ(std::stoul(config.substr(2 * i, 2), nullptr, 16), img.bytes[i]) << i;
  // The bootstrap mailbox (ETG.2010 Table 2 words 0x14-0x17) is the device's own: SM0/SM1 of
  // BOOT, and the ESI Eeprom/BootStrap holds the same 8 bytes; FoE is announced in both.
  EXPECT_EQ(info.bootstrap_receive_offset, mdp::sm::kBootMailboxOutStart);
  EXPECT_EQ(info.bootstrap_receive_size, mdp::sm::kBootMailboxSize);
  EXPECT_EQ(info.bootstrap_send_offset, mdp::sm::kBootMailboxInStart);
  EXPECT_EQ(info.bootstrap_send_size, mdp::sm::kBootMailboxSize);
  std::string boot = eeprom.child_value("BootStrap");
  ASSERT_EQ(boot.size(), 16u);
  for (size_t i = 0; i < 8; ++i)
    EXPECT_EQ(std::stoul(boot.substr(2 * i, 2), nullptr, 16), img.bytes[2 * 0x14 + i]) << i;
  EXPECT_EQ(info.mailbox_protocol, sii::kProtoCoE | sii::kProtoFoE);
  EXPECT_TRUE(doc.select_node("//Devices/Device/Mailbox/FoE"));
}

TEST_P(RackEsi, SiiPdoCategoriesListTheAssignedPdosInOrder) {
  auto info = parse_sii(build_sii(*device).span());
  const auto& od = device->dictionary();
  auto assigned = [&](uint16_t index) {
    std::vector<uint16_t> out;
    const auto* o = od.find(index);
    for (uint8_t s = 1; o && s <= o->sub0(); ++s) out.push_back(static_cast<uint16_t>(o->get_u(s)));
    return out;
  };
  std::vector<uint16_t> rx, tx;
  for (const auto& p : info.rx_pdos) rx.push_back(p.index);
  for (const auto& p : info.tx_pdos) tx.push_back(p.index);
  EXPECT_EQ(rx, assigned(0x1C12));
  EXPECT_EQ(tx, assigned(0x1C13));
  for (const auto& p : info.tx_pdos) {
    const auto* mapping = od.find(p.index);
    ASSERT_NE(mapping, nullptr);
    ASSERT_EQ(p.entries.size(), mapping->sub0());
    for (size_t k = 0; k < p.entries.size(); ++k) {
      auto v = static_cast<uint32_t>(mapping->get_u(static_cast<uint8_t>(k + 1)));
      EXPECT_EQ(p.entries[k].index, v >> 16);
      EXPECT_EQ(p.entries[k].subindex, (v >> 8) & 0xFF);
      EXPECT_EQ(p.entries[k].bit_length, v & 0xFF);
    }
  }
}

TEST_P(RackEsi, ConfigurationCategoriesAndDeviceNameLieInSoemsSiiCache) {
  // SOEM reads SII bytes below EC_MAXEEPBUF = 4096 only; beyond, it sees 0xFF ("End").
  auto img = build_sii(*device);
  auto info = parse_sii(img.span());
  std::set<uint16_t> needed = {30, 40, 41, 10};
  for (const auto& c : info.categories) {
    if (!needed.count(c.type)) continue;
    size_t end = 2u * (c.word_address + 2u) + (c.type == 10 ? 64u : 2u * c.length_words);
    EXPECT_LE(end, 4096u) << "category " << c.type;
    needed.erase(c.type);
  }
  EXPECT_TRUE(needed.empty());
}

INSTANTIATE_TEST_SUITE_P(Racks, RackEsi, ::testing::Values("tiny", "default", "modules120"));

TEST(RackModules, OneModulePerIdentWithItsObjectsAndPdos) {
  auto modules = describe_module_types();
  std::set<uint32_t> idents;
  for (const auto& card : mdp::card_catalogue()) idents.insert(card.module_ident);
  ASSERT_EQ(modules.size(), idents.size());
  for (const auto& m : modules) {
    EXPECT_TRUE(idents.count(m.ident)) << m.type;
    const auto* card = mdp::find_card_by_ident(m.ident);
    ASSERT_NE(card, nullptr);
    // Module 1's indices: 0x3001 module information, inputs 0x600X / outputs 0x700X.
    EXPECT_NE(m.dictionary.find(0x3001), nullptr) << m.type;
    if (card->input) {
      EXPECT_NE(m.dictionary.find(static_cast<uint16_t>(0x6000 + uint16_t(*card->input))), nullptr)
          << m.type;
      ASSERT_EQ(m.tx_pdos.size(), 1u) << m.type;
      EXPECT_EQ(m.tx_pdos[0].index, 0x1A00);
    }
    if (card->output) {
      EXPECT_NE(m.dictionary.find(static_cast<uint16_t>(0x7000 + uint16_t(*card->output))), nullptr)
          << m.type;
      ASSERT_EQ(m.rx_pdos.size(), 1u) << m.type;
      EXPECT_EQ(m.rx_pdos[0].index, 0x1600);
    }
    m.dictionary.for_each([&](const coe::Object& o) {
      // Module 1's areas: 0x3001..0x700F, and for the encoder card its configuration and
      // information objects 0x800X / 0x900X (docs/ENCODER.md).
      const bool area = (o.index() >= 0x3001 && o.index() <= 0x700F) ||
                        (card->encoder() && (o.index() & 0xEFF0) == 0x8000);
      EXPECT_TRUE(area) << m.type << fmt::format(" object 0x{:04X} outside module 1", o.index());
    });
  }
}

TEST(RackModules, EsiSlotsListEveryIdentWithTheMdpIncrements) {
  mdp::Device device(mdp::default_rack(), no_state());
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(write_esi(device).c_str()));
  auto slots = doc.select_node("//Devices/Device/Slots").node();
  ASSERT_TRUE(slots);
  EXPECT_STREQ(slots.attribute("SlotIndexIncrement").value(), "#x10");
  EXPECT_EQ(slots.attribute("SlotPdoIncrement").as_uint(), mdp::sm::kPdoIndexIncrement);
  std::set<std::string> in_slot;
  for (auto id : slots.child("Slot").children("ModuleIdent")) in_slot.insert(id.text().get());
  std::set<std::string> modules;
  for (auto m : doc.select_nodes("//Descriptions/Modules/Module/Type"))
    modules.insert(m.node().attribute("ModuleIdent").value());
  EXPECT_EQ(in_slot, modules);
  for (const auto& card : mdp::card_catalogue())
    EXPECT_TRUE(in_slot.count(esi_hex(card.module_ident, 8))) << card.name;
}

}  // namespace
}  // namespace rackcat::esi
