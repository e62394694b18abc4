// The ESI writer against a hand-built dictionary: schema-valid, and every object, PDO and SM
// of the dictionary appears with the same type, size, access and PDO flags.
#include <gtest/gtest.h>

#include <pugixml.hpp>

#include "esi/describe_dictionary.hpp"
#include "esi/esi_writer.hpp"
#include "esi/sii_image.hpp"
#include "tests/esi/esi_checks.hpp"
#include "tests/esi/sample_dictionary.hpp"

namespace rackcat::esi {
namespace {

struct Sample {
  coe::ObjectDictionary od = testing::sample_dictionary();
  DeviceDescription d = describe_dictionary(od, testing::sample_texts(), SmPlan{});
  SiiImage sii = encode_sii(d);

  EsiContent content() const {
    EsiContent c;
    c.device = &d;
    c.dictionary = &od;
    c.config_data = encode_config_area(d.config);
    c.eeprom_bytes = sii.bytes.size();
    return c;
  }
};

ModuleDescription sample_module() {
  ModuleDescription m;
  m.ident = 0x00D00000;
  m.type = "CDI-10";
  m.name = "16xDin 24V";
  auto od = testing::sample_dictionary();
  coe::Object obj(0x6000, coe::ObjectCode::Var, "DINx16", 0x0006);
  coe::Entry e;
  e.name = "DIN[15..0]";
  e.data_type = 0x0006;
  e.access = coe::access::kRo | coe::access::kTxPdoMappable;
  obj.add(e);
  m.dictionary.add(std::move(obj));
  PdoDescription p;
  p.index = 0x1A00;
  p.name = "TxPDO Mapping (DINx16)";
  p.sm = 3;
  p.entries.push_back({0x6000, 0, "DIN[15..0]", 0x0006, 16});
  m.tx_pdos.push_back(p);
  return m;
}

pugi::xml_document parse(const std::string& xml) {
  pugi::xml_document doc;
  EXPECT_TRUE(doc.load_string(xml.c_str()));
  return doc;
}

TEST(EsiWriter, ValidatesAgainstTheEtg2000Schema) {
  if (testing::schema_dir().empty())
    GTEST_SKIP() << "ESI schema not found at " RACKCAT_ESI_SCHEMA_DIR;
  Sample s;
  auto c = s.content();
  c.modules.push_back(sample_module());
  EXPECT_EQ(testing::validate_with_xmllint(write_esi(c), "sample"), "ok");
}

TEST(EsiWriter, EveryDictionaryObjectAppearsWithSameTypeSizeAccessAndPdoFlags) {
  Sample s;
  auto doc = parse(write_esi(s.content()));
  auto device = doc.select_node("/EtherCATInfo/Descriptions/Devices/Device").node();
  testing::expect_dictionary_matches(device, s.od);
  testing::expect_pdos_and_sms_match(device, s.d);
}

TEST(EsiWriter, PerStateAccessBecomesRestrictions) {
  Sample s;
  auto doc = parse(write_esi(s.content()));
  auto o = doc.select_node("//Profile/Dictionary/Objects/Object[Index='#x7000']").node();
  ASSERT_TRUE(o);
  auto a = o.child("Flags").child("Access");
  EXPECT_STREQ(a.text().get(), "rw");
  EXPECT_STREQ(a.attribute("ReadRestrictions").value(), "SafeOP_OP");
  EXPECT_STREQ(a.attribute("WriteRestrictions").value(), "OP");
  EXPECT_STREQ(o.child("Flags").child_value("PdoMapping"), "R");
  auto ip = doc.select_node("//DataType[Name='DT2000']/SubItem[SubIdx='1']").node();
  EXPECT_STREQ(ip.child("Flags").child_value("Access"), "rw");
  EXPECT_STREQ(ip.child("Flags").child_value("Backup"), "1");
  auto cmd = doc.select_node("//DataType[Name='DT2000']/SubItem[SubIdx='2']").node();
  EXPECT_STREQ(cmd.child("Flags").child_value("Access"), "wo");
}

TEST(EsiWriter, DataTypesCoverBasicArrayRecordAndEnumTypes) {
  Sample s;
  auto doc = parse(write_esi(s.content()));
  EXPECT_TRUE(doc.select_node("//DataTypes/DataType[Name='UDINT' and BitSize='32']"));
  EXPECT_TRUE(doc.select_node("//DataTypes/DataType[Name='STRING(16)' and BitSize='128']"));
  EXPECT_TRUE(doc.select_node("//DataTypes/DataType[Name='BIT4' and BitSize='4']"));
  // 0x6002 ARRAY [1..4] OF INT: array type + object type with SubIndex 000 and Elements.
  auto arr = doc.select_node("//DataTypes/DataType[Name='DT6002ARR']").node();
  ASSERT_TRUE(arr);
  EXPECT_STREQ(arr.child_value("BaseType"), "INT");
  EXPECT_EQ(arr.child("ArrayInfo").child("Elements").text().as_int(), 4);
  EXPECT_TRUE(doc.select_node("//DataTypes/DataType[Name='DT6002']/SubItem[Name='Elements']"));
  EXPECT_TRUE(doc.select_node("//DataTypes/DataType[Name='DT1018']/SubItem[Name='Vendor ID']"));
  auto en = doc.select_node("//DataTypes/DataType[Name='DT0800EN02']").node();
  ASSERT_TRUE(en);
  EXPECT_TRUE(en.select_node("EnumInfo[Text='RS-485' and Enum='1']"));
  // Defaults are the dictionary's start-up values, little-endian hex.
  auto vendor =
      doc.select_node("//Object[Index='#x1018']/Info/SubItem[Name='Vendor ID']/Info").node();
  EXPECT_STREQ(vendor.child_value("DefaultData"), "BC0A0000");
  auto name = doc.select_node("//Object[Index='#x1008']/Info").node();
  EXPECT_STREQ(name.child_value("DefaultString"), "Sample rack");
}

TEST(EsiWriter, IdentityMailboxDcAndEepromMatchTheSii) {
  Sample s;
  auto doc = parse(write_esi(s.content()));
  auto device = doc.select_node("/EtherCATInfo/Descriptions/Devices/Device").node();
  EXPECT_STREQ(doc.select_node("/EtherCATInfo/Vendor/Id").node().text().get(), "#x00000ABC");
  EXPECT_STREQ(device.child("Type").attribute("ProductCode").value(), "#x00464E01");
  EXPECT_STREQ(device.child("Type").attribute("RevisionNo").value(), "#x00010009");
  auto coe = device.child("Mailbox").child("CoE");
  for (const char* flag : {"SdoInfo", "PdoAssign", "PdoConfig", "CompleteAccess", "SegmentedSdo"})
    EXPECT_TRUE(coe.attribute(flag).as_bool()) << flag;
  std::vector<std::string> modes;
  for (auto m : device.child("Dc").children("OpMode")) modes.push_back(m.child_value("Name"));
  EXPECT_EQ(modes, (std::vector<std::string>{"FreeRun", "SM-Synchron", "DC"}));
  EXPECT_STREQ(device.select_node("Dc/OpMode[Name='DC']/AssignActivate").node().text().get(),
               "#x0300");
  EXPECT_EQ(device.child("Eeprom").child("ByteSize").text().as_ullong(), s.sii.bytes.size());
  // ConfigData = SII words 0..7 (16 bytes) exactly.
  std::string config = device.child("Eeprom").child_value("ConfigData");
  ASSERT_EQ(config.size(), 32u);
  for (size_t i = 0; i < 16; ++i)
    EXPECT_EQ(std::stoul(config.substr(2 * i, 2), nullptr, 16), s.sii.bytes[i]) << i;
}

TEST(EsiWriter, ModulesAndSlotsDescribeEachCardType) {
  Sample s;
  auto c = s.content();
  c.modules.push_back(sample_module());
  auto doc = parse(write_esi(c));
  auto slots = doc.select_node("//Device/Slots").node();
  ASSERT_TRUE(slots);
  EXPECT_STREQ(slots.attribute("SlotIndexIncrement").value(), "#x10");
  EXPECT_STREQ(slots.attribute("SlotPdoIncrement").value(), "1");
  EXPECT_STREQ(slots.child("Slot").child_value("ModuleIdent"), "#x00D00000");
  auto mod = doc.select_node("//Descriptions/Modules/Module").node();
  ASSERT_TRUE(mod);
  EXPECT_STREQ(mod.child("Type").attribute("ModuleIdent").value(), "#x00D00000");
  EXPECT_STREQ(mod.child_value("Name"), "16xDin 24V");
  EXPECT_TRUE(mod.child("TxPdo").child("Index").attribute("DependOnSlot").as_bool());
  auto obj = mod.select_node("Profile/Dictionary/Objects/Object[Index='#x6000']").node();
  ASSERT_TRUE(obj);
  EXPECT_TRUE(obj.child("Index").attribute("DependOnSlot").as_bool());
}

}  // namespace
}  // namespace rackcat::esi
