// ENI import (ETG.2100): the hand-written ENI of the test line builds the same line as its line
// file, and each bad ENI (or bad ESI behind it) gives one precise FILE:LINE error.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "apps/line/eni_file.hpp"
#include "apps/line/line_file.hpp"
#include "device/esi_error.hpp"
#include "device/generic_device.hpp"

namespace rackcat::apps {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The 1-based line of the first occurrence of `needle` in `text`.
size_t line_of(const std::string& text, const std::string& needle) {
  const size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  return 1 +
         static_cast<size_t>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

void replace(std::string& text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

class EniFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rackcat-eni-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_ / "esi");
    fs::copy_file(fs::path(RACKCAT_DEVICE_TEST_DATA) / "rackcat-test-devices.xml",
                  dir_ / "esi/rackcat-test-devices.xml", fs::copy_options::overwrite_existing);
    fs::copy_file(fs::path(RACKCAT_SOURCE_DIR) / "examples/tiny-rack.yaml",
                  dir_ / "esi/tiny-rack.yaml", fs::copy_options::overwrite_existing);
    eni_ = slurp(fs::path(RACKCAT_APPS_TEST_DATA) / "test-line.eni.xml");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const auto p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  LineFile load(const std::string& text) {
    return load_eni_file(write("line.eni.xml", text), (dir_ / "esi").string());
  }
  // Exactly one error, in `file` (default: the ENI) at `line`, containing `part`.
  void expect_error(const std::string& text, size_t line, const std::string& part,
                    const std::string& file = "line.eni.xml") {
    try {
      load(text);
      FAIL() << "no error for " << part;
    } catch (const device::FileError& e) {
      EXPECT_NE(e.file().find(file), std::string::npos) << e.what();
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
    }
  }

  fs::path dir_;
  std::string eni_;
};

TEST_F(EniFileTest, BuildsTheSameLineAsTheLineFile) {
  const auto from_eni = load(eni_);
  const auto from_line =
      load_line_file(write("esi/line.yaml",
                           "devices:\n"
                           "  - {esi: rackcat-test-devices.xml, device: RC1100, alias: 0x100}\n"
                           "  - {esi: rackcat-test-devices.xml, device: RC1008}\n"
                           "  - {esi: rackcat-test-devices.xml, device: RC2008}\n"
                           "  - {esi: rackcat-test-devices.xml, device: RC3102}\n"
                           "  - {rack: tiny-rack.yaml}\n"));
  ASSERT_EQ(from_eni.devices.size(), 5u);
  ASSERT_EQ(from_line.devices.size(), 5u);
  for (size_t i = 0; i < 4; ++i) {
    const auto& a = *from_eni.devices[i].esi;
    const auto& b = *from_line.devices[i].esi;
    EXPECT_EQ(a.description.vendor_id, b.description.vendor_id) << i;
    EXPECT_EQ(a.description.product_code, b.description.product_code) << i;
    EXPECT_EQ(a.description.revision, b.description.revision) << i;
    EXPECT_EQ(a.description.device_name, b.description.device_name) << i;
    const device::GenericDevice ga(a), gb(b);
    EXPECT_EQ(ga.process_data_sizes().outputs, gb.process_data_sizes().outputs) << i;
    EXPECT_EQ(ga.process_data_sizes().inputs, gb.process_data_sizes().inputs) << i;
    EXPECT_EQ(ga.eeprom().size(), gb.eeprom().size()) << i;
    EXPECT_TRUE(std::equal(ga.eeprom().begin(), ga.eeprom().end(), gb.eeprom().begin())) << i;
  }
  ASSERT_TRUE(from_eni.devices[4].rack);
  EXPECT_EQ(from_eni.devices[4].rack->control.product_code, 0x00464E01u);
  EXPECT_EQ(from_eni.devices[3].name, "Term 4 (RC3102)");
}

// Info/Identification with ADO 0x0012: the station alias, SII word 4 (ETG.2010 Table 2).
TEST_F(EniFileTest, IdentificationBecomesTheStationAlias) {
  const auto line = load(eni_);
  EXPECT_EQ(line.devices[0].esi->description.config.station_alias, 0x100);
  const device::GenericDevice g(*line.devices[0].esi);
  EXPECT_EQ(g.eeprom()[8], 0x00);
  EXPECT_EQ(g.eeprom()[9], 0x01);
}

TEST_F(EniFileTest, IdentificationByAnotherRegister) {
  std::string eni = eni_;
  replace(eni, "<Ado>#x0012</Ado>", "<Ado>#x0134</Ado>");
  expect_error(eni, line_of(eni, "<Ado>#x0134"), "identification by ADO #x0134 is not emulated");
}

// A modular device's modules: the 0xF030 list its CoE init commands download (ETG.5001.1).
std::string modular_eni(const std::string& init_cmds) {
  return "<EtherCATConfig><Config>\n"
         "<Slave><Info><Name>Head</Name><VendorId>3612</VendorId><ProductCode>#x5001</ProductCode>"
         "<RevisionNo>#x10000</RevisionNo></Info>\n"
         "<Mailbox><CoE><InitCmds>\n" +
         init_cmds +
         "</InitCmds></CoE></Mailbox></Slave>\n"
         "</Config></EtherCATConfig>\n";
}

TEST_F(EniFileTest, ModulesFromTheConfiguredModuleIdentList) {
  const std::string cmd =
      "<InitCmd CompleteAccess=\"true\"><Transition>PS</Transition><Index>#xF030</Index>"
      "<SubIndex>0</SubIndex><Data>02000200000001000000</Data></InitCmd>\n";
  const auto line = load(modular_eni(cmd));
  ASSERT_EQ(line.devices.size(), 1u);
  const auto& esi = *line.devices[0].esi;
  EXPECT_EQ(esi.module_idents, (std::vector<uint32_t>{2, 1}));
  EXPECT_NE(esi.dictionary.find(0x7000), nullptr);
  EXPECT_NE(esi.dictionary.find(0x6010), nullptr);
  // Entry by entry, the count last.
  const std::string entries =
      "<InitCmd><Transition>PS</Transition><Index>#xF030</Index><SubIndex>1</SubIndex>"
      "<Data>01000000</Data></InitCmd>\n"
      "<InitCmd><Transition>PS</Transition><Index>#xF030</Index><SubIndex>0</SubIndex>"
      "<Data>01</Data></InitCmd>\n";
  EXPECT_EQ(load(modular_eni(entries)).devices[0].esi->module_idents, (std::vector<uint32_t>{1}));
}

TEST_F(EniFileTest, UnknownModuleInTheConfiguredList) {
  const std::string eni = modular_eni(
      "<InitCmd CompleteAccess=\"true\"><Transition>PS</Transition><Index>#xF030</Index>"
      "<SubIndex>0</SubIndex><Data>010007000000</Data></InitCmd>\n");
  expect_error(eni, line_of(eni, "<InitCmd Complete"), "unknown module \"#x00000007\"");
}

TEST_F(EniFileTest, ConfiguredListWithoutItsEntries) {
  const std::string eni = modular_eni(
      "<InitCmd><Transition>PS</Transition><Index>#xF030</Index><SubIndex>0</SubIndex>"
      "<Data>02</Data></InitCmd>\n");
  expect_error(eni, line_of(eni, "<InitCmd><"), "no init command sets subindex 1");
}

// The analog terminal's init commands assign 0x1A01 alone (0x1C13:01, then the count 1).
void assign_only_1a01(std::string& eni) {
  replace(eni, "<SubIndex>1</SubIndex><Data>001a</Data>",
          "<SubIndex>1</SubIndex><Data>011a</Data>");
  replace(eni,
          "<InitCmd Fixed=\"true\"><Transition>PS</Transition><Comment>download pdo 0x1C13:02 "
          "index</Comment><Timeout>0</Timeout><Ccs>1</Ccs><Index>7187</Index><SubIndex>2</"
          "SubIndex><Data>011a</Data></InitCmd>",
          "");
  replace(eni, "<SubIndex>0</SubIndex><Data>02</Data>", "<SubIndex>0</SubIndex><Data>01</Data>");
}

// Without an assignment in ProcessData, the init commands' assignment becomes the device's
// start-up assignment: 0x1C13, the SII's assigned PDOs and SM3's size.
TEST_F(EniFileTest, TheInitCmdsAssignmentBecomesTheStartUpAssignment) {
  std::string eni = eni_;
  const size_t from = eni.find("<TxPdo Sm=\"3\"><Index>#x1a00</Index>");
  const size_t to = eni.find("</ProcessData>", from);
  eni.erase(from, to - from);
  replace(eni, "<Recv><BitStart>8</BitStart><BitLength>64</BitLength></Recv>", "");
  assign_only_1a01(eni);
  const auto line = load(eni);
  const auto& ai = *line.devices[3].esi;
  EXPECT_EQ(device::GenericDevice(ai).process_data_sizes().inputs, 4u);
  EXPECT_EQ(ai.dictionary.find(0x1C13)->get_u(0), 1u);
  EXPECT_EQ(ai.dictionary.find(0x1C13)->get_u(1), 0x1A01u);
  ASSERT_EQ(ai.description.tx_pdos.size(), 2u);
  EXPECT_EQ(ai.description.tx_pdos[0].index, 0x1A01);
  EXPECT_TRUE(ai.description.tx_pdos[0].assigned);
  EXPECT_FALSE(ai.description.tx_pdos[1].assigned);
  EXPECT_EQ(ai.description.sms[3].default_size, 4);
}

// The init commands contradict the ENI's own process image.
TEST_F(EniFileTest, InitCmdsContradictTheProcessData) {
  std::string eni = eni_;
  replace(eni, "<Recv><BitStart>8</BitStart><BitLength>64</BitLength></Recv>",
          "<Recv><BitStart>8</BitStart><BitLength>32</BitLength></Recv>");
  replace(eni, "<TxPdo Sm=\"3\"><Index>#x1a00</Index>", "<TxPdo><Index>#x1a00</Index>");
  expect_error(eni, line_of(eni, "<Comment>download pdo 0x1C13 count"),
               "the init commands leave #x1C13 = #x1A00, #x1A01 but ProcessData assigns #x1A01");
}

// The master's download would be refused by the device: the SDO abort, at that command.
TEST_F(EniFileTest, InitCmdAssigningAPdoTheDeviceLacks) {
  std::string eni = eni_;
  replace(eni, "<SubIndex>1</SubIndex><Data>001a</Data>",
          "<SubIndex>1</SubIndex><Data>051a</Data>");
  expect_error(eni, line_of(eni, "<Comment>download pdo 0x1C13:01"),
               "InitCmd writes 0x1C13:1 but RC3102 (");
  expect_error(eni, line_of(eni, "<Comment>download pdo 0x1C13:01"),
               "answers SDO abort 0x06020000");
}

// A modular device: the module list (0xF030) and then the assignment of the chosen modules'
// PDOs at their slot indices (RM-DO4 in slot 1, RM-DI4 in slot 2: TxPDO 0x1A01).
TEST_F(EniFileTest, ModuleInitCmdsConfigureTheChosenModules) {
  const std::string modules =
      "<InitCmd CompleteAccess=\"true\"><Transition>PS</Transition><Index>#xF030</Index>"
      "<SubIndex>0</SubIndex><Data>02000200000001000000</Data></InitCmd>\n"
      "<InitCmd><Transition>PS</Transition><Index>#x1C13</Index><SubIndex>0</SubIndex>"
      "<Data>00</Data></InitCmd>\n";
  const auto line =
      load(modular_eni(modules + "<InitCmd><Transition>PS</Transition><Index>#x1C13</Index>"
                                 "<SubIndex>1</SubIndex><Data>011a</Data></InitCmd>\n"
                                 "<InitCmd><Transition>PS</Transition><Index>#x1C13</Index>"
                                 "<SubIndex>0</SubIndex><Data>01</Data></InitCmd>\n"));
  EXPECT_EQ(line.devices[0].esi->dictionary.find(0x1C13)->get_u(1), 0x1A01u);
  const std::string eni = modular_eni(modules +
                                      "<InitCmd><Transition>PS</Transition><Index>#x1C13</Index>"
                                      "<SubIndex>1</SubIndex><Data>001a</Data></InitCmd>\n");
  expect_error(eni, line_of(eni, "<Data>001a"), "answers SDO abort 0x06020000");
}

TEST_F(EniFileTest, TheEnisAssignmentBecomesTheStartUpAssignment) {
  // Only TxPDO 0x1A01 assigned: 4 input bytes, 0x1C13 = {1: 0x1A01}.
  std::string eni = eni_;
  replace(eni, "<Recv><BitStart>8</BitStart><BitLength>64</BitLength></Recv>",
          "<Recv><BitStart>8</BitStart><BitLength>32</BitLength></Recv>");
  replace(eni, "<TxPdo Sm=\"3\"><Index>#x1a00</Index>", "<TxPdo><Index>#x1a00</Index>");
  // The init commands the master sends assign the same (they are replayed and must agree).
  assign_only_1a01(eni);
  const auto line = load(eni);
  const auto& ai = *line.devices[3].esi;
  EXPECT_EQ(device::GenericDevice(ai).process_data_sizes().inputs, 4u);
  const coe::Object* assign = ai.dictionary.find(0x1C13);
  ASSERT_NE(assign, nullptr);
  EXPECT_EQ(assign->get_u(0), 1u);
  EXPECT_EQ(assign->get_u(1), 0x1A01u);
}

TEST_F(EniFileTest, MissingDevice) {
  std::string eni = eni_;
  replace(eni, "<ProductCode>8200</ProductCode>", "<ProductCode>8201</ProductCode>");
  expect_error(eni, line_of(eni, "<Info><Name>Term 3"),
               "no ESI device or rack file in " + (dir_ / "esi").string() +
                   " has vendor #x00000E1C, product code #x00002009, revision #x00010000 "
                   "(\"Term 3 (RC2008)\")");
}

TEST_F(EniFileTest, WrongRevisionNamesTheNearMiss) {
  std::string eni = eni_;
  replace(eni, "<RevisionNo>131072</RevisionNo>", "<RevisionNo>131073</RevisionNo>");
  expect_error(eni, line_of(eni, "<Info><Name>Term 4"),
               "(rackcat-test-devices.xml has revision #x00020000)");
}

TEST_F(EniFileTest, UnknownDataTypeInTheEsiNamesTheEsiLine) {
  std::string esi = slurp(dir_ / "esi/rackcat-test-devices.xml");
  replace(esi, "<Type>UINT</Type><BitSize>16</BitSize><Info><DefaultValue>#x0005",
          "<Type>UINT17</Type><BitSize>16</BitSize><Info><DefaultValue>#x0005");
  write("esi/rackcat-test-devices.xml", esi);
  expect_error(eni_, line_of(esi, "UINT17"), "UINT17", "rackcat-test-devices.xml");
}

TEST_F(EniFileTest, PdoBeyondSmSize) {
  // An ESI whose inputs SM holds 2 bytes, one PDO of 2 bytes assigned, a second one offered;
  // the ENI assigns both (4 bytes).
  write("esi/narrow.xml", R"(<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x00000E1C</Id><Name>rackcat test devices</Name></Vendor>
<Descriptions><Devices><Device Physics="YY">
  <Type ProductCode="#x00007002" RevisionNo="#x1">RC7002</Type><Name>RC7002 narrow input</Name>
  <Fmmu>Inputs</Fmmu>
  <Sm StartAddress="#x1000" ControlByte="#x00" Enable="1" MaxSize="2">Inputs</Sm>
  <TxPdo Sm="0"><Index>#x1A00</Index><Name>A</Name><Entry><Index>#x6000</Index><SubIndex>1</SubIndex><BitLen>16</BitLen><Name>A</Name><DataType>UINT</DataType></Entry></TxPdo>
  <TxPdo><Index>#x1A01</Index><Name>B</Name><Entry><Index>#x6010</Index><SubIndex>1</SubIndex><BitLen>16</BitLen><Name>B</Name><DataType>UINT</DataType></Entry></TxPdo>
</Device></Devices></Descriptions></EtherCATInfo>
)");
  const std::string eni = R"(<?xml version="1.0"?>
<EtherCATConfig><Config>
  <Slave>
    <Info><Name>narrow</Name><VendorId>3612</VendorId><ProductCode>#x7002</ProductCode><RevisionNo>1</RevisionNo></Info>
    <ProcessData>
      <TxPdo Sm="3"><Index>#x1A00</Index><Name>A</Name><Entry><Index>#x6000</Index><SubIndex>1</SubIndex><BitLen>16</BitLen></Entry></TxPdo>
      <TxPdo Sm="3"><Index>#x1A01</Index><Name>B</Name><Entry><Index>#x6010</Index><SubIndex>1</SubIndex><BitLen>16</BitLen></Entry></TxPdo>
    </ProcessData>
  </Slave>
</Config></EtherCATConfig>
)";
  expect_error(eni, 5,
               "the assigned TxPDOs need 4 bytes but SM3 of RC7002 holds at most 2 (MaxSize)");
}

