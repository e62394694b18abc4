// User-mappable PDOs (guide §2.6, §4.8, Appendix A RX/TX column; ETG.1000.6 §5.6.7.4.7 -
// §5.6.7.4.9 for the mapping and assignment rules and their abort codes, Table 11 for AL status
// 0x001D/0x001E): the operator maps 0x2000:0F and a thermocouple's ohms into the user TxPDO in
// PREOP, assigns it, and the values travel in SM3 every cycle.
#include <gtest/gtest.h>

#include <cstring>

#include "mdp/device.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "sdo_client.hpp"

namespace rackcat::mdp {
namespace {

using rackcat::EsmState;
using testing::SdoClient;

constexpr uint32_t kSubZero = 0x06010003;
constexpr uint32_t kNotMappable = 0x06040041;
constexpr uint32_t kPdoLength = 0x06040042;
constexpr uint32_t kIncompatible = 0x06040043;
constexpr uint32_t kNoObject = 0x06020000;
constexpr uint32_t kDeviceState = 0x08000022;
constexpr uint32_t kReadOnly = 0x06010002;

// Mapping entry values (ETG.1000.6 §5.6.7.4.7: index << 16 | subindex << 8 | bit length).
constexpr uint32_t kCpuTemperature = 0x20000F20;  // 0x2000:0F REAL
// Default rack module 15 is the K thermocouple card (nn = 0x0E): 0x50E4:01 "Ohms[1]" UINT.
constexpr uint32_t kOhms1 = 0x50E40110;

class UserPdo : public testing::DeviceSdoTest {
 protected:
  UserPdo() : DeviceSdoTest("user_pdo") {}
  // Appends `pdo` to 0x1C13 the way masters do: subindex 0 to 0, the entry, subindex 0 to n.
  uint32_t assign_tx(uint16_t pdo) {
    const uint8_t n = static_cast<uint8_t>(sdo->read_u(0x1C13, 0));
    if (uint32_t rc = sdo->write_u(0x1C13, 0, 0, 1)) return rc;
    if (uint32_t rc = sdo->write_u(0x1C13, static_cast<uint8_t>(n + 1), pdo, 2)) return rc;
    const uint32_t rc = sdo->write_u(0x1C13, 0, n + 1, 1);
    if (rc != 0) sdo->write_u(0x1C13, 0, n, 1);
    return rc;
  }
};

TEST_F(UserPdo, MappingIsWritableInPreopWithTheEtgAbortCodes) {
  EXPECT_EQ(sdo->read_u(sm::kUserTxPdo, 0), 0u);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 1, kCpuTemperature, 4), 0u);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 2, kOhms1, 4), 0u);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 2, 1), 0u);
  // Entries change only while subindex 0 is 0.
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 3, kOhms1 + 0x100, 4), kSubZero);
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 0, 1), 0u);
  // 0x2000:01 (Part Number) is not mappable; an output object is not a TxPDO entry either.
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 3, 0x20000100 | 0x00, 4), kNotMappable);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 3, 0x70000110, 4), kNotMappable);
  // Wrong length, missing object.
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 3, 0x20000F10, 4), kIncompatible);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 3, 0x5FF40110, 4), kNoObject);
  // The user RxPDO takes output objects only.
  EXPECT_EQ(sdo->write_u(sm::kUserRxPdo, 1, kCpuTemperature, 4), kNotMappable);
  EXPECT_EQ(sdo->write_u(sm::kUserRxPdo, 1, 0x70000110, 4), 0u);
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 2, 1), 0u);
  // Not in SAFEOP/OP.
  go(EsmState::SafeOp);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 0, 1), kDeviceState);
  // The module PDOs stay as Appendix A lists them: read-only.
  go(EsmState::PreOp);
  EXPECT_EQ(sdo->write_u(0x1A01, 0, 0, 1), kReadOnly);
}

