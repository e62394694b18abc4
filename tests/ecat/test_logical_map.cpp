// The line's logical-address map (ecat/logical_map.*, ETG.1000.4 §6.6): LRD/LWR/LRW reach the
// ESCs whose FMMUs meet them, and only those; working counters stay ETG.1000.4 §5.4.4's (LRD
// and LWR +1, LRW +1 read +2 write, once per ESC per datagram however many of its FMMUs match).
// Expected bytes follow from the FMMU registers written (0x0600 + 16n: logical start, length,
// start bit, stop bit, physical start, physical bit, type, enable).
#include <gtest/gtest.h>

#include "ecat/logical_map.hpp"
#include "tests/ecat/test_master.hpp"
#include "tests/support/fmmu_entry.hpp"

namespace rackcat::ecat::test {
namespace {

using rackcat::testing::fmmu_entry;
constexpr uint8_t kRead = 1;
constexpr uint8_t kWrite = 2;

struct LogicalMapTest : ::testing::Test {
  explicit LogicalMapTest(size_t n = 3) : line(n) {
    for (size_t i = 0; i < n; ++i) {
      line.master->send(Command::Apwr, static_cast<uint16_t>(0 - i), 0x0010,
                        bytes16(Line::station(i)));
    }
  }
  void map(size_t slave, int index, const std::vector<uint8_t>& f) {
    ASSERT_EQ(
        line.master->fpwr(Line::station(slave), static_cast<uint16_t>(0x0600 + 16 * index), f).wkc,
        1);
  }
  void poke(size_t slave, uint16_t address, std::vector<uint8_t> bytes) {
    ASSERT_EQ(line.master->fpwr(Line::station(slave), address, std::move(bytes)).wkc, 1);
  }
  Line line;
};

TEST_F(LogicalMapTest, OverlappingFmmusOfTwoEscsAnswerInLineOrder) {
  // Slave 0 reads logical 0x1000-0x1001, slave 1 reads 0x1001-0x1002: byte 0x1001 is mapped by
  // both; the frame passes slave 0 first, so slave 1's byte is what comes back.
  map(0, 0, fmmu_entry(0x1000, 2, 0, 7, 0x1100, 0, kRead));
  map(1, 0, fmmu_entry(0x1001, 2, 0, 7, 0x1100, 0, kRead));
  poke(0, 0x1100, {0x10, 0x11});
  poke(1, 0x1100, {0x21, 0x22});
  const auto r = line.master->send_logical(Command::Lrd, 0x1000, {0xEE, 0xEE, 0xEE, 0xEE});
  EXPECT_EQ(r.wkc, 2);
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0x10, 0x21, 0x22, 0xEE}));
  // Slave 2 has no FMMU: it is not in the map at all.
  EXPECT_EQ(line.segment->logical_map().entries(), 2u);
  // The same datagram again (the map's cached targets) gives the same answer.
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x1000, {0xEE, 0xEE, 0xEE, 0xEE}).data,
            (std::vector<uint8_t>{0x10, 0x21, 0x22, 0xEE}));
}

TEST_F(LogicalMapTest, ReadAndWriteFmmusOfOneEscCountOnceEach) {
  // FMMU0 writes logical 0x0-0x1 to 0x1100, FMMU1 reads 0x2-0x3 from 0x1200, FMMU2 writes
  // 0x4 to 0x1300: one LRW over all of it counts +1 (read) +2 (write) for this ESC, once.
  map(0, 0, fmmu_entry(0x0, 2, 0, 7, 0x1100, 0, kWrite));
  map(0, 1, fmmu_entry(0x2, 2, 0, 7, 0x1200, 0, kRead));
  map(0, 2, fmmu_entry(0x4, 1, 0, 7, 0x1300, 0, kWrite));
  poke(0, 0x1200, {0xC1, 0xC2});
  const auto r = line.master->send_logical(Command::Lrw, 0x0, {0xA1, 0xA2, 0x00, 0x00, 0xA5});
  EXPECT_EQ(r.wkc, 3);
  // Written bytes are not read back (no read FMMU over them); the read ones are.
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0xA1, 0xA2, 0xC1, 0xC2, 0xA5}));
  EXPECT_EQ(line.esc(0).read16(0x1100), 0xA2A1);
  EXPECT_EQ(line.esc(0).read8(0x1300), 0xA5);
  // Only the write FMMUs inside the datagram: +2; only the read one: +1.
  EXPECT_EQ(line.master->send_logical(Command::Lrw, 0x0, {1, 2}).wkc, 2);
  EXPECT_EQ(line.master->send_logical(Command::Lrw, 0x2, {0, 0}).wkc, 1);
  // LWR over read and write FMMUs: +1 for the ESC, reads nothing.
  const auto w = line.master->send_logical(Command::Lwr, 0x0, {7, 8, 9, 9, 6});
  EXPECT_EQ(w.wkc, 1);
  EXPECT_EQ(w.data, (std::vector<uint8_t>{7, 8, 9, 9, 6}));
}

