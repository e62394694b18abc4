// Issue 15 item 6: Detect Modules (0xF002) and the device reset (0xFBF0) with Detect Modules
// Override 0 and RIM 2 offline leave a consistent dictionary (mdp/module_enumeration.hpp, guide
// §4.2 Table 23, §2.3, ETG.5001.1): 0xF050 detected, 0x3000 ident map, the default 0xF030
// configured list and the default 0x1C12/0x1C13 assignment describe the same modules, so
// PREOP->SAFEOP is accepted; a configured list of the master's that differs is refused with AL
// status 0x0070. Driven through RackSlave (the ESC's application interface) and SDO.
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <thread>
#include <vector>

#include "apps/rack_slave/rack_loading.hpp"
#include "apps/rack_slave/rack_slave.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "tests/mdp/sdo_client.hpp"

namespace rackcat::apps {
namespace {

using rackcat::EsmState;

// Default rack: RIM 1 slots 1..19 = modules 1..19, RIM 2 slots 1..8 = modules 20..27.
constexpr size_t kRim1Modules = 19, kAllModules = 27;
const std::vector<uint8_t> kScan{0x73, 0x63, 0x61, 0x6E};
const std::vector<uint8_t> kSave{0x73, 0x61, 0x76, 0x65};
const std::vector<uint8_t> kDeviceReset{0x74, 0x65, 0x73, 0x65, 0x72, 0x00};

class DetectModules : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = std::filesystem::temp_directory_path() /
          ("rackcat-test-detect-" + std::to_string(::getpid()) + "-" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    slave = std::make_unique<RackSlave>(*load_rack_or_report(""), dir.string(), 0);
    slave->set_restart_handler([this] { ++restarts; });
    ASSERT_EQ(slave->on_state_request(EsmState::Init, EsmState::PreOp), 0);
    slave->on_state_changed(EsmState::Init, EsmState::PreOp);
    sdo = std::make_unique<mdp::testing::SdoClient>(slave->device());
  }
  void TearDown() override {
    sdo.reset();
    slave.reset();
    std::filesystem::remove_all(dir);
  }

  std::vector<uint64_t> list(uint16_t index) {
    std::vector<uint64_t> v;
    const uint64_t n = sdo->read_u(index, 0);
    for (uint8_t s = 1; s <= n; ++s) v.push_back(sdo->read_u(index, s));
    return v;
  }
  // Modules (1-based) whose PDOs 0x1C12 (rx) / 0x1C13 assign.
  std::vector<uint64_t> assigned_modules(bool rx) {
    std::vector<uint64_t> out;
    for (uint64_t pdo : list(rx ? 0x1C12 : 0x1C13)) {
      out.push_back(pdo - (rx ? mdp::sm::kRxPdoBase : mdp::sm::kTxPdoBase) + 1);
    }
    return out;
  }
  void wait(uint16_t index) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (sdo->read_u(index, 2) == 255 && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  void unplug_rim2_with_override_0() {
    ASSERT_EQ(sdo->write_u(0x2000, 0x0B, 0, 1), 0u);  // Detect Modules Override 0 (PREOP)
    slave->rack().set_rim_state(2, modules::RimState::Offline);
  }
  void expect_consistent(size_t modules) {
    const auto detected = list(0xF050);
    EXPECT_EQ(detected.size(), modules);
    EXPECT_EQ(list(0x3000), detected);
    EXPECT_EQ(list(0xF030), detected);
    for (bool rx : {true, false}) {
      for (uint64_t m : assigned_modules(rx)) EXPECT_LE(m, modules) << (rx ? "0x1C12" : "0x1C13");
    }
    EXPECT_FALSE(assigned_modules(false).empty());
    EXPECT_EQ(slave->on_state_request(EsmState::PreOp, EsmState::SafeOp), 0);
  }

  std::filesystem::path dir;
  std::unique_ptr<RackSlave> slave;
  std::unique_ptr<mdp::testing::SdoClient> sdo;
  int restarts = 0;
};

TEST_F(DetectModules, ScanWithARimOfflineLeavesEveryListConsistent) {
  unplug_rim2_with_override_0();
  ASSERT_EQ(sdo->download(0xF002, 1, kScan), 0u);
  expect_consistent(kRim1Modules);
  // The process data follows the new assignment: no RIM 2 module in it.
  const auto sizes = slave->process_data_sizes();
  EXPECT_GT(sizes.inputs, 0);
  // RIM 2 back and a new scan: all modules again.
  slave->rack().set_rim_state(2, modules::RimState::Online);
  ASSERT_EQ(sdo->download(0xF002, 1, kScan), 0u);
  expect_consistent(kAllModules);
  EXPECT_GT(slave->process_data_sizes().inputs, sizes.inputs);
}

TEST_F(DetectModules, AnAssignmentOfTheMastersIsKept) {
  // The master assigns only module 1's RxPDO; a scan does not overwrite it.
  ASSERT_EQ(sdo->write_u(0x1C12, 0, 0, 1), 0u);
  ASSERT_EQ(sdo->write_u(0x1C12, 1, mdp::sm::kRxPdoBase, 2), 0u);
  ASSERT_EQ(sdo->write_u(0x1C12, 0, 1, 1), 0u);
  unplug_rim2_with_override_0();
  ASSERT_EQ(sdo->download(0xF002, 1, kScan), 0u);
  EXPECT_EQ(assigned_modules(true), std::vector<uint64_t>{1});
  for (uint64_t m : assigned_modules(false)) EXPECT_LE(m, kRim1Modules);
}

TEST_F(DetectModules, AConfiguredListThatDiffersIsRefusedWith0x0070) {
  unplug_rim2_with_override_0();
  ASSERT_EQ(sdo->download(0xF002, 1, kScan), 0u);
  // A configured list the master wrote earlier (here straight into the dictionary, as a stored
  // parameter set of the full rack would be): 27 modules against 19 detected.
  coe::Object& configured = *slave->device().dictionary().find(0xF030);
  configured.image()[0] = static_cast<uint8_t>(kAllModules);
  for (uint8_t s = 1; s <= kAllModules; ++s) {
    configured.set_u(s, slave->device().modules()[s - 1].card->module_ident);
  }
  EXPECT_EQ(slave->on_state_request(EsmState::PreOp, EsmState::SafeOp), 0x0070);
  // sub 0 = 0 switches the check off (ETG.5001.1).
  ASSERT_EQ(sdo->write_u(0xF030, 0, 0, 1), 0u);
  EXPECT_EQ(slave->on_state_request(EsmState::PreOp, EsmState::SafeOp), 0);
}

TEST_F(DetectModules, DeviceResetWithARimOfflineEnumeratesWhatIsDetected) {
  ASSERT_EQ(sdo->write_u(0x2000, 0x0B, 0, 1), 0u);
  ASSERT_EQ(sdo->download(0xFBF2, 1, kSave), 0u);  // Override 0 survives the reset
  wait(0xFBF2);
  slave->rack().set_rim_state(2, modules::RimState::Offline);
  ASSERT_EQ(sdo->download(0xFBF0, 1, kDeviceReset), 0u);
  std::array<uint8_t, 128> reply{};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (restarts == 0 && std::chrono::steady_clock::now() < deadline) {
    slave->coe_mailbox().poll(reply);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_EQ(restarts, 1);
  EXPECT_EQ(sdo->read_u(0x2000, 0x0B), 0u);
  expect_consistent(kRim1Modules);
}

}  // namespace
}  // namespace rackcat::apps
