// The AL state machine (ETG.1000.6 §5.3, Tables 8 and 9) and every AL status code the ESC
// produces (Table 11): which request gets which code, the error flag and its acknowledge.
#include <gtest/gtest.h>

#include "ecat/al_status_code.hpp"
#include "ecat/registers.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

constexpr uint16_t kStation = 0x1001;

struct EsmTest : ::testing::Test {
  EsmTest() : line(1) {}
  uint16_t status() { return line.master->fprd16(kStation, 0x0130); }
  uint16_t code() { return line.master->fprd16(kStation, 0x0134); }
  uint16_t request(uint16_t control) {
    return line.master->request_state(kStation, static_cast<uint8_t>(control));
  }
  Line line;
};

TEST_F(EsmTest, FullPathUpAndDown) {
  line.to_op();
  EXPECT_EQ(status(), 0x0008);
  EXPECT_EQ(request(0x04), 0x0004);
  EXPECT_EQ(request(0x02), 0x0002);
  EXPECT_EQ(request(0x01), 0x0001);
  const std::vector<std::pair<EsmState, EsmState>> expected = {
      {EsmState::Init, EsmState::PreOp},   {EsmState::PreOp, EsmState::SafeOp},
      {EsmState::SafeOp, EsmState::Op},    {EsmState::Op, EsmState::SafeOp},
      {EsmState::SafeOp, EsmState::PreOp}, {EsmState::PreOp, EsmState::Init}};
  EXPECT_EQ(line.app(0).transitions, expected);
}

TEST_F(EsmTest, OpDirectlyToInit) {
  line.to_op();
  EXPECT_EQ(request(0x01), 0x0001);
  // In INIT every SyncManager is deactivated again from the PDI side.
  EXPECT_EQ(line.master->fprd8(kStation, 0x0807) & 0x01, 0x01);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0817) & 0x01, 0x01);
}

TEST_F(EsmTest, InitToOpIsInvalidStateChange0x0011) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  EXPECT_EQ(request(0x08), 0x0011);  // stays INIT, error flag
  EXPECT_EQ(code(), 0x0011);
  EXPECT_EQ(request(0x04), 0x0011);  // not acknowledged: ignored, code unchanged
  EXPECT_EQ(code(), 0x0011);
}

TEST_F(EsmTest, PreopToOpAndPreopToBootAreInvalid) {
  line.to_preop();
  EXPECT_EQ(request(0x08), 0x0012);
  EXPECT_EQ(code(), 0x0011);
  EXPECT_EQ(request(0x13), 0x0012);  // acknowledge + BOOT from PREOP
  EXPECT_EQ(code(), 0x0011);
}

TEST_F(EsmTest, UnknownState0x0012) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  EXPECT_EQ(request(0x05), 0x0011);
  EXPECT_EQ(code(), 0x0012);
}

TEST_F(EsmTest, AcknowledgeClearsErrorAndTakesTheRequest) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  request(0x08);
  ASSERT_EQ(status(), 0x0011);
  line.master->config_init();  // writes 0x11 first (INIT + ack), ends with PREOP + ack
  EXPECT_EQ(status(), 0x0002);
  EXPECT_EQ(code(), 0x0000);
}

TEST_F(EsmTest, InitRequestClearsErrorWithoutAcknowledge) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  request(0x08);
  EXPECT_EQ(request(0x01), 0x0001);
  EXPECT_EQ(code(), 0);
}

TEST_F(EsmTest, OneByteAndTwoByteControlWrites) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0120, 0x08), 1);  // SOEM 1.4: one byte
  EXPECT_EQ(status(), 0x0011);
  EXPECT_EQ(line.master->fpwr16(kStation, 0x0120, 0x0011), 1);  // SOEM 2.x: two bytes
  EXPECT_EQ(status(), 0x0001);
}

TEST_F(EsmTest, BootstrapNotSupported0x0013) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  EXPECT_EQ(request(0x03), 0x0011);
  EXPECT_EQ(code(), 0x0013);
}

