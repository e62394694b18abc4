// The second PDI backend: the same firmware reaching the chip model through the LAN9252 host
// bus protocol (CSR command/data 0x300/0x304, process RAM through the PRAM FIFOs; LAN9252
// datasheet Table 5-1), both as a bare port and as a whole slave line driven by the master.
#include <gtest/gtest.h>

#include <vector>

#include "ecat/esc/esc_pdi.hpp"
#include "ecat/esc/lan9252_model.hpp"
#include "ecat/lan9252/lan9252_pdi.hpp"
#include "tests/ecat/chip_master.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

struct Lan9252Test : ::testing::Test {
  Lan9252Test() : esc(eeprom, clock), model(esc), port(model), direct(esc) {}
  ManualClock clock;
  TestEeprom eeprom;
  Esc esc;
  Lan9252Model model;
  Lan9252Pdi port;
  EscPdi direct;
};

TEST_F(Lan9252Test, StartFindsTheChipAndEnablesItsIrq) {
  EXPECT_TRUE(port.start());
  EXPECT_FALSE(port.irq());
  port.write32(0x0204, 0x1);  // AL event mask: AL control
  // APWR of AL control by the master: AL event bit 0, the IRQ pin follows.
  std::vector<uint8_t> d{0x02, 0, 0x00, 0x00, 0x20, 0x01, 1, 0, 0, 0, 0x02, 0, 0};
  esc.begin_frame({});
  esc.process_datagram(d.data(), 1);
  EXPECT_TRUE(port.irq());
  EXPECT_EQ(port.read8(0x0120), 0x02);  // the read clears the event
  EXPECT_FALSE(port.irq());
}

TEST_F(Lan9252Test, RegistersGoThroughTheCsrInterfaceInAlignedPieces) {
  ASSERT_TRUE(port.start());
  const uint64_t before = port.transactions();
  // 7 bytes from 0x0131: 1 + 2 + 4 byte CSR accesses, each command + status + data.
  std::vector<uint8_t> got(7, 0xEE);
  port.read(0x0131, got);
  std::vector<uint8_t> want(7);
  direct.read(0x0131, want);
  EXPECT_EQ(got, want);
  EXPECT_EQ(port.transactions() - before, 9u);
  port.write16(0x0134, 0x001D);
  EXPECT_EQ(esc.read16(0x0134), 0x001D);
  port.write8(0x0010, 0x55);  // ECAT-only register: the PDI write has no effect
  EXPECT_EQ(esc.read8(0x0010), 0x00);
}

TEST_F(Lan9252Test, ProcessRamGoesThroughTheFifosAtAnyAlignment) {
  ASSERT_TRUE(port.start());
  // Plain process RAM (no SyncManager there): write at an odd address, read it back both ways.
  std::vector<uint8_t> data(70);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i * 7 + 1);
  port.write(0x1203, data);
  std::vector<uint8_t> back(data.size());
  direct.read(0x1203, back);
  EXPECT_EQ(back, data);
  std::vector<uint8_t> via(data.size());
  port.read(0x1203, via);
  EXPECT_EQ(via, data);
  EXPECT_EQ(esc.read8(0x1202), 0x00);  // the bytes around stay untouched
  EXPECT_EQ(esc.read8(0x1203 + 70), 0x00);
}

TEST(Lan9252Line, FirmwareBehindLan9252ReachesOpCyclesAndAnswersTheMailbox) {
  SegmentOptions options;
  options.pdi = PdiAccess::Lan9252Emulated;
  Line line(2, options);
  line.to_op();
  for (size_t k = 0; k < 2; ++k) ASSERT_EQ(line.fw(k).state(), EsmState::Op) << k;
  line.app(1).inputs_value = {6, 5, 4, 3, 2, 1};
  line.cycle({1, 2, 3, 4, 5, 6, 7, 8});
  const auto r = line.cycle({1, 2, 3, 4, 5, 6, 7, 8});
  EXPECT_EQ(r[0].wkc, 6);
  EXPECT_EQ(line.app(0).last_outputs, (std::vector<uint8_t>{1, 2, 3, 4}));
  EXPECT_EQ(line.app(1).last_outputs, (std::vector<uint8_t>{5, 6, 7, 8}));
  EXPECT_EQ(std::vector<uint8_t>(r[0].data.begin() + 14, r[0].data.end()),
            line.app(1).inputs_value);
  // A mailbox round trip through the FIFOs.
  std::vector<uint8_t> request(kMbxSize, 0);
  request[0] = 4;
  request[5] = 0x13;
  request[6] = 0xAB;
  EXPECT_EQ(line.master->fpwr(Line::station(0), kMbxOutStart, request).wkc, 1);
  const auto reply = line.master->fprd(Line::station(0), kMbxInStart, kMbxSize);
  EXPECT_EQ(reply.wkc, 1);
  EXPECT_EQ(reply.data[6], 0xAB);
  EXPECT_EQ(line.app(0).mailbox_requests, 1);
  // The ESM answers through it too.
  EXPECT_EQ(line.master->request_state(Line::station(0), 0x01), 0x0001);
}

}  // namespace
}  // namespace rackcat::ecat::test