TEST_F(EniFileTest, PdoTheEsiLacks) {
  std::string eni = eni_;
  replace(eni, "<TxPdo Sm=\"3\"><Index>#x1a01</Index>", "<TxPdo Sm=\"3\"><Index>#x1a05</Index>");
  expect_error(eni, line_of(eni, "<TxPdo Sm=\"3\"><Index>#x1a05"),
               "TxPdo #x1A05 is not a PDO of RC3102");
}

TEST_F(EniFileTest, RemappedPdoEntry) {
  std::string eni = eni_;
  replace(eni, "<Entry><Index>#x6010</Index><SubIndex>17</SubIndex><BitLen>16</BitLen>",
          "<Entry><Index>#x6010</Index><SubIndex>18</SubIndex><BitLen>16</BitLen>");
  expect_error(eni, line_of(eni, "<SubIndex>18</SubIndex>"),
               "TxPdo #x1A01 entry 4 differs from the ESI's (#x6010:17, 16 bit)");
}

TEST_F(EniFileTest, ProcessDataLengthContradictsThePdos) {
  std::string eni = eni_;
  replace(eni, "<Send><BitStart>0</BitStart><BitLength>8</BitLength></Send>",
          "<Send><BitStart>0</BitStart><BitLength>16</BitLength></Send>");
  expect_error(eni, line_of(eni, "<BitLength>16</BitLength>"),
               "<Send> BitLength 16 but the assigned RxPDOs have 8 bits");
}