TEST(Esm, BootWithBootstrapMailbox) {
  ManualClock clock;
  TestApplication app;
  // SII words 0x14-0x17: bootstrap mailbox at 0x1000/0x1200, 256 bytes each.
  const uint16_t words[4] = {0x1000, 0x0100, 0x1200, 0x0100};
  for (int i = 0; i < 4; ++i) {
    app.sii[(0x14 + i) * 2] = static_cast<uint8_t>(words[i]);
    app.sii[(0x14 + i) * 2 + 1] = static_cast<uint8_t>(words[i] >> 8);
  }
  Segment segment({&app}, clock);
  TestMaster master(segment);
  master.send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  // Standard mailbox SMs do not match the bootstrap words: 0x0015.
  master.fpwr(kStation, 0x0800, hex("00 10 80 00 26 00 01 00 80 10 80 00 22 00 01 00", 0));
  EXPECT_EQ(master.request_state(kStation, 0x03), 0x0011);
  EXPECT_EQ(master.fprd16(kStation, 0x0134), 0x0015);
  master.fpwr(kStation, 0x0800, std::vector<uint8_t>(16, 0));
  master.fpwr(kStation, 0x0800, hex("00 10 00 01 26 00 01 00 00 12 00 01 22 00 01 00", 0));
  EXPECT_EQ(master.request_state(kStation, 0x13), 0x0003);
  EXPECT_EQ(master.request_state(kStation, 0x02), 0x0013);  // BOOT -> PREOP invalid
  EXPECT_EQ(master.fprd16(kStation, 0x0134), 0x0011);
  EXPECT_EQ(master.request_state(kStation, 0x01), 0x0001);
}

TEST_F(EsmTest, InvalidMailboxConfiguration0x0016) {
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  // SM0 64 bytes where the SII says 128.
  line.master->fpwr(kStation, 0x0800, hex("00 10 40 00 26 00 01 00 80 10 80 00 22 00 01 00", 0));
  EXPECT_EQ(request(0x02), 0x0011);
  EXPECT_EQ(code(), 0x0016);
  // SM1 in buffered mode instead of mailbox mode.
  line.master->fpwr(kStation, 0x0800, std::vector<uint8_t>(16, 0));
  line.master->fpwr(kStation, 0x0800, hex("00 10 80 00 26 00 01 00 80 10 80 00 20 00 01 00", 0));
  EXPECT_EQ(request(0x12), 0x0011);
  EXPECT_EQ(code(), 0x0016);
  // SM1 not enabled.
  line.master->fpwr(kStation, 0x0800, std::vector<uint8_t>(16, 0));
  line.master->fpwr(kStation, 0x0800, hex("00 10 80 00 26 00 01 00 80 10 80 00 22 00 00 00", 0));
  EXPECT_EQ(request(0x12), 0x0011);
  EXPECT_EQ(code(), 0x0016);
}

TEST_F(EsmTest, InvalidSmConfiguration0x0017) {
  line.to_preop();
  line.master->config_map();
  // SM3 moved onto SM2's buffer.
  line.master->fpwr(kStation, 0x0818, {0x00, 0x11, kInputBytes, 0x00, 0x20, 0x00, 0x01, 0x00});
  line.master->fpwr8(kStation, 0x081E, 0x00);
  line.master->fpwr(kStation, 0x0818, {0x00, 0x11, kInputBytes, 0x00, 0x20, 0x00, 0x01, 0x00});
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x0017);
}

TEST_F(EsmTest, InvalidOutputConfiguration0x001D) {
  line.to_preop();
  line.master->config_map();
  line.master->fpwr8(kStation, 0x0816, 0x00);
  line.master->fpwr(kStation, 0x0810,
                    {0x00, 0x11, 0x02, 0x00, 0x64, 0x00, 0x01, 0x00});  // 2 bytes, not 4
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x001D);
  EXPECT_EQ(std::string(al_status_code_name(code())), "Invalid output configuration");
}

