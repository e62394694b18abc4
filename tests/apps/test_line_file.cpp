// Line file: a good line and one precise FILE:LINE error per bad line file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "apps/line/line_file.hpp"
#include "device/esi_error.hpp"

namespace rackcat::apps {
namespace {

namespace fs = std::filesystem;

class LineFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rackcat-line-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    fs::copy_file(fs::path(RACKCAT_DEVICE_TEST_DATA) / "rackcat-test-devices.xml",
                  dir_ / "devices.xml", fs::copy_options::overwrite_existing);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& text) {
    const auto p = dir_ / "line.yaml";
    std::ofstream(p) << text;
    return p.string();
  }
  void expect_error(const std::string& text, size_t line, const std::string& part) {
    const auto path = write(text);
    try {
      load_line_file(path);
      FAIL() << "no error for " << part;
    } catch (const device::FileError& e) {
      EXPECT_EQ(e.file(), path) << e.what();
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
    }
  }
  fs::path dir_;
};

TEST_F(LineFileTest, DevicesCountsAliasesWiring) {
  auto line =
      load_line_file(write("devices:\n"
                           "  - {esi: devices.xml, device: RC1100, alias: 0x100}\n"
                           "  - {esi: devices.xml, device: RC1008, name: di, count: 2}\n"
                           "  - {esi: devices.xml, device: RC2008, name: do}\n"
                           "wiring:\n"
                           "  - {from: do, to: di, bits: 8}\n"
                           "  - {from: do, to: 2, bits: 4, to_bit: 4}\n"));
  ASSERT_EQ(line.devices.size(), 4u);
  EXPECT_EQ(line.devices[0].esi->description.config.station_alias, 0x100);
  EXPECT_EQ(line.devices[2].name, "di#1");
  EXPECT_EQ(line.devices[2].esi->description.serial, 1u);
  ASSERT_EQ(line.wiring.size(), 2u);
  EXPECT_EQ(line.wiring[0].from, 3u);
  EXPECT_EQ(line.wiring[0].to, 1u);
  EXPECT_EQ(line.wiring[1].line, 7u);
}

// ETG.5001 modular device with the modules of its slots named in the line file.
TEST_F(LineFileTest, ModularDeviceWithItsModules) {
  auto line =
      load_line_file(write("devices:\n"
                           "  - esi: devices.xml\n"
                           "    device: RC5001\n"
                           "    modules: [RM-DO4, 0x00000001]\n"));
  ASSERT_EQ(line.devices.size(), 1u);
  EXPECT_EQ(line.devices[0].esi->module_idents, (std::vector<uint32_t>{2, 1}));
  EXPECT_NE(line.devices[0].esi->dictionary.find(0x6010), nullptr);
}

TEST_F(LineFileTest, UnknownModuleNamesItsLine) {
  expect_error(
      "devices:\n"
      "  - esi: devices.xml\n"
      "    device: RC5001\n"
      "    modules:\n"
      "      - RM-DI4\n"
      "      - RM-AI8\n",
      6, "unknown module \"RM-AI8\"");
}

TEST_F(LineFileTest, ModuleNotAllowedInTheSlot) {
  expect_error(
      "devices:\n"
      "  - esi: devices.xml\n"
      "    device: RC5001\n"
      "    modules:\n"
      "      - RM-PS\n",
      5, "is not allowed in slot position 1");
}