TEST_F(UserPdo, AssignedUserPdoResizesSm3AndCarriesTheLiveValuesEveryCycle) {
  const uint16_t before = device->input_bytes();
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 1, kCpuTemperature, 4), 0u);
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 2, kOhms1, 4), 0u);
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 2, 1), 0u);
  ASSERT_EQ(assign_tx(sm::kUserTxPdo), 0u);
  EXPECT_EQ(device->input_bytes(), before + 6);
  go(EsmState::SafeOp);
  go(EsmState::Op);

  coe::ObjectDictionary& od = device->dictionary();
  auto set_real = [&](float v) {
    uint32_t raw;
    std::memcpy(&raw, &v, 4);
    od.find(0x2000)->set_u(0x0F, raw);
  };
  std::vector<uint8_t> sm3(device->input_bytes());
  set_real(41.5f);
  od.find(0x50E4)->set_u(1, 1234);
  device->read_inputs(sm3);
  const uint8_t first[6] = {0x00, 0x00, 0x26, 0x42, 0xD2, 0x04};  // 41.5f, 1234
  EXPECT_EQ(std::memcmp(&sm3[before], first, 6), 0);
  set_real(-3.0f);
  od.find(0x50E4)->set_u(1, 65535);
  device->read_inputs(sm3);
  const uint8_t second[6] = {0x00, 0x00, 0x40, 0xC0, 0xFF, 0xFF};  // -3.0f, 65535
  EXPECT_EQ(std::memcmp(&sm3[before], second, 6), 0);
}

// 64 oversampled 16-channel analog cards (256 bytes of inputs each) fill SM3's 16384 bytes.
RackConfig full_input_rack() {
  std::string yaml = "rims:\n";
  int modules = 0;
  for (int rim = 1; rim <= 3; ++rim) {
    yaml += "  - rim: " + std::to_string(rim) + "\n    type: 24-slot\n    slots:\n";
    for (int slot = 1; slot <= 24 && modules < 64; ++slot, ++modules) {
      yaml += "      - {slot: " + std::to_string(slot) + ", card: CAI-15/X8}\n";
    }
  }
  return parse_rack_config(yaml, "full.yaml");
}

TEST_F(UserPdo, TooLongAProcessImageIsRefusedWhereverItWouldArise) {
  make(full_input_rack());
  ASSERT_EQ(device->input_bytes(), 16384);
  // Mapped first, then assigned: the assignment is refused.
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 1, kCpuTemperature, 4), 0u);
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 1, 1), 0u);
  EXPECT_EQ(assign_tx(sm::kUserTxPdo), kPdoLength);
  EXPECT_EQ(device->input_bytes(), 16384);
  // Assigned empty, then mapped: the mapping is refused.
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 0, 1), 0u);
  ASSERT_EQ(assign_tx(sm::kUserTxPdo), 0u);
  EXPECT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 1, 1), kPdoLength);
  EXPECT_EQ(device->input_bytes(), 16384);
}

TEST_F(UserPdo, AnInvalidConfigurationLeftInPreopIsRefusedWithAlStatus001E) {
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 1, kOhms1, 4), 0u);
  ASSERT_EQ(sdo->write_u(sm::kUserTxPdo, 0, 1, 1), 0u);
  ASSERT_EQ(assign_tx(sm::kUserTxPdo), 0u);
  // A mapping that became invalid behind the validators' back (a stored image, a bug): the
  // ESM's PREOP->SAFEOP check answers with the direction's AL status code.
  device->dictionary().find(sm::kUserTxPdo)->set_u(1, 0x20000110);
  EXPECT_EQ(device->request_state(EsmState::PreOp, EsmState::SafeOp), 0x001E);
  device->dictionary().find(sm::kUserTxPdo)->set_u(1, kOhms1);
  EXPECT_EQ(device->request_state(EsmState::PreOp, EsmState::SafeOp), 0);
}

}  // namespace
}  // namespace rackcat::mdp