TEST_F(EsmTest, InvalidInputConfiguration0x001E) {
  line.to_preop();
  line.master->config_map();
  line.master->fpwr8(kStation, 0x081E, 0x00);
  line.master->fpwr(kStation, 0x0818,
                    {0x80, 0x11, kInputBytes, 0x00, 0x24, 0x00, 0x01, 0x00});  // ECAT write
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x001E);
}

TEST_F(EsmTest, DeviceWithoutOutputsRefusesEnabledSm2) {
  line.app(0).sizes.outputs = 0;
  line.to_preop();
  line.master->config_map();
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x001D);
}

TEST_F(EsmTest, SmWatchdog0x001BFallsToSafeop) {
  line.to_op();
  ASSERT_EQ(line.fw(0).state(), EsmState::Op);
  // Reset values: (2498 + 2) x 40 ns x 1000 = 100 ms.
  EXPECT_EQ(line.segment->next_event_ns(), line.clock.now_ns() + 100'000'000);
  line.clock.advance(99'000'000);
  line.cycle({1, 2, 3, 4});  // retriggers
  line.clock.advance(99'000'000);
  line.segment->service();
  EXPECT_EQ(line.fw(0).state(), EsmState::Op);
  line.clock.advance(2'000'000);
  line.segment->service();
  EXPECT_EQ(line.fw(0).state(), EsmState::SafeOp);
  EXPECT_EQ(status(), 0x0014);
  EXPECT_EQ(code(), 0x001B);
  EXPECT_EQ(line.app(0).watchdog_expiries, 1);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0440) & 0x01, 0);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0442), 1);
  // Acknowledge and back to OP.
  line.cycle({0, 0, 0, 0});
  EXPECT_EQ(request(0x18), 0x0008);
}

TEST_F(EsmTest, WatchdogTimeZeroDisablesIt) {
  line.to_safeop();
  line.master->fpwr16(kStation, 0x0420, 0);
  line.cycle({0, 0, 0, 0});
  request(0x08);
  line.clock.advance(10'000'000'000);
  line.segment->service();
  EXPECT_EQ(line.fw(0).state(), EsmState::Op);
}

TEST_F(EsmTest, InvalidDcSyncConfiguration0x0030) {
  line.to_preop();
  line.master->config_map();
  line.master->fpwr8(kStation, 0x0981, 0x02);  // SYNC0 without cyclic operation
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x0030);
  line.master->fpwr8(kStation, 0x0981, 0x00);
  line.master->fpwr32(kStation, 0x09A0, 0);  // SYNC0 with cycle time 0
  line.master->fpwr8(kStation, 0x0981, 0x03);
  EXPECT_EQ(request(0x14), 0x0012);
  EXPECT_EQ(code(), 0x0030);
}

TEST_F(EsmTest, FatalSyncError0x002CWhenSyncStopsInOp) {
  line.to_preop();
  line.master->config_map();
  const uint64_t now = line.master->fprd64(kStation, 0x0910);
  line.master->fpwr64(kStation, 0x0990, now + 1'000'000);
  line.master->fpwr32(kStation, 0x09A0, 1'000'000);
  line.master->fpwr8(kStation, 0x0981, 0x03);
  EXPECT_EQ(request(0x04), 0x0004);
  line.cycle({0, 0, 0, 0});
  EXPECT_EQ(request(0x08), 0x0008);
  line.master->fpwr8(kStation, 0x0981, 0x00);  // the master stops SYNC0
  EXPECT_EQ(status(), 0x0014);
  EXPECT_EQ(code(), 0x002C);
}

TEST_F(EsmTest, ApplicationVetoSetsItsCode) {
  line.app(0).veto_code = 0x0070;
  line.app(0).veto_to = EsmState::SafeOp;
  line.to_preop();
  line.master->config_map();
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x0070);
  EXPECT_EQ(line.esc(0).al_status_code(), 0x0070);
  EXPECT_EQ(std::string(al_status_code_name(0x0070)), "Detected module ident list does not match");
}

TEST_F(EsmTest, SameStateRequestIsANoOp) {
  line.to_preop();
  const size_t n = line.app(0).transitions.size();
  EXPECT_EQ(request(0x02), 0x0002);
  EXPECT_EQ(line.app(0).transitions.size(), n);
}

