// SDO behaviour of the device per ESM state, through the CoE SDO server (mailbox bytes in,
// mailbox bytes out): access per state, value range, length, string formats, PDO assignment and
// the module ident lists.
#include <gtest/gtest.h>

#include "mdp/device.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "sdo_client.hpp"

namespace rackcat::mdp {
namespace {

using testing::SdoClient;

constexpr uint32_t kDeviceState = 0x08000022;
constexpr uint32_t kReadOnly = 0x06010002;
constexpr uint32_t kValueRange = 0x06090030;
constexpr uint32_t kTooHigh = 0x06090031;
constexpr uint32_t kLengthTooHigh = 0x06070012;
constexpr uint32_t kLengthTooLow = 0x06070013;
constexpr uint32_t kPdoLength = 0x06040042;
constexpr uint32_t kIncompatible = 0x06040043;
constexpr uint32_t kModuleList = 0x06090033;
constexpr uint32_t kNoObject = 0x06020000;
constexpr uint32_t kSubZero = 0x06010003;

class SdoBehaviour : public testing::DeviceSdoTest {
 protected:
  SdoBehaviour() : DeviceSdoTest("sdo_behaviour") {}
};

TEST_F(SdoBehaviour, ReadsIdentityAndDeviceInformation) {
  EXPECT_EQ(sdo->read_u(0x1000, 0), 0x1389u);
  EXPECT_EQ(sdo->read_text(0x2000, 0x01), "FI-CM0100-00");
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "192.168.9.50");
  EXPECT_EQ(sdo->read_text(0x3001, 0x01), "CDO-10");
  EXPECT_EQ(sdo->read_u(0xF050, 0), device->modules().size());
  std::vector<uint8_t> d;
  EXPECT_EQ(sdo->upload(0x9999, 0, d), kNoObject);
}

TEST_F(SdoBehaviour, IpAddressIsWritableInPreopOnlyAndValidated) {
  EXPECT_EQ(sdo->write_text(0x2000, 0x04, "10.1.2.3"), 0u);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.1.2.3");
  EXPECT_EQ(sdo->write_text(0x2000, 0x04, "10.1.2.300"), kValueRange);
  EXPECT_EQ(sdo->write_text(0x2000, 0x04, "not an ip"), kValueRange);
  EXPECT_EQ(sdo->write_text(0x2000, 0x04, "10.1.2.3.4.5.6.7.8"), kLengthTooHigh);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.1.2.3");  // bad writes change nothing
  go(EsmState::SafeOp);
  EXPECT_EQ(sdo->write_text(0x2000, 0x04, "10.9.9.9"), kDeviceState);
  go(EsmState::Op);
  EXPECT_EQ(sdo->write_text(0x2000, 0x04, "10.9.9.9"), kDeviceState);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.1.2.3");
}

TEST_F(SdoBehaviour, ClockIsWritableInPreopAndKeepsRunningFromTheWrittenTime) {
  EXPECT_EQ(sdo->write_text(0x2000, 0x08, "2021-02-27 02:09:45"), 0u);
  const std::string now = sdo->read_text(0x2000, 0x08);
  EXPECT_EQ(now.substr(0, 16), "2021-02-27 02:09");
  EXPECT_EQ(sdo->write_text(0x2000, 0x08, "2021-02-30 02:09:45"), kValueRange);
  EXPECT_EQ(sdo->write_text(0x2000, 0x08, "2021/02/27 02:09:45"), kValueRange);
  go(EsmState::SafeOp);
  EXPECT_EQ(sdo->write_text(0x2000, 0x08, "2021-02-27 02:09:45"), kDeviceState);
}

TEST_F(SdoBehaviour, ReadOnlyObjectsRefuseWrites) {
  EXPECT_EQ(sdo->write_u(0x1018, 1, 5, 4), kReadOnly);
  EXPECT_EQ(sdo->write_text(0x2000, 0x01, "x"), kReadOnly);
  EXPECT_EQ(sdo->write_u(0xF050, 1, 0, 4), kReadOnly);
}

TEST_F(SdoBehaviour, SafeStateSettingsAreWritableInOpOnlyWithinTheChannelMask) {
  // Module 1 is a CDO-10 (16 channels, 0x4000); module 3 a CRS-14 (4 channels, 0x4021).
  EXPECT_EQ(sdo->write_u(0x4000, 1, 0xFFFF, 2), kDeviceState);
  go(EsmState::SafeOp);
  EXPECT_EQ(sdo->write_u(0x4000, 1, 0xFFFF, 2), kDeviceState);
  go(EsmState::Op);
  EXPECT_EQ(sdo->write_u(0x4000, 1, 0xFFFF, 2), 0u);
  EXPECT_EQ(sdo->read_u(0x4000, 1), 0xFFFFu);
  EXPECT_EQ(sdo->write_u(0x4021, 1, 0x0F, 1), 0u);
  EXPECT_EQ(sdo->write_u(0x4021, 1, 0x10, 1), kTooHigh);
  EXPECT_EQ(sdo->write_u(0x4000, 1, 0xFF, 1), kLengthTooLow);
  EXPECT_EQ(sdo->write_u(0x4000, 1, 0xFF, 4), kLengthTooHigh);
}

TEST_F(SdoBehaviour, UartConfigurationAcceptsOnlyEnumeratedValuesInPreop) {
  const Module* uart = device->config().module_at(1, 19);
  ASSERT_NE(uart, nullptr);
  const uint16_t cfg = uart->index(0x5000, 5);
  EXPECT_EQ(sdo->write_u(cfg, 0x02, 8, 1), 0u);  // 115200 baud
  EXPECT_EQ(sdo->read_u(cfg, 0x02), 8u);
  EXPECT_EQ(sdo->write_u(cfg, 0x02, 9, 1), kValueRange);
  EXPECT_EQ(sdo->write_u(cfg, 0x01, 3, 1), kValueRange);  // interface 3 is not defined
  go(EsmState::SafeOp);
  EXPECT_EQ(sdo->write_u(cfg, 0x02, 4, 1), kDeviceState);
}

TEST_F(SdoBehaviour, CompleteAccessOfPdoAssignmentHasSixteenBitSubindexZero) {
  std::vector<uint8_t> d;
  ASSERT_EQ(sdo->upload(0x1C12, 0, d, true), 0u);
  const size_t n = device->dictionary().find(0x1C12)->sub0();
  ASSERT_EQ(d.size(), 2 + 2 * n);
  EXPECT_EQ(d[0], n);
  EXPECT_EQ(d[1], 0);
  EXPECT_EQ(d[2], 0x00);  // module 1's RxPDO 0x1600
  EXPECT_EQ(d[3], 0x16);
}

TEST_F(SdoBehaviour, PdoAssignmentIsValidatedAndResizesTheProcessImage) {
  const uint16_t before = device->output_bytes();
  EXPECT_EQ(sdo->write_u(0x1C12, 0, 0, 1), 0u);
  EXPECT_EQ(device->output_bytes(), 0);
  EXPECT_EQ(sdo->write_u(0x1C12, 1, 0x1234, 2), kIncompatible);  // not a mapping index
  EXPECT_EQ(sdo->write_u(0x1C12, 1, 0x1A01, 2), kIncompatible);  // a TxPDO
  EXPECT_EQ(sdo->write_u(0x1C12, 1, 0x1601, 2), kNoObject);      // module 2 has no outputs
  EXPECT_EQ(sdo->write_u(0x1C12, 1, 0x1600, 2), 0u);
  EXPECT_EQ(sdo->write_u(0x1C12, 2, 0x1600, 2), 0u);
  EXPECT_EQ(sdo->write_u(0x1C12, 0, 2, 1), kIncompatible);  // the same PDO twice
  EXPECT_EQ(sdo->write_u(0x1C12, 0, 1, 1), 0u);
  EXPECT_EQ(sdo->write_u(0x1C12, 1, 0x1600, 2), kSubZero);  // entries change only at 0
  EXPECT_EQ(device->output_bytes(), 2);                     // DOUTx16
  EXPECT_LT(device->output_bytes(), before);
  go(EsmState::SafeOp);
  EXPECT_EQ(sdo->write_u(0x1C12, 0, 0, 1), kDeviceState);
}

TEST_F(SdoBehaviour, PdoAssignmentBeyondTheSyncManagerMaximumIsRefused) {
  // 120 oversampled 16-channel analog inputs: 256 bytes each, 30720 bytes in all.
  std::string text = "rims:\n";
  for (int r = 1; r <= 5; ++r) {
    text += "  - rim: " + std::to_string(r) + "\n    type: 24-slot\n    slots:\n";
    for (int s = 1; s <= 24; ++s)
      text += "      - {slot: " + std::to_string(s) + ", card: CAI-15/X8}\n";
  }
  make(parse_rack_config(text, "big.yaml"));
  EXPECT_EQ(device->dictionary().find(0x1C13)->sub0(), 64);  // as many as fit 16384 bytes
  EXPECT_EQ(device->input_bytes(), sm::kMaxProcessDataBytes);
  EXPECT_EQ(sdo->write_u(0x1C13, 0, 0, 1), 0u);
  for (uint16_t n = 1; n <= 65; ++n) {
    ASSERT_EQ(sdo->write_u(0x1C13, static_cast<uint8_t>(n), sm::tx_pdo_index(n), 2), 0u);
  }
  EXPECT_EQ(sdo->write_u(0x1C13, 0, 65, 1), kPdoLength);
  EXPECT_EQ(sdo->write_u(0x1C13, 0, 64, 1), 0u);
  EXPECT_EQ(device->input_bytes(), sm::kMaxProcessDataBytes);
}

TEST_F(SdoBehaviour, SyncManagerParametersAcceptTheSupportedSyncTypes) {
  EXPECT_EQ(sdo->read_u(0x1C32, 0x04), 0x0007u);
  EXPECT_EQ(sdo->write_u(0x1C32, 0x01, 2, 2), 0u);  // DC SYNC0
  EXPECT_EQ(sdo->write_u(0x1C32, 0x01, 0x22, 2), kValueRange);
  EXPECT_EQ(sdo->write_u(0x1C33, 0x01, 0x22, 2), 0u);        // inputs on the SM2 event
  EXPECT_EQ(sdo->write_u(0x1C32, 0x01, 3, 2), kValueRange);  // SYNC1 not supported
  device->sync_statistics(true).sm_event_missed = 3;
  device->sync_statistics(true).cycle_time_too_small = 2;
  EXPECT_EQ(sdo->read_u(0x1C32, 0x0B), 3u);
  EXPECT_EQ(sdo->read_u(0x1C32, 0x0C), 2u);
  EXPECT_EQ(sdo->write_u(0x1C32, 0x08, 2, 2), 0u);  // reset the counters
  EXPECT_EQ(sdo->read_u(0x1C32, 0x0B), 0u);
  EXPECT_EQ(sdo->write_u(0x1C32, 0x08, 3, 2), kTooHigh);
}

TEST_F(SdoBehaviour, ConfiguredModuleListMustMatchTheDetectedOne) {
  // ETG.5001.1 sequence: subindex 0 = 0, the entries, then the count.
  const auto& mods = device->modules();
  EXPECT_EQ(sdo->write_u(0xF030, 0, 0, 1), 0u);
  for (const auto& m : mods) {
    ASSERT_EQ(sdo->write_u(0xF030, static_cast<uint8_t>(m.number), m.card->module_ident, 4), 0u);
  }
  EXPECT_EQ(sdo->write_u(0xF030, 0, mods.size(), 1), 0u);
  EXPECT_EQ(device->request_state(EsmState::PreOp, EsmState::SafeOp), 0);
  // A list that differs is refused with the guide's abort and changes nothing.
  EXPECT_EQ(sdo->write_u(0xF030, 1, 0x0064A016, 4), kModuleList);
  EXPECT_EQ(sdo->write_u(0xF030, 0, mods.size() - 1, 1), kModuleList);
  EXPECT_EQ(sdo->read_u(0xF030, 1), mods[0].card->module_ident);
  // The detected list changes (a RIM lost, Detect Modules): PREOP->SAFEOP answers 0x0070.
  device->dictionary().find(0xF050)->image()[0] = static_cast<uint8_t>(mods.size() - 1);
  EXPECT_EQ(device->request_state(EsmState::PreOp, EsmState::SafeOp), 0x0070);
  // Switching the check off (subindex 0 = 0) lets the device start.
  EXPECT_EQ(sdo->write_u(0xF030, 0, 0, 1), 0u);
  EXPECT_EQ(device->request_state(EsmState::PreOp, EsmState::SafeOp), 0);
}

TEST_F(SdoBehaviour, DetectModulesCommandNeedsItsByteSequence) {
  EXPECT_EQ(sdo->download(0xF002, 1, std::vector<uint8_t>{1, 2, 3, 4}), kIncompatible);
  EXPECT_EQ(sdo->download(0xF002, 1, std::vector<uint8_t>{0x73, 0x63, 0x61, 0x6E}), 0u);
  EXPECT_EQ(sdo->read_u(0xF002, 2), 200u);  // guide Appendix A: 200 = 100 % done
  EXPECT_EQ(sdo->read_u(0xF050, 0), device->modules().size());
}

}  // namespace
}  // namespace rackcat::mdp