TEST_F(LogicalMapTest, AnFmmuDisabledAndReEnabledMidRun) {
  map(1, 3, fmmu_entry(0x40, 1, 0, 7, 0x1100, 0, kRead));
  poke(1, 0x1100, {0x5A});
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x40, {0}).wkc, 1);
  // Enable 0x063C bit 0 cleared: the ESC no longer answers; the map follows.
  poke(1, 0x063C, {0x00});
  auto r = line.master->send_logical(Command::Lrd, 0x40, {0x77});
  EXPECT_EQ(r.wkc, 0);
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0x77}));
  EXPECT_EQ(line.segment->logical_map().entries(), 0u);
  poke(1, 0x063C, {0x01});
  r = line.master->send_logical(Command::Lrd, 0x40, {0x77});
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0x5A}));
  // Moved to another logical address: the old one is empty, the new one answers.
  map(1, 3, fmmu_entry(0x80, 1, 0, 7, 0x1100, 0, kRead));
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x40, {0}).wkc, 0);
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x80, {0}).wkc, 1);
}

TEST_F(LogicalMapTest, BitGranularFmmusOfTwoEscsShareOneLogicalByte) {
  // Logical 0x10 bits 0-3 -> slave 0's 0x1100 bits 0-3; bits 4-7 -> slave 1's 0x1100 bits 0-3.
  map(0, 0, fmmu_entry(0x10, 1, 0, 3, 0x1100, 0, kWrite));
  map(1, 0, fmmu_entry(0x10, 1, 4, 7, 0x1100, 0, kWrite));
  EXPECT_EQ(line.master->send_logical(Command::Lwr, 0x10, {0xA5}).wkc, 2);
  EXPECT_EQ(line.esc(0).read8(0x1100), 0x05);
  EXPECT_EQ(line.esc(1).read8(0x1100), 0x0A);
  // The next byte meets neither.
  EXPECT_EQ(line.master->send_logical(Command::Lwr, 0x11, {0xFF}).wkc, 0);
  // Logical 0x20 bit 4 .. 0x21 bit 3 on slave 2: a datagram on 0x21 alone meets bits 0-3 of it,
  // one on 0x22 does not.
  map(2, 0, fmmu_entry(0x20, 2, 4, 3, 0x1100, 0, kRead));
  poke(2, 0x1100, {0xDA});
  auto r = line.master->send_logical(Command::Lrd, 0x21, {0xF0});
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0xFD}));  // bits 0-3 <- physical bits 4-7 (0xD)
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x22, {0}).wkc, 0);
  // One byte whose stop bit lies before its start bit maps nothing.
  map(2, 1, fmmu_entry(0x30, 1, 4, 3, 0x1200, 0, kRead));
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x30, {0}).wkc, 0);
}

TEST_F(LogicalMapTest, ARangeStraddlingTwoEscs) {
  map(0, 0, fmmu_entry(0x100, 4, 0, 7, 0x1100, 0, kRead));
  map(1, 0, fmmu_entry(0x104, 4, 0, 7, 0x1100, 0, kRead));
  poke(0, 0x1100, {0x00, 0x01, 0x02, 0x03});
  poke(1, 0x1100, {0x10, 0x11, 0x12, 0x13});
  const auto r = line.master->send_logical(Command::Lrd, 0x102, {0, 0, 0, 0});
  EXPECT_EQ(r.wkc, 2);
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0x02, 0x03, 0x10, 0x11}));
  // Ending exactly before slave 1's range: slave 0 only.
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x102, {0, 0}).wkc, 1);
}

TEST_F(LogicalMapTest, AnFmmuWrittenInTheSameFrameAsTheLogicalDatagram) {
  // Frame: FPWR of slave 1's FMMU0, then an LRD over it. Slave 1 sees its FMMU before the LRD
  // reaches it (the frame passes each ESC datagram by datagram), so it answers in this frame.
  map(0, 0, fmmu_entry(0x200, 1, 0, 7, 0x1100, 0, kRead));
  poke(0, 0x1100, {0x0A});
  poke(1, 0x1100, {0x1B});
  EXPECT_EQ(line.master->send_logical(Command::Lrd, 0x200, {0, 0}).wkc, 1);  // map built
  FrameBuilder frame;
  frame.add(Command::Fpwr, Line::station(1), 0x0600, fmmu_entry(0x201, 1, 0, 7, 0x1100, 0, kRead));
  frame.add_logical(Command::Lrd, 0x200, {0, 0});
  const auto replies = line.master->send_frame(frame);
  ASSERT_EQ(replies.size(), 2u);
  EXPECT_EQ(replies[0].wkc, 1);
  EXPECT_EQ(replies[1].wkc, 2);
  EXPECT_EQ(replies[1].data, (std::vector<uint8_t>{0x0A, 0x1B}));
}