// Signal sources (modules/signals) on an ESI device's input fields.
TEST_F(LineFileTest, SignalSourcesOnInputs) {
  auto line = load_line_file(write(
      "devices:\n"
      "  - esi: devices.xml\n"
      "    product_code: 0x3102\n"
      "    count: 2\n"
      "    inputs:\n"
      "      - {bit: 16, bits: 16, source: sine, amplitude: 1000, period_s: 2}\n"
      "      - {bit: 0, bits: 1, source: constant, value: 1}\n"
      "  - esi: devices.xml\n"
      "    device: RC1008\n"
      "    inputs: [{bits: 8, source: ramp, from: 0, to: 255, period_s: 1, signed: false}]\n"));
  ASSERT_EQ(line.devices.size(), 3u);
  ASSERT_EQ(line.devices[0].inputs.size(), 2u);
  const auto& sine = line.devices[0].inputs[0];
  EXPECT_EQ(sine.bit, 16u);
  EXPECT_EQ(sine.line, 6u);
  // Each copy has its own source.
  EXPECT_NE(line.devices[1].inputs[0].source, sine.source);
  EXPECT_EQ(sine.code(-1000.4), static_cast<uint64_t>(-1000) & 0xFFFFFFFFFFFFFFFF);
  EXPECT_EQ(sine.code(1e9), 32767u);
  EXPECT_EQ(static_cast<int64_t>(sine.code(-1e9)), -32768);
  EXPECT_EQ(line.devices[0].inputs[1].code(0.6), 1u);
  EXPECT_EQ(line.devices[0].inputs[1].code(0.4), 0u);
  const auto& ramp = line.devices[2].inputs[0];
  EXPECT_EQ(ramp.code(300), 255u);
  EXPECT_EQ(ramp.code(-3), 0u);
}

TEST_F(LineFileTest, SignalSourceErrors) {
  const std::string head = "devices:\n  - esi: devices.xml\n    device: RC1008\n    inputs:\n";
  expect_error(head + "      - {bits: 8, source: wobble}\n", 5, "source wobble");
  expect_error(head + "      - {bit: 4, bits: 8, source: constant, value: 1}\n", 5,
               "input bits 4..11 but the device has 8 input bits");
  expect_error(head + "      - {bits: 8, source: loopback}\n", 5, "use wiring:");
  expect_error(head + "      - {bits: 8, source: sine, amplitude: x}\n", 5, "source sine");
  expect_error(head +
                   "      - {bits: 4, source: constant, value: 1}\n"
                   "      - {bit: 2, bits: 4, source: constant, value: 1}\n",
               6, "already driven by the source on line 5");
}

TEST_F(LineFileTest, MissingEsiDevice) {
  // The ESI's own error, naming the ESI file.
  const auto path = write("devices:\n  - {esi: devices.xml, device: NOPE}\n");
  try {
    load_line_file(path);
    FAIL();
  } catch (const device::FileError& e) {
    EXPECT_NE(e.file().find("devices.xml"), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("no <Device> matches name \"NOPE\""), std::string::npos);
  }
}

TEST_F(LineFileTest, CyclicLoopback) {
  // a's outputs drive b's inputs and b's outputs drive a's: a cycle through the wiring.
  expect_error(
      "devices:\n"
      "  - {esi: devices.xml, device: RC4004, name: a}\n"
      "  - {esi: devices.xml, device: RC4004, name: b}\n"
      "wiring:\n"
      "  - {from: a, to: b, bits: 4}\n"
      "  - {from: b, to: a, bits: 4}\n",
      6, "wiring cycle");  // the wire that closes it
}

TEST_F(LineFileTest, WireBeyondProcessData) {
  expect_error(
      "devices:\n"
      "  - {esi: devices.xml, device: RC2008, name: do}\n"
      "  - {esi: devices.xml, device: RC1008, name: di}\n"
      "wiring:\n"
      "  - {from: do, to: di, bits: 9}\n",
      5, "wire reads output bits 0..8 but the device has 8 output bits");
}

TEST_F(LineFileTest, DoubleDrivenInput) {
  expect_error(
      "devices:\n"
      "  - {esi: devices.xml, device: RC2008, name: do}\n"
      "  - {esi: devices.xml, device: RC1008, name: di}\n"
      "wiring:\n"
      "  - {from: do, to: di, bits: 8}\n"
      "  - {from: do, to: di, bits: 1, to_bit: 7}\n",
      6, "already driven by the wire on line 5");
}

TEST_F(LineFileTest, FileOutsideTheLineDirectory) {
  expect_error("devices:\n  - {esi: ../devices.xml, device: RC1008}\n", 2, "not below");
}

TEST_F(LineFileTest, UnknownKey) {
  expect_error("devices:\n  - {esi: devices.xml, device: RC1008, colour: red}\n", 2,
               "unknown device key \"colour\"");
}

}  // namespace
}  // namespace rackcat::apps
