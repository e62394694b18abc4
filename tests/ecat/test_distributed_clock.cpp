// Distributed clocks (ETG.1000.4 §6.10, §9): receive-time latches with the line's propagation
// delays, local/system time, offset and delay, the FRMW compare into 0x092C and the control
// loop, SYNC0/SYNC1 generation on a manual clock.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdlib>

#include "ecat/registers.hpp"
#include "tests/ecat/chip_master.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

TEST(DistributedClock, ReceiveTimesFollowTheLine) {
  Line line(3);
  line.to_preop();
  line.clock.advance(5'000'000);
  EXPECT_EQ(line.master->send(Command::Bwr, 0, 0x0900, {0, 0, 0, 0}).wkc, 3);
  // Defaults: 320 ns forward through a slave, 280 ns back, 10 ns per cable. Slave 0 sees the
  // frame return at port 1 after it went through slaves 1 and 2: 330 + (320 + 20 + 320 + 280)
  // + 10 ns; slave 1 after slave 2 only: 330 + 320 + 10 ns.
  const uint32_t p0_0 = line.master->fprd32(Line::station(0), 0x0900);
  const uint32_t p1_0 = line.master->fprd32(Line::station(0), 0x0904);
  const uint32_t p0_1 = line.master->fprd32(Line::station(1), 0x0900);
  const uint32_t p1_1 = line.master->fprd32(Line::station(1), 0x0904);
  EXPECT_EQ(p1_0 - p0_0, 1280u);
  EXPECT_EQ(p1_1 - p0_1, 660u);
  EXPECT_EQ(line.master->fprd32(Line::station(2), 0x0904), 0u);  // no link on port 1
  // 0x0918: 64-bit local time at the processing unit, same instant as port 0.
  const uint64_t r0 = line.master->fprd64(Line::station(0), 0x0918);
  const uint64_t r1 = line.master->fprd64(Line::station(1), 0x0918);
  EXPECT_EQ(static_cast<uint32_t>(r0), p0_0);
  // Local clocks started at power-up: slave 1 powered up 1'234'567 ns "earlier" and sees the
  // frame 330 ns later.
  EXPECT_EQ(r0, 5'000'000u);
  EXPECT_EQ(r1, 5'000'000u + 1'234'567u + 330u);
}

TEST(DistributedClock, SystemTimeIsLocalTimePlusOffset) {
  Line line(1);
  line.to_preop();
  const uint64_t t1 = line.master->fprd64(0x1001, 0x0910);
  line.clock.advance(1000);
  EXPECT_EQ(line.master->fprd64(0x1001, 0x0910), t1 + 1000);
  line.master->fpwr64(0x1001, 0x0920, 1'000'000'000'000ull);
  EXPECT_EQ(line.master->fprd64(0x1001, 0x0910), t1 + 1000 + 1'000'000'000'000ull);
  EXPECT_EQ(line.esc(0).system_time(line.clock.now_ns()), t1 + 1000 + 1'000'000'000'000ull);
}

struct DriftTest : ::testing::Test {
  DriftTest() : line(2) {
    line.to_preop();
    line.master->send(Command::Bwr, 0, 0x0900, {0, 0, 0, 0});
    const uint64_t r0 = line.master->fprd64(Line::station(0), 0x0918);
    const uint64_t r1 = line.master->fprd64(Line::station(1), 0x0918);
    // Master side of ETG.1000.4 §9.1.3: align slave 1 to the reference (slave 0), with the
    // propagation delay of 330 ns between them.
    offset1 = r0 + 330 - r1;
    line.master->fpwr64(Line::station(1), 0x0920, offset1);
    line.master->fpwr32(Line::station(1), 0x0928, 330);
  }
  uint32_t frmw() {
    line.master->send(Command::Frmw, Line::station(0), 0x0910, std::vector<uint8_t>(8, 0));
    return line.master->fprd32(Line::station(1), 0x092C);
  }
  Line line;
  uint64_t offset1 = 0;
};

TEST_F(DriftTest, AlignedClocksShowNoDifference) {
  const auto r =
      line.master->send(Command::Frmw, Line::station(0), 0x0910, std::vector<uint8_t>(8, 0));
  EXPECT_EQ(r.wkc, 2);  // reference reads, slave 1 writes
  EXPECT_EQ(line.master->fprd32(Line::station(1), 0x092C), 0u);
}

TEST_F(DriftTest, DifferenceIsReportedAndCompensated) {
  line.master->fpwr64(Line::station(1), 0x0920, offset1 - 500);  // slave 1 runs 500 ns behind
  // Bit 31: the local copy is smaller than the received time; bits 30:0: 500 ns.
  EXPECT_EQ(frmw(), 0x80000000u | 500u);
  uint32_t diff = 0;
  for (int i = 0; i < 20; ++i) diff = frmw();
  EXPECT_LE(diff & 0x7FFFFFFF, 1u);
}

