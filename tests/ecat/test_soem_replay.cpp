// SOEM's config_init sequence (steps 1-12) replayed in process: the slaves end in
// PREOP with the addresses, identity and mailbox SMs SOEM expects.
#include <gtest/gtest.h>

#include "ecat/registers.hpp"
#include "ecat/segment.hpp"
#include "tests/ecat/test_application.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

TEST(SoemReplay, ConfigInitBringsOneSlaveToPreop) {
  ManualClock clock;
  TestApplication app;
  Segment segment({&app}, clock);
  TestMaster master(segment);

  // Step 3: BRD 0x0000 counts the slaves through its working counter.
  EXPECT_EQ(master.send(Command::Brd, 0, 0x0000, {0, 0}).wkc, 1);
  master.config_init();

  Esc& esc = segment.slave(0).esc();
  EXPECT_EQ(esc.station_address(), 0x1001);
  EXPECT_EQ(master.fprd16(0x1001, 0x0130), 0x0002);  // PREOP, no error
  EXPECT_EQ(master.fprd16(0x1001, 0x0134), 0x0000);
  EXPECT_EQ(segment.slave(0).firmware().state(), EsmState::PreOp);
  ASSERT_FALSE(app.transitions.empty());
  EXPECT_EQ(app.transitions.back(), std::make_pair(EsmState::Init, EsmState::PreOp));
  // Identity from SII as SOEM reads it.
  EXPECT_EQ(master.sii_read_word(0x1001, 0x08) | master.sii_read_word(0x1001, 0x09) << 16,
            kVendorId);
  EXPECT_EQ(master.sii_read_word(0x1001, 0x0A) | master.sii_read_word(0x1001, 0x0B) << 16,
            kProductCode);
  // PDI control loaded from SII word 0; DL status of a lone slave: only port 0 open.
  EXPECT_EQ(master.fprd8(0x1001, 0x0140), 0x05);
  EXPECT_EQ(master.fprd16(0x1001, 0x0110), 0x5613);
}

TEST(SoemReplay, ConfigInitOnSixteenSlaves) {
  ManualClock clock;
  std::vector<TestApplication> apps(16);
  std::vector<Application*> ptrs;
  for (auto& a : apps) ptrs.push_back(&a);
  Segment segment(ptrs, clock);
  TestMaster master(segment);
  EXPECT_EQ(master.send(Command::Brd, 0, 0x0000, {0, 0}).wkc, 16);
  master.config_init();
  for (uint16_t k = 0; k < 16; ++k) {
    EXPECT_EQ(segment.slave(k).esc().station_address(), 0x1001 + k);
    EXPECT_EQ(segment.slave(k).firmware().state(), EsmState::PreOp) << "slave " << k;
    // In-line slaves have port 1 open as well; the last one only port 0.
    EXPECT_EQ(master.fprd16(static_cast<uint16_t>(0x1001 + k), 0x0110), k == 15 ? 0x5613 : 0x5A33);
  }
}

}  // namespace
}  // namespace rackcat::ecat::test
