// apps/rack_slave: RackSlave adapts one rack (mdp::Device + modules::Rack) to the ESC's
// ecat::Application. These tests drive it through that interface alone, as the ESC does.
#include "apps/rack_slave/rack_slave.hpp"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "apps/rack_slave/rack_loading.hpp"
#include "mdp/firmware_image.hpp"
#include "tests/mdp/sdo_client.hpp"

namespace rackcat::apps {
namespace {

using rackcat::EsmState;

class RackSlaveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rackcat-test-rack-slave-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  mdp::RackConfig default_rack() {
    auto config = load_rack_or_report("");
    EXPECT_TRUE(config.has_value());
    return *config;
  }

  std::filesystem::path dir_;
};

// INIT -> PREOP as the ESC does it: ask, then report the change. SDO needs PREOP.
void to_preop(RackSlave& slave) {
  ASSERT_EQ(slave.on_state_request(EsmState::Init, EsmState::PreOp), 0);
  slave.on_state_changed(EsmState::Init, EsmState::PreOp);
}

// The restart handler counts in `restarts` (the ESC restart that follows a device reset).
void count_restarts(RackSlave& slave, int& restarts) {
  slave.set_restart_handler([&slave, &restarts] {
    slave.finish_device_reset();
    ++restarts;
  });
}

// 0xFBF0:01 device reset with its signature "reset" (docs/MDP.md command table): 0 or the SDO
// abort code.
uint32_t request_device_reset(mdp::testing::SdoClient& sdo) {
  const std::vector<uint8_t> reset{0x74, 0x65, 0x73, 0x65, 0x72, 0x00};
  return sdo.download(0xFBF0, 1, reset);
}

// The reset runs on the device's parameter thread; the ESC polls the mailbox each cycle. The
// restart comes on the poll after the device has reset (SM1 free: the answer was read). Polls
// until then (5 s at most).
void poll_until_restarted(RackSlave& slave, const int& restarts) {
  std::array<uint8_t, 128> reply{};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (restarts == 0 && std::chrono::steady_clock::now() < deadline) {
    slave.coe_mailbox().poll(reply);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

uint32_t sii_u32(std::span<const uint8_t> sii,
                 size_t word) {  // little-endian u32 at a word address
  return static_cast<uint32_t>(sii[2 * word]) | (static_cast<uint32_t>(sii[2 * word + 1]) << 8) |
         (static_cast<uint32_t>(sii[2 * word + 2]) << 16) |
         (static_cast<uint32_t>(sii[2 * word + 3]) << 24);
}

TEST_F(RackSlaveTest, TheSiiCarriesTheDeviceIdentityAndThePositionInTheSerial) {
  const mdp::RackConfig config = default_rack();
  RackSlave first(config, dir_.string(), 0);
  RackSlave third(config, dir_.string(), 2);
  to_preop(first);
  to_preop(third);
  // SII words 0x08..0x0F: vendor, product, revision, serial (ETG.2010 Table 2) = 0x1018:01..04.
  mdp::testing::SdoClient sdo(first.device());
  EXPECT_EQ(sii_u32(first.eeprom(), 0x08), sdo.read_u(0x1018, 1));
  EXPECT_EQ(sii_u32(first.eeprom(), 0x0A), sdo.read_u(0x1018, 2));
  EXPECT_EQ(sii_u32(first.eeprom(), 0x0E), config.control.serial);
  EXPECT_EQ(sii_u32(third.eeprom(), 0x0E), config.control.serial + 2);
  mdp::testing::SdoClient sdo3(third.device());
  EXPECT_EQ(sdo3.read_u(0x1018, 4), config.control.serial + 2);
}

TEST_F(RackSlaveTest, EachPositionHasItsOwnStateDirectory) {
  const mdp::RackConfig config = default_rack();
  RackSlave first(config, dir_.string(), 0);
  RackSlave second(config, dir_.string(), 1);
  EXPECT_EQ(std::filesystem::path(first.device().state_dir()), dir_);
  EXPECT_EQ(std::filesystem::path(second.device().state_dir()), dir_ / "slave-1");
}

TEST_F(RackSlaveTest, ProcessDataSizesAreTheDevicesPdoAssignment) {
  RackSlave slave(default_rack(), dir_.string(), 0);
  const ecat::ProcessDataSizes sizes = slave.process_data_sizes();
  EXPECT_EQ(sizes.outputs, slave.device().output_bytes());
  EXPECT_EQ(sizes.inputs, slave.device().input_bytes());
  EXPECT_GT(sizes.inputs, 0);
}

TEST_F(RackSlaveTest, MailboxRequestsReachTheDevicesSdoServer) {
  RackSlave slave(default_rack(), dir_.string(), 0);
  to_preop(slave);
  // The mailbox data the firmware hands the CoE protocol: CoE header (SDO request, ETG.1000.6
  // §5.6.1), SDO upload initiate 0x40 of 0x1018:02 (§5.6.2.2).
  const std::array<uint8_t, 10> data{0x00, 0x20, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0};
  ecat::MailboxRequest request;
  request.data = data;
  request.capacity = 122;
  request.state = EsmState::PreOp;
  std::array<uint8_t, 122> reply{};
  const mailbox::Answer answer = slave.coe_mailbox().on_request(request, reply);
  ASSERT_EQ(answer.error, mailbox::Error::None);
  ASSERT_GE(answer.length, 10u);
  EXPECT_EQ(reply[1] >> 4, 0x3);                                // SDO response
  EXPECT_EQ(reply[2] & 0xE0, 0x40);                             // upload initiate response
  EXPECT_EQ(sii_u32(reply, 3), sii_u32(slave.eeprom(), 0x0A));  // bytes 6..9 = product code
}

TEST_F(RackSlaveTest, StateChangesReachTheDevice) {
  RackSlave slave(default_rack(), dir_.string(), 0);
  to_preop(slave);
  EXPECT_EQ(slave.device().state(), EsmState::PreOp);
  slave.on_state_changed(EsmState::PreOp, EsmState::Init);
  EXPECT_EQ(slave.device().state(), EsmState::Init);
}

TEST_F(RackSlaveTest, DeviceResetRestartsTheEscOnceTheAnswerIsRead) {
  RackSlave slave(default_rack(), dir_.string(), 0);
  int restarts = 0;
  count_restarts(slave, restarts);
  to_preop(slave);
  mdp::testing::SdoClient sdo(slave.device());
  EXPECT_EQ(request_device_reset(sdo), 0u);
  EXPECT_EQ(restarts, 0);
  poll_until_restarted(slave, restarts);
  EXPECT_EQ(restarts, 1);
  std::array<uint8_t, 128> reply{};
  slave.coe_mailbox().poll(reply);
  EXPECT_EQ(restarts, 1);  // once per reset
}

// Issue 17: a firmware installed (over FoE, docs/FOE.md) since power-on runs after the device
// reset 0xFBF0; the SII image the application offers carries its revision in word 0x0C
// (ETG.2010 Table 2), the same value as 0x1018:03.
TEST_F(RackSlaveTest, DeviceResetPutsTheNewFirmwareRevisionIntoTheSii) {
  RackSlave slave(default_rack(), dir_.string(), 0);
  const auto& cm = slave.device().config().control;
  const uint32_t old_revision = cm.revision;
  ASSERT_EQ(sii_u32(slave.eeprom(), 0x0C), old_revision);
  std::string error;
  const auto file =
      mdp::pack_firmware({cm.vendor_id, cm.product_code, 0x00020001, "2.00.1", "7a"}, {}, error);
  ASSERT_TRUE(file) << error;
  std::ofstream(dir_ / "firmware.rfw", std::ios::binary)
      .write(reinterpret_cast<const char*>(file->data()),
             static_cast<std::streamsize>(file->size()));
  int restarts = 0;
  count_restarts(slave, restarts);
  to_preop(slave);
  mdp::testing::SdoClient sdo(slave.device());
  EXPECT_EQ(request_device_reset(sdo), 0u);
  poll_until_restarted(slave, restarts);
  ASSERT_EQ(restarts, 1);
  EXPECT_EQ(sii_u32(slave.eeprom(), 0x0C), 0x00020001u);
  EXPECT_EQ(sdo.read_u(0x1018, 3), 0x00020001u);
}

}  // namespace
}  // namespace rackcat::apps