TEST_F(DriftTest, HugeDifferenceIsReportedButNotFollowed) {
  // SOEM's reset write of 0 to 0x0910 (5 s after power-up): reported, clock not stepped.
  line.clock.advance(5'000'000'000);
  const uint64_t before = line.esc(1).local_time(line.clock.now_ns());
  line.master->send(Command::Bwr, 0, 0x0910, {0, 0, 0, 0});
  EXPECT_EQ(line.esc(1).local_time(line.clock.now_ns()), before);
  EXPECT_NE(line.master->fprd32(Line::station(1), 0x092C), 0u);
}

// The ARMW/FRMW of the system time that a DC master sends every cycle (ETG.1000.4 §9), checked
// against the ESC datasheet rule for 0x0910 "write: compare with local copy": the reference
// (the addressed slave) returns its system time; every other slave adds its delay 0x0928 to
// the received time (all 64 bits, or the low 32 for a 4-byte access), reports the difference
// to its own system time in 0x092C (bit 31: local copy smaller, bits 30:0 the magnitude) and
// moves its clock half-way towards the reference when the difference is below 1 ms.
struct SystemTimeCompare : ::testing::Test {
  static constexpr size_t kSlaves = 5;
  // Received time + delay - local system time per slave (slave 0 is the reference); the last
  // is small in its low 32 bits only.
  static constexpr std::array<int64_t, kSlaves> kDiff = {0, 500, -301, 1,
                                                         500'000 - (int64_t{7} << 32)};
  static constexpr std::array<uint32_t, kSlaves> kDelay = {0, 330, 660, 990, 1320};

  SystemTimeCompare() : line(kSlaves) {
    line.to_preop();
    line.clock.advance(3'000'000'000);
    const uint64_t reference = system_time(0);
    for (size_t k = 1; k < kSlaves; ++k) {
      const uint64_t wanted = reference + kDelay[k] - static_cast<uint64_t>(kDiff[k]);
      line.master->fpwr32(Line::station(k), reg::kDcSystemTimeDelay, kDelay[k]);
      line.master->fpwr64(Line::station(k), reg::kDcSystemTimeOffset,
                          wanted - system_time(k) + offset(k));
    }
  }
  uint64_t system_time(size_t k) { return line.master->fprd64(Line::station(k), 0x0910); }
  uint64_t offset(size_t k) { return line.master->fprd64(Line::station(k), 0x0920); }
  uint32_t difference(size_t k) { return line.master->fprd32(Line::station(k), 0x092C); }
  static uint32_t expected_difference(int64_t diff) {
    uint32_t v = static_cast<uint32_t>(std::min<uint64_t>(std::llabs(diff), 0x7FFFFFFF));
    return diff > 0 ? v | 0x80000000u : v;
  }
  static int64_t expected_step(int64_t diff) {
    if (diff == 0 || diff <= -1'000'000 || diff >= 1'000'000) return 0;
    return diff / 2 != 0 ? diff / 2 : diff;
  }
  // The difference a compare of `bytes` bytes sees for slave k.
  static int64_t seen(size_t k, uint16_t bytes) {
    return bytes == 8 ? kDiff[k] : static_cast<int32_t>(static_cast<uint32_t>(kDiff[k]));
  }
  // Sends `cmd` (the reference addressed) over `len` bytes at `ado` and checks every slave.
  void compare(Command cmd, uint16_t ado, uint16_t len, uint16_t bytes) {
    std::array<uint64_t, kSlaves> before{};
    for (size_t k = 0; k < kSlaves; ++k) before[k] = system_time(k);
    const std::vector<uint8_t> untouched = {line.esc(1).memory().begin() + 0x0910,
                                            line.esc(1).memory().begin() + 0x0918};
    const uint16_t adp = cmd == Command::Armw ? 0 : Line::station(0);
    const Reply r = line.master->send(cmd, adp, ado, std::vector<uint8_t>(len, 0xEE));
    EXPECT_EQ(r.wkc, kSlaves);  // the reference reads, every other slave writes
    const size_t at = 0x0910 - ado;
    uint64_t returned = 0;
    for (size_t i = 0; i < bytes; ++i) returned |= static_cast<uint64_t>(r.data[at + i]) << 8 * i;
    const uint64_t mask = bytes == 8 ? ~uint64_t{0} : 0xFFFFFFFFu;
    EXPECT_EQ(returned, before[0] & mask);
    // A compare does not latch: 0x0910 keeps what the last read latched.
    EXPECT_EQ(std::vector<uint8_t>(line.esc(1).memory().begin() + 0x0910,
                                   line.esc(1).memory().begin() + 0x0918),
              untouched);
    for (size_t k = 1; k < kSlaves; ++k) {
      SCOPED_TRACE(k);
      EXPECT_EQ(difference(k), expected_difference(seen(k, bytes)));
      EXPECT_EQ(system_time(k), before[k] + static_cast<uint64_t>(expected_step(seen(k, bytes))));
    }
  }
  Line line;
};

TEST_F(SystemTimeCompare, FrmwOf64Bits) {
  compare(Command::Frmw, 0x0910, 8, 8);
}
TEST_F(SystemTimeCompare, FrmwOf32Bits) {
  compare(Command::Frmw, 0x0910, 4, 4);
}
TEST_F(SystemTimeCompare, ArmwOf64Bits) {
  compare(Command::Armw, 0x0910, 8, 8);
}
TEST_F(SystemTimeCompare, ArmwOf32Bits) {
  compare(Command::Armw, 0x0910, 4, 4);
}
TEST_F(SystemTimeCompare, FrmwAroundTheSystemTimeComparesAll64Bits) {
  compare(Command::Frmw, 0x090C, 12, 8);  // receive time port 3, then the system time
}
TEST_F(SystemTimeCompare, FrmwFromTheMiddleComparesNothing) {
  const uint32_t before = difference(1);
  EXPECT_EQ(line.master->send(Command::Frmw, Line::station(0), 0x0914, {0, 0, 0, 0}).wkc, kSlaves);
  EXPECT_EQ(difference(1), before);
}

TEST_F(SystemTimeCompare, ReadWriteReturnsTheTimeAndCompares) {
  // FPRW: the old content goes back (WKC +1) while the incoming time is compared (+2).
  std::array<uint64_t, kSlaves> before{};
  for (size_t k = 0; k < kSlaves; ++k) before[k] = system_time(k);
  const uint32_t untouched = difference(2);
  const uint64_t sent = before[1] - kDelay[1] + 400;
  std::vector<uint8_t> data(8);
  for (size_t i = 0; i < 8; ++i) data[i] = static_cast<uint8_t>(sent >> 8 * i);
  const Reply r = line.master->send(Command::Fprw, Line::station(1), 0x0910, data);
  EXPECT_EQ(r.wkc, 3);
  uint64_t returned = 0;
  for (size_t i = 0; i < 8; ++i) returned |= static_cast<uint64_t>(r.data[i]) << 8 * i;
  EXPECT_EQ(returned, before[1]);
  EXPECT_EQ(difference(1), expected_difference(400));
  EXPECT_EQ(system_time(1), before[1] + 200);
  EXPECT_EQ(difference(2), untouched);  // not addressed
}

TEST_F(SystemTimeCompare, BroadcastReadsOrTheTimes) {
  // BRD and BRW OR every slave's time into the datagram; BRD counts 1 per slave, BRW 3.
  uint64_t ored = 0;
  for (size_t k = 0; k < kSlaves; ++k) ored |= system_time(k);
  for (const Command cmd : {Command::Brd, Command::Brw}) {
    SCOPED_TRACE(static_cast<int>(cmd));
    const Reply r = line.master->send(cmd, 0, 0x0910, std::vector<uint8_t>(8, 0));
    EXPECT_EQ(r.wkc, cmd == Command::Brd ? kSlaves : 3 * kSlaves);
    uint64_t returned = 0;
    for (size_t i = 0; i < 8; ++i) returned |= static_cast<uint64_t>(r.data[i]) << 8 * i;
    EXPECT_EQ(returned, ored);
  }
}

TEST_F(SystemTimeCompare, WriteProtectedSlaveDiscardsTheCompare) {
  // Register write protection (0x0021 bit 0) without the enable 0x0020 in the same frame: the
  // write is discarded and gets no working counter.
  EXPECT_EQ(line.master->fpwr8(Line::station(1), reg::kWriteProtection, 0x01), 1);
  const uint64_t before = system_time(1);
  const uint32_t diff_before = difference(1);
  const Reply r =
      line.master->send(Command::Frmw, Line::station(0), 0x0910, std::vector<uint8_t>(8, 0));
  EXPECT_EQ(r.wkc, kSlaves - 1);
  EXPECT_EQ(difference(1), diff_before);
  EXPECT_EQ(system_time(1), before);
  EXPECT_EQ(difference(2), expected_difference(kDiff[2]));
}

TEST(DistributedClock, SyncManagerOverTheSystemTimeKeepsItsBufferRules) {
  // A mailbox the master writes placed over 0x0910 (ETG.1000.4 §6.7.1): the first write
  // fills it, the next is refused (no WKC) until the PDI has read it.
  ChipMaster chip;
  chip.sm(0, 0x0910, 8, 0x26);
  EXPECT_EQ(chip.datagram(Command::Apwr, 0, 0x0910, std::vector<uint8_t>(8, 0)).second, 1);
  EXPECT_EQ(chip.esc.read8(0x0805) & 0x08, 0x08);
  EXPECT_EQ(chip.datagram(Command::Apwr, 0, 0x0910, std::vector<uint8_t>(8, 0)).second, 0);
}

TEST(DistributedClock, Sync0FiresEveryCycle) {
  Line line(1);
  line.to_preop();
  const uint64_t now = line.master->fprd64(0x1001, 0x0910);
  const uint64_t start = now + 1'000'000;
  line.master->fpwr64(0x1001, 0x0990, start);
  line.master->fpwr32(0x1001, 0x09A0, 1'000'000);
  line.master->fpwr8(0x1001, 0x0981, 0x03);
  EXPECT_EQ(line.master->fprd8(0x1001, 0x0984) & 0x01, 0x01);  // first pulse pending
  EXPECT_EQ(line.segment->next_sync_event_ns(), line.clock.now_ns() + 1'000'000);
  for (int i = 0; i < 10; ++i) {
    line.clock.advance(1'000'000);
    line.segment->service();
  }
  auto& syncs = line.app(0).syncs;
  ASSERT_EQ(syncs.size(), 10u);
  for (size_t i = 0; i < syncs.size(); ++i) {
    EXPECT_EQ(syncs[i], std::make_pair(0, start + i * 1'000'000));
  }
  EXPECT_EQ(line.master->fprd64(0x1001, 0x0990), start + 10'000'000);  // next pulse
  // The firmware took each pulse: its PDI read of the SYNC0 status cleared it (ESC datasheet
  // 0x098E) and the AL event (0x0220 bit 2).
  EXPECT_EQ(line.master->fprd8(0x1001, 0x098E) & 0x01, 0x00);
  EXPECT_EQ(line.esc(0).read8(0x0220) & 0x04, 0x00);
  EXPECT_EQ(line.master->fprd8(0x1001, 0x0984) & 0x01, 0x00);
}

TEST(DistributedClock, LateServiceFiresOnceForTheLatestPulse) {
  Line line(1);
  line.to_preop();
  const uint64_t start = line.master->fprd64(0x1001, 0x0910) + 1'000'000;
  line.master->fpwr64(0x1001, 0x0990, start);
  line.master->fpwr32(0x1001, 0x09A0, 1'000'000);
  line.master->fpwr8(0x1001, 0x0981, 0x03);
  line.clock.advance(10'500'000);
  line.segment->service();
  ASSERT_EQ(line.app(0).syncs.size(), 1u);
  EXPECT_EQ(line.app(0).syncs[0].second, start + 9'000'000);
  EXPECT_EQ(line.segment->next_sync_event_ns(), line.clock.now_ns() + 500'000);
}

TEST(DistributedClock, Sync1FollowsSync0ByItsCycleTime) {
  Line line(1);
  line.to_preop();
  const uint64_t start = line.master->fprd64(0x1001, 0x0910) + 1'000'000;
  line.master->fpwr64(0x1001, 0x0990, start);
  line.master->fpwr32(0x1001, 0x09A0, 1'000'000);
  line.master->fpwr32(0x1001, 0x09A4, 200'000);
  line.master->fpwr8(0x1001, 0x0981, 0x07);
  line.clock.advance(1'000'000);
  line.segment->service();
  EXPECT_EQ(line.segment->next_sync_event_ns(), line.clock.now_ns() + 200'000);
  line.clock.advance(200'000);
  line.segment->service();
  const std::vector<std::pair<int, uint64_t>> expected = {{0, start}, {1, start + 200'000}};
  EXPECT_EQ(line.app(0).syncs, expected);
}

TEST(DistributedClock, StartTimeInThePastStartsAtNextCycle) {
  Line line(1);
  line.to_preop();
  const uint64_t now = line.master->fprd64(0x1001, 0x0910);
  line.master->fpwr64(0x1001, 0x0990, now - 2'500'000);
  line.master->fpwr32(0x1001, 0x09A0, 1'000'000);
  line.master->fpwr8(0x1001, 0x0981, 0x03);
  EXPECT_EQ(line.master->fprd64(0x1001, 0x0990), now + 500'000);
}

TEST(DistributedClock, DeactivationStopsSync) {
  Line line(1);
  line.to_preop();
  line.master->fpwr64(0x1001, 0x0990, line.master->fprd64(0x1001, 0x0910) + 1000);
  line.master->fpwr32(0x1001, 0x09A0, 1'000'000);
  line.master->fpwr8(0x1001, 0x0981, 0x03);
  line.master->fpwr8(0x1001, 0x0981, 0x00);
  EXPECT_EQ(line.segment->next_sync_event_ns(), UINT64_MAX);
  line.clock.advance(5'000'000);
  line.segment->service();
  EXPECT_TRUE(line.app(0).syncs.empty());
}

}  // namespace
}  // namespace rackcat::ecat::test