namespace rackcat::mdp {
namespace {

// Every entry of the whole dictionary answers an SDO upload in PREOP, SAFEOP and OP with its
// value (nothing in Appendix A is write-only), and every ARRAY/RECORD a complete-access upload.
TEST_F(SdoBehaviour, EveryEntryIsReadableInEveryMailboxState) {
  for (EsmState s : {EsmState::PreOp, EsmState::SafeOp, EsmState::Op}) {
    if (s != EsmState::PreOp) go(s);
    size_t entries = 0;
    device->dictionary().for_each([&](const coe::Object& o) {
      for (const auto& e : o.entries()) {
        if (e.padding) continue;
        std::vector<uint8_t> d;
        ASSERT_EQ(sdo->upload(o.index(), e.subindex, d), 0u)
            << std::hex << o.index() << ":" << int(e.subindex);
        if (e.bit_length % 8 == 0) {
          EXPECT_EQ(d.size(), e.bit_length / 8u) << std::hex << o.index() << ":" << int(e.subindex);
        }
        ++entries;
      }
      if (o.code() != coe::ObjectCode::Var) {
        std::vector<uint8_t> d;
        EXPECT_EQ(sdo->upload(o.index(), 0, d, true), 0u) << std::hex << o.index();
      }
    });
    EXPECT_GT(entries, 3000u);
  }
}

}  // namespace
}  // namespace rackcat::mdp
