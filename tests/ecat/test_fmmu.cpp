// FMMU bit mapping (ETG.1000.4 §6.6): bit-granular logical -> physical, read/write/read-write
// types, mapping of registers (SOEM maps SM1 status 0x080D).
#include <gtest/gtest.h>

#include "tests/ecat/test_master.hpp"
#include "tests/support/fmmu_entry.hpp"

namespace rackcat::ecat::test {
namespace {

using rackcat::testing::fmmu_entry;

struct FmmuTest : ::testing::Test {
  FmmuTest() : line(1) { line.master->send(Command::Apwr, 0, 0x0010, bytes16(0x1001)); }
  Line line;
};

TEST_F(FmmuTest, NibbleToBitZeroWrite) {
  // Logical 0x100 bits 4-7 -> physical 0x1300 bits 0-3.
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x100, 1, 4, 7, 0x1300, 0, 2));
  line.master->fpwr(0x1001, 0x1300, {0xF0});
  EXPECT_EQ(line.master->send_logical(Command::Lwr, 0x100, {0xA5}).wkc, 1);
  EXPECT_EQ(line.esc(0).read8(0x1300), 0xFA);  // bits 4-7 of physical untouched
}

TEST_F(FmmuTest, BitFieldAcrossBytesRead) {
  // Logical 0x200 bit 4 .. 0x201 bit 3 (8 bits) <- physical 0x1400 bits 0-7.
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x200, 2, 4, 3, 0x1400, 0, 1));
  line.master->fpwr(0x1001, 0x1400, {0xDA});
  const auto r = line.master->send_logical(Command::Lrd, 0x200, {0x0F, 0xF0});
  EXPECT_EQ(r.wkc, 1);
  // Unmapped bits keep the datagram's values.
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0xAF, 0xFD}));
}

TEST_F(FmmuTest, AlignedBitsKeepNeighbours) {
  // Logical 0x300 bits 2-5 <-> physical 0x1500 bits 2-5 (same positions: byte path).
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x300, 1, 2, 5, 0x1500, 2, 2));
  line.master->send_logical(Command::Lwr, 0x300, {0xFF});
  EXPECT_EQ(line.esc(0).read8(0x1500), 0x3C);
}

TEST_F(FmmuTest, AlignedBitsOverSeveralBytesMergeTheEdges) {
  // Logical 0x500 bit 3 .. 0x502 bit 5 <-> physical 0x1700 bit 3 .. 0x1702 bit 5: whole middle
  // byte, first byte bits 3-7 (mask 0xF8), last byte bits 0-5 (mask 0x3F).
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x500, 3, 3, 5, 0x1700, 3, 3));
  line.master->fpwr(0x1001, 0x1700, {0x11, 0x22, 0x33});
  EXPECT_EQ(line.master->send_logical(Command::Lwr, 0x500, {0xFF, 0xAB, 0xFF}).wkc, 1);
  EXPECT_EQ(line.esc(0).read8(0x1700), 0xF9);
  EXPECT_EQ(line.esc(0).read8(0x1701), 0xAB);
  EXPECT_EQ(line.esc(0).read8(0x1702), 0x3F);
  const auto r = line.master->send_logical(Command::Lrd, 0x500, {0x00, 0x00, 0x00});
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0xF8, 0xAB, 0x3F}));
}

TEST_F(FmmuTest, DatagramCoveringPartOfTheMapping) {
  // FMMU maps 8 logical bytes; the datagram covers bytes 4-11 of logical space from 0x404.
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x400, 8, 0, 7, 0x1600, 0, 1));
  line.master->fpwr(0x1001, 0x1600, {0, 1, 2, 3, 4, 5, 6, 7});
  const auto r = line.master->send_logical(Command::Lrd, 0x404, std::vector<uint8_t>(8, 0xEE));
  EXPECT_EQ(r.data, (std::vector<uint8_t>{4, 5, 6, 7, 0xEE, 0xEE, 0xEE, 0xEE}));
}

TEST_F(FmmuTest, ReadWriteTypeReturnsOldAndWritesNew) {
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x500, 2, 0, 7, 0x1700, 0, 3));
  line.master->fpwr(0x1001, 0x1700, {0x12, 0x34});
  const auto r = line.master->send_logical(Command::Lrw, 0x500, {0xAB, 0xCD});
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0x12, 0x34}));
  EXPECT_EQ(r.wkc, 3);
  EXPECT_EQ(line.esc(0).read16(0x1700), 0xCDAB);
}

TEST_F(FmmuTest, InactiveFmmuMapsNothing) {
  auto f = fmmu_entry(0x600, 1, 0, 7, 0x1800, 0, 1);
  f[12] = 0;  // activate bit clear
  line.master->fpwr(0x1001, 0x0600, f);
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x600, {0}).wkc, 0);
}

TEST_F(FmmuTest, MapsRegisterSm1Status) {
  // SOEM 2.x maps 0x080D (SM1 status) into the cyclic frame to see mailbox replies.
  Line l(1);
  l.to_preop();
  l.master->fpwr(0x1001, 0x0620, fmmu_entry(0x9000, 1, 0, 7, 0x080D, 0, 1));
  EXPECT_EQ(l.master->send_logical(Command::Lrd, 0x9000, {0}).data[0] & 0x08, 0);
  std::vector<uint8_t> msg = {2, 0, 0, 0, 0, 0x13, 0xAA, 0xBB};
  msg.resize(kMbxSize, 0);
  l.master->fpwr(0x1001, kMbxOutStart, msg);
  const auto r = l.master->send_logical(Command::Lrd, 0x9000, {0});
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data[0] & 0x08, 0x08);  // mailbox full
}

TEST_F(FmmuTest, MappingPastTheAddressSpaceIsIgnored) {
  line.master->fpwr(0x1001, 0x0600, fmmu_entry(0x700, 4, 0, 7, 0xFFFE, 0, 1));
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x700, {0, 0, 0, 0}).wkc, 0);
}

}  // namespace
}  // namespace rackcat::ecat::test