TEST_F(LogicalMapTest, AnFmmuActivatedThroughAnFmmuByTheCyclicFrame) {
  // A frame of one LRW (the path of a master's cyclic frame). Slave 0 writes, through its
  // FMMU0, the activate byte of its own FMMU1 (0x061C), which maps logical 0x601 onto its byte
  // 0x1100. The datagram was planned without that FMMU: slave 0 counts its write only, and the
  // rest of the line still answers. The next frame finds FMMU1 and slave 0 reads as well; slave
  // 1, later on the line, puts its byte over slave 0's.
  map(0, 1, fmmu_entry(0x601, 1, 0, 7, 0x1100, 0, kRead, 0x00));
  map(0, 0, fmmu_entry(0x600, 1, 0, 7, 0x061C, 0, kWrite));
  map(1, 0, fmmu_entry(0x601, 1, 0, 7, 0x1100, 0, kRead));
  poke(0, 0x1100, {0x0A});
  poke(1, 0x1100, {0x1B});
  const auto first = line.master->send_logical(Command::Lrw, 0x600, {0x01, 0x00});
  EXPECT_EQ(first.wkc, 2 + 1);
  EXPECT_EQ(first.data, (std::vector<uint8_t>{0x01, 0x1B}));
  const auto second = line.master->send_logical(Command::Lrw, 0x600, {0x01, 0x00});
  EXPECT_EQ(second.wkc, 2 + 1 + 1);
  EXPECT_EQ(second.data, (std::vector<uint8_t>{0x01, 0x1B}));
}

TEST_F(LogicalMapTest, ManyLogicalDatagramsInOneFrame) {
  // More distinct logical datagrams than the map resolves per frame: the rest are answered
  // all the same (through each ESC's own FMMUs).
  for (size_t s = 0; s < 3; ++s) {
    map(s, 0, fmmu_entry(static_cast<uint32_t>(0x300 + s), 1, 0, 7, 0x1100, 0, kRead));
    poke(s, 0x1100, {static_cast<uint8_t>(0xB0 + s)});
  }
  FrameBuilder frame;
  const size_t n = LogicalMap::kCachedRanges + 4;
  // Three ranges that reach one slave each, repeated, then n distinct ranges nobody maps.
  for (size_t d = 0; d < n; ++d) {
    frame.add_logical(Command::Lrd, static_cast<uint32_t>(0x300 + d % 3), {0});
  }
  for (size_t d = 0; d < n; ++d) {
    frame.add_logical(Command::Lrd, static_cast<uint32_t>(0x400 + d), {0});
  }
  const auto replies = line.master->send_frame(frame);
  ASSERT_EQ(replies.size(), 2 * n);
  for (size_t d = 0; d < n; ++d) {
    EXPECT_EQ(replies[d].wkc, 1) << d;
    EXPECT_EQ(replies[d].data[0], 0xB0 + d % 3) << d;
    EXPECT_EQ(replies[n + d].wkc, 0) << d;
  }
}

TEST(LogicalMap, ResolvesTargetsInLineOrderWithTheirFmmus) {
  LogicalMap m(4, 16);
  // Laid out against line order: slave 3 first in the logical space.
  m.add(3, 0, 15, 0);
  m.add(1, 16, 31, 2);
  m.add(1, 8, 11, 5);  // overlaps slave 3's range
  m.add(0, 64, 71, 1);
  m.finish();
  m.begin_frame();
  const auto* t = m.resolve(0, 4);  // bits 0-31
  ASSERT_NE(t, nullptr);
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ((*t)[0].slave, 1u);
  EXPECT_EQ((*t)[0].fmmus, (1u << 2) | (1u << 5));
  EXPECT_EQ((*t)[1].slave, 3u);
  EXPECT_EQ((*t)[1].fmmus, 1u);
  EXPECT_TRUE(m.resolve(4, 4)->empty());
  ASSERT_EQ(m.resolve(8, 1)->size(), 1u);
  EXPECT_EQ(m.resolve(8, 1)->front().slave, 0u);
}

}  // namespace
}  // namespace rackcat::ecat::test