TEST_F(EniFileTest, InitCmdOnAnObjectTheDictionaryLacks) {
  std::string eni = eni_;
  replace(eni, "<Index>#x8000</Index>", "<Index>#x8010</Index>");
  expect_error(eni, line_of(eni, "<Comment>AI Filter"),
               "InitCmd writes #x8010:0 but the dictionary of RC3102");
}

TEST_F(EniFileTest, InitCmdOnAReadOnlyEntry) {
  std::string eni = eni_;
  replace(eni, "<Index>#x8000</Index><SubIndex>0</SubIndex><Data>0500</Data>",
          "<Index>#x1000</Index><SubIndex>0</SubIndex><Data>00000000</Data>");
  expect_error(eni, line_of(eni, "<Comment>AI Filter"), "not writable");
}

TEST_F(EniFileTest, InitCmdOfTheWrongSize) {
  std::string eni = eni_;
  replace(eni, "<Data>0500</Data>", "<Data>050000</Data>");
  expect_error(eni, line_of(eni, "<Comment>AI Filter"),
               "InitCmd writes 3 byte(s) to #x8000:0 (AI Filter) which has 2");
}

TEST_F(EniFileTest, CoeInitCmdsForADeviceWithoutMailbox) {
  std::string eni = eni_;
  replace(
      eni,
      "<ProductCode>4104</ProductCode><RevisionNo>65536</RevisionNo><SerialNo>0</SerialNo></Info>",
      "<ProductCode>4104</ProductCode><RevisionNo>65536</RevisionNo><SerialNo>0</SerialNo></Info>"
      "\n      <Mailbox><CoE><InitCmds><InitCmd><Transition>PS</Transition><Index>#x8000</Index>"
      "<SubIndex>0</SubIndex><Data>00</Data></InitCmd></InitCmds></CoE></Mailbox>");
  expect_error(eni, line_of(eni, "<Mailbox><CoE><InitCmds>"), "has no CoE mailbox");
}

TEST_F(EniFileTest, NotAnEni) {
  expect_error("<EtherCATInfo/>\n", 1, "root element is not <EtherCATConfig> (ETG.2100)");
}

}  // namespace
}  // namespace rackcat::apps
