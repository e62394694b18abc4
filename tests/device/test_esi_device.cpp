// ESI device reader: the test devices of data/rackcat-test-devices.xml (written for these tests
// from ETG.2000) and one precise error per bad file.
#include <gtest/gtest.h>

#include <string>

#include "device/esi_device.hpp"
#include "device/esi_error.hpp"
#include "esi/sii_image.hpp"
#include "esi/sii_parser.hpp"

namespace rackcat::device {
namespace {

const std::string kFile = std::string(RACKCAT_DEVICE_TEST_DATA) + "/rackcat-test-devices.xml";

EsiDevice load(const std::string& name) {
  return load_esi_device(kFile, DeviceSelector::named(name));
}

TEST(EsiDevice, CouplerWithoutMailboxHasIdentityAndNoSm) {
  auto d = load("RC1100");
  EXPECT_FALSE(d.has_coe);
  EXPECT_EQ(d.description.vendor_id, 0x0E1Cu);
  EXPECT_EQ(d.description.product_code, 0x1100u);
  EXPECT_EQ(d.description.revision, 0x00010000u);
  EXPECT_EQ(d.description.device_name, "RC1100 EtherCAT coupler");
  EXPECT_EQ(d.description.group_name, "Couplers");
  EXPECT_TRUE(d.description.sms.empty());
  auto info = esi::parse_sii(esi::encode_sii(d.description).span());
  EXPECT_EQ(info.product_code, 0x1100u);
  EXPECT_EQ(info.standard_receive_size, 0u);
  EXPECT_EQ(info.mailbox_protocol, 0u);
  EXPECT_EQ(info.string(info.general.name_idx), "RC1100 EtherCAT coupler");
  EXPECT_EQ(info.pdi_control, 0x0105u);  // from <ConfigData>
}

TEST(EsiDevice, DigitalInputPdosGoToSm3) {
  auto d = load("RC1008");
  EXPECT_FALSE(d.has_coe);
  ASSERT_EQ(d.description.sms.size(), 4u);
  EXPECT_EQ(d.description.sms[3].type, esi::SmType::ProcessIn);
  EXPECT_EQ(d.description.sms[3].default_size, 1u);
  EXPECT_FALSE(d.description.sms[0].enable);
  ASSERT_EQ(d.description.tx_pdos.size(), 8u);
  EXPECT_EQ(d.description.tx_pdos[7].sm, 3);
  auto info = esi::parse_sii(esi::encode_sii(d.description).span());
  ASSERT_EQ(info.tx_pdos.size(), 8u);
  EXPECT_EQ(info.tx_pdos[0].entries[0].index, 0x6000u);
  EXPECT_EQ(info.tx_pdos[0].entries[0].bit_length, 1u);
}

TEST(EsiDevice, ByProductCode) {
  auto d = load_esi_device(kFile, DeviceSelector::by_code(0x2008, 0x00010000));
  EXPECT_EQ(d.description.order_code, "RC2008");
  EXPECT_EQ(d.description.sms[2].type, esi::SmType::ProcessOut);
  EXPECT_EQ(d.description.sms[2].default_size, 1u);
}

TEST(EsiDevice, AnalogDictionaryFromEsi) {
  auto d = load("RC3102");
  ASSERT_TRUE(d.has_coe);
  const auto& od = d.dictionary;
  ASSERT_NE(od.find(0x1C13), nullptr);
  EXPECT_EQ(od.find(0x1C13)->code(), coe::ObjectCode::Array);
  EXPECT_EQ(od.find(0x1C13)->get_u(0), 2u);
  EXPECT_EQ(od.find(0x1C13)->get_u(1), 0x1A00u);
  EXPECT_EQ(od.find(0x1C13)->get_u(2), 0x1A01u);
  EXPECT_TRUE(od.find(0x1C13)->entry(1)->access & coe::access::kWritePreOp);
  EXPECT_FALSE(od.find(0x1C13)->entry(1)->access & coe::access::kWriteOp);
  const auto* ai = od.find(0x6000);
  ASSERT_NE(ai, nullptr);
  EXPECT_EQ(ai->code(), coe::ObjectCode::Record);
  EXPECT_EQ(ai->entry(0x11)->data_type, static_cast<uint16_t>(coe::DataType::Integer16));
  EXPECT_EQ(ai->entry(0x11)->bit_offset, 32u);
  EXPECT_TRUE(ai->entry(0x11)->access & coe::access::kTxPdoMappable);
  EXPECT_EQ(od.find(0x8000)->get_u(0), 5u);
  EXPECT_TRUE(od.find(0x8000)->entry(0)->access & coe::access::kBackup);
  EXPECT_EQ(od.find(0x1008)->get_string(0), "RC3102");
  // Derived from the ESI: identity and mapping objects.
  EXPECT_EQ(od.find(0x1018)->get_u(2), 0x3102u);
  EXPECT_EQ(od.find(0x1A01)->get_u(4), 0x60101110u);
  EXPECT_EQ(d.description.sms[3].default_size, 8u);  // 2 x (1+1+14+16) bits
  ASSERT_EQ(d.description.dc_modes.size(), 2u);
  EXPECT_EQ(d.description.dc_modes[1].assign_activate, 0x0300u);
  auto info = esi::parse_sii(esi::encode_sii(d.description).span());
  EXPECT_EQ(info.mailbox_protocol, esi::sii::kProtoCoE);
  EXPECT_EQ(info.standard_receive_offset, 0x1000u);
}

// One precise error: file, line, reason.
void expect_error(const std::string& xml, size_t line, const std::string& reason_part,
                  const DeviceSelector& sel = DeviceSelector{}) {
  try {
    parse_esi_device(xml, "bad.xml", sel);
    FAIL() << "no error for " << reason_part;
  } catch (const FileError& e) {
    EXPECT_EQ(e.file(), "bad.xml");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(e.reason().find(reason_part), std::string::npos) << e.what();
  }
}

std::string wrap(const std::string& device) {
  return "<EtherCATInfo>\n<Vendor><Id>#x1</Id></Vendor>\n<Descriptions><Devices>\n" + device +
         "</Devices></Descriptions></EtherCATInfo>\n";
}

TEST(EsiDeviceErrors, MissingDevice) {
  expect_error(wrap("<Device><Type ProductCode=\"#x1\">A</Type></Device>\n"), 3,
               "no <Device> matches name \"B\"", DeviceSelector::named("B"));
}

TEST(EsiDeviceErrors, UnknownDataType) {
  expect_error(wrap("<Device><Type>A</Type>\n"
                    "<Sm StartAddress=\"#x1000\" ControlByte=\"#x20\">Inputs</Sm>\n"
                    "<TxPdo Sm=\"0\"><Index>#x1A00</Index>\n"
                    "<Entry><Index>#x6000</Index><SubIndex>1</SubIndex><BitLen>8</BitLen>\n"
                    "<DataType>FOO8</DataType></Entry></TxPdo></Device>\n"),
               8, "unknown data type \"FOO8\"");
}

TEST(EsiDeviceErrors, PdoBeyondSmSize) {
  expect_error(wrap("<Device><Type>A</Type>\n"
                    "<Sm StartAddress=\"#x1000\" ControlByte=\"#x20\" MaxSize=\"1\">Inputs</Sm>\n"
                    "<TxPdo Sm=\"0\"><Index>#x1A00</Index>\n"
                    "<Entry><Index>#x6000</Index><SubIndex>1</SubIndex><BitLen>16</BitLen>\n"
                    "<DataType>UINT</DataType></Entry></TxPdo></Device>\n"),
               5, "need 2 bytes, more than MaxSize 1");
}

TEST(EsiDeviceErrors, ContradictoryBitLength) {
  expect_error(wrap("<Device><Type>A</Type>\n"
                    "<Sm StartAddress=\"#x1000\" ControlByte=\"#x20\">Inputs</Sm>\n"
                    "<TxPdo Sm=\"0\"><Index>#x1A00</Index>\n"
                    "<Entry><Index>#x6000</Index><SubIndex>1</SubIndex>\n<BitLen>8</BitLen>\n"
                    "<DataType>UINT</DataType></Entry></TxPdo></Device>\n"),
               8, "<BitLen> 8 contradicts UINT");
}

// ETG.5001 modular device: served as its device-level description says (the default module
// configuration); the <Slots>/<Modules> catalogue is not applied (docs/LINE.md).
TEST(EsiDevice, ModularDeviceAsItsDeviceLevelDescription) {
  const auto dev = load("RC5001");
  EXPECT_TRUE(dev.has_coe);
  EXPECT_TRUE(dev.description.rx_pdos.empty());
  EXPECT_TRUE(dev.description.tx_pdos.empty());
}

// ETG.5001 with a chosen module list: each module's objects and PDOs at its slot position
// (SlotIndexIncrement 0x10, SlotPdoIncrement 1), the ident lists 0xF030/0xF050 naming them.
DeviceSelector with_modules(std::vector<std::string> refs, const char* device = "RC5001") {
  DeviceSelector s = DeviceSelector::named(device);
  s.modules.emplace();
  size_t line = 10;
  for (auto& r : refs) s.modules->push_back({r, "line.yaml", line++});
  return s;
}

TEST(EsiDevice, ModularDeviceWithChosenModules) {
  const auto dev = load_esi_device(kFile, with_modules({"RM-DI4", "0x00000002", "#x1"}));
  ASSERT_EQ(dev.module_idents, (std::vector<uint32_t>{1, 2, 1}));
  ASSERT_EQ(dev.description.tx_pdos.size(), 2u);
  EXPECT_EQ(dev.description.tx_pdos[0].index, 0x1A00);
  EXPECT_EQ(dev.description.tx_pdos[1].index, 0x1A02);
  EXPECT_EQ(dev.description.tx_pdos[1].entries[0].index, 0x6020);
  ASSERT_EQ(dev.description.rx_pdos.size(), 1u);
  EXPECT_EQ(dev.description.rx_pdos[0].index, 0x1601);
  EXPECT_EQ(dev.description.rx_pdos[0].entries[3].index, 0x7010);
  const auto& od = dev.dictionary;
  EXPECT_NE(od.find(0x6000), nullptr);
  EXPECT_NE(od.find(0x7010), nullptr);
  EXPECT_NE(od.find(0x6020), nullptr);
  EXPECT_EQ(od.find(0x6010), nullptr);
  EXPECT_EQ(od.find(0x7000), nullptr);
  for (uint16_t list : {uint16_t{0xF030}, uint16_t{0xF050}}) {
    const auto* o = od.find(list);
    ASSERT_NE(o, nullptr);
    EXPECT_EQ(o->sub0(), 3);
    EXPECT_EQ(o->get_u(1), 1u);
    EXPECT_EQ(o->get_u(2), 2u);
    EXPECT_EQ(o->get_u(3), 1u);
  }
  const auto* assign = od.find(0x1C13);
  ASSERT_NE(assign, nullptr);
  EXPECT_EQ(assign->sub0(), 2);
  EXPECT_EQ(assign->get_u(2), 0x1A02u);
  // SII: SM2 one byte of outputs, SM3 two bytes of inputs.
  EXPECT_EQ(dev.description.sms[2].default_size, 1);
  EXPECT_EQ(dev.description.sms[3].default_size, 2);
}

void expect_module_error(std::vector<std::string> refs, size_t line, const std::string& part,
                         const char* device = "RC5001") {
  try {
    load_esi_device(kFile, with_modules(std::move(refs), device));
    FAIL() << "expected an error containing " << part;
  } catch (const FileError& e) {
    EXPECT_EQ(e.file(), "line.yaml") << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
  }
}

TEST(EsiDeviceErrors, UnknownModule) {
  expect_module_error({"RM-DI4", "RM-AI8"}, 11, "unknown module \"RM-AI8\"");
}

TEST(EsiDeviceErrors, ModuleNotAllowedInItsSlot) {
  expect_module_error({"RM-PS"}, 10,
                      "module 0x00000003 (RM-PS) is not allowed in slot position 1: slot "
                      "\"Slot\" takes 0x00000001, 0x00000002");
}

TEST(EsiDeviceErrors, MoreModulesThanSlots) {
  expect_module_error({"RM-DI4", "RM-DI4", "RM-DI4", "RM-DI4", "RM-DO4"}, 14,
                      "more than the device's 4 slots");
}

// ETG.2000 SlotGroups and ModuleClass (RC5002): group 0 takes class "DI" modules, group 1
// RM-DO4. DependOnSlot indices move by the position within the group x SlotIndexIncrement
// (0x10) / SlotPdoIncrement (1), DependOnSlotGroup ones by SlotGroup x SlotGroupIndexIncrement
// (0x100) / SlotGroupPdoIncrement (0x20). The device-level per-slot lists follow: 0x3000 (held
// the default configuration's idents) gets the chosen idents, 0xF010 the modules' ProfileNo.
TEST(EsiDevice, SlotGroupsAndModuleClass) {
  const auto dev =
      load_esi_device(kFile, with_modules({"RM-DI4", "RM-DI4", "RM-DO4", "RM-DO4"}, "RC5002"));
  ASSERT_EQ(dev.module_idents, (std::vector<uint32_t>{1, 1, 2, 2}));
  const auto& d = dev.description;
  ASSERT_EQ(d.tx_pdos.size(), 2u);
  EXPECT_EQ(d.tx_pdos[0].index, 0x1A00);
  EXPECT_EQ(d.tx_pdos[1].index, 0x1A01);
  EXPECT_EQ(d.tx_pdos[1].entries[0].index, 0x6010);
  ASSERT_EQ(d.rx_pdos.size(), 2u);
  EXPECT_EQ(d.rx_pdos[0].index, 0x1620);
  EXPECT_EQ(d.rx_pdos[0].entries[0].index, 0x7100);
  EXPECT_EQ(d.rx_pdos[1].index, 0x1621);
  EXPECT_EQ(d.rx_pdos[1].entries[3].index, 0x7110);
  const auto& od = dev.dictionary;
  for (uint16_t i : {0x6000, 0x6010, 0x7100, 0x7110, 0x1620, 0x1621})
    EXPECT_NE(od.find(i), nullptr) << std::hex << i;
  for (uint16_t i : {0x7000, 0x7010, 0x6020, 0x1600})
    EXPECT_EQ(od.find(i), nullptr) << std::hex << i;
  const auto* mapping = od.find(0x1621);
  ASSERT_NE(mapping, nullptr);
  EXPECT_EQ(mapping->get_u(1), 0x71100101u);
  auto list = [&](uint16_t index) {
    std::vector<uint64_t> v;
    const auto* o = od.find(index);
    if (o)
      for (uint8_t i = 1; i <= o->sub0(); ++i) v.push_back(o->get_u(i));
    return v;
  };
  EXPECT_EQ(list(0xF050), (std::vector<uint64_t>{1, 1, 2, 2}));
  EXPECT_EQ(list(0xF030), (std::vector<uint64_t>{1, 1, 2, 2}));
  EXPECT_EQ(list(0x3000), (std::vector<uint64_t>{1, 1, 2, 2}));
  EXPECT_EQ(list(0xF010), (std::vector<uint64_t>{1101, 1101, 1102, 1102}));
  EXPECT_EQ(od.find(0x3000)->name(), "Module Ident Map");
  EXPECT_EQ(list(0x1C12), (std::vector<uint64_t>{0x1620, 0x1621}));
  EXPECT_EQ(d.sms[2].default_size, 2);
  EXPECT_EQ(d.sms[3].default_size, 2);
}

TEST(EsiDeviceErrors, ModuleOfAnotherClassInASlotGroup) {
  expect_module_error({"RM-DO4"}, 10,
                      "module 0x00000002 (RM-DO4) is not allowed in slot position 1: slot "
                      "\"Input group\" takes class \"DI\" and needs 1 module(s)",
                      "RC5002");
  expect_module_error({"RM-DI4", "RM-PS"}, 11,
                      "module 0x00000003 (RM-PS) is not allowed in slot position 2: slot "
                      "\"Input group\" takes class \"DI\"; slot \"Output group\" takes 0x00000002",
                      "RC5002");
  expect_module_error({"RM-DI4", "RM-DI4", "RM-DI4"}, 12,
                      "module 0x00000001 (RM-DI4) is not allowed in slot position 3: slot "
                      "\"Input group\" takes class \"DI\" (full: MaxInstances 2); slot "
                      "\"Output group\" takes 0x00000002",
                      "RC5002");
}

// A mailbox device with FoE and no CoE (RC6001): accepted, the SII announces FoE only.
TEST(EsiDevice, FoeWithoutCoe) {
  const auto dev = load("RC6001");
  EXPECT_FALSE(dev.has_coe);
  EXPECT_TRUE(dev.description.foe);
  const auto img = esi::encode_sii(dev.description).bytes;
  EXPECT_EQ(img[0x1C * 2] | (img[0x1C * 2 + 1] << 8), 0x0008);
}

TEST(EsiDeviceErrors, NotXml) {
  expect_error("<EtherCATInfo>\n<Vendor>", 2, "not well-formed");
}

}  // namespace
}  // namespace rackcat::device