TEST(AlStatusCodeNames, TableLookup) {
  EXPECT_EQ(al_status_code_name(0x0011), "Invalid requested state change");
  EXPECT_EQ(al_status_code_name(0x001B), "Sync manager watchdog");
  EXPECT_EQ(al_status_code_name(0x002C), "Fatal sync error");
  EXPECT_EQ(al_status_code_name(0x0030), "Invalid DC SYNC configuration");
  EXPECT_EQ(al_status_code_name(0x7777), "Unknown AL status code");
}

}  // namespace
}  // namespace rackcat::ecat::test

namespace rackcat::ecat::test {
namespace {

TEST_F(EsmTest, DisablingOutputsSmInOpFallsToPreop) {
  line.to_op();
  line.master->fpwr8(kStation, 0x0816, 0x00);  // master switches SM2 off
  EXPECT_EQ(status(), 0x0012);
  EXPECT_EQ(code(), 0x001D);
  EXPECT_EQ(line.app(0).transitions.back(), std::make_pair(EsmState::Op, EsmState::PreOp));
}

TEST_F(EsmTest, MovingMailboxSmInPreopFallsToInit) {
  line.to_preop();
  line.master->fpwr8(kStation, 0x0806, 0x00);
  EXPECT_EQ(status(), 0x0011);
  EXPECT_EQ(code(), 0x0016);
}

TEST_F(EsmTest, InitRequestTogetherWithSmResetIsClean) {
  line.to_op();
  // ethercrab/SOEM style reset: INIT + ack and the SM clear in one frame.
  FrameBuilder b;
  b.add(Command::Bwr, 0, 0x0120, {0x11});
  b.add(Command::Bwr, 0, 0x0800, std::vector<uint8_t>(32, 0));
  line.master->send_frame(b);
  EXPECT_EQ(status(), 0x0001);
  EXPECT_EQ(code(), 0x0000);
}

TEST(Esm, SyncManagerPastTheAddressSpaceIsNotASyncManager) {
  Line line(1);
  line.to_op();
  // Disable SM3, move it to the top of memory with a length past 0xFFFF, enable again: the ESC
  // does not treat it as a SyncManager (no buffer semantics, no device call past memory).
  line.master->fpwr8(0x1001, 0x081E, 0x00);
  line.master->fpwr(0x1001, 0x0818, {0xF0, 0xFF, 0x00, 0x01, 0x20, 0x00, 0x01, 0x00});
  EXPECT_EQ(line.fw(0).state(), EsmState::PreOp);
  EXPECT_EQ(line.esc(0).al_status_code(), 0x001E);
  EXPECT_EQ(line.master->fprd(0x1001, 0xFFF0, 16).wkc, 1);
}

}  // namespace
}  // namespace rackcat::ecat::test

namespace rackcat::ecat::test {
namespace {

TEST(Esm, ApplicationErrorFallsOnlyDown) {
  Line line(1);
  line.to_op();
  line.fw(0).application_error(EsmState::SafeOp, 0x0070);
  EXPECT_EQ(line.fw(0).state(), EsmState::SafeOp);
  EXPECT_EQ(line.master->fprd16(0x1001, 0x0130), 0x0014);
  EXPECT_EQ(line.master->fprd16(0x1001, 0x0134), 0x0070);
  // A "fall" upwards keeps the state; the code is updated.
  line.fw(0).application_error(EsmState::Op, 0x0071);
  EXPECT_EQ(line.fw(0).state(), EsmState::SafeOp);
  EXPECT_EQ(line.esc(0).al_status_code(), 0x0071);
  // BOOT is not below SAFEOP in the state machine.
  line.fw(0).application_error(EsmState::Boot, 0x0072);
  EXPECT_EQ(line.fw(0).state(), EsmState::SafeOp);
  // The master acknowledges and goes on.
  EXPECT_EQ(line.master->request_state(0x1001, 0x14), 0x0004);
}

}  // namespace
}  // namespace rackcat::ecat::test
