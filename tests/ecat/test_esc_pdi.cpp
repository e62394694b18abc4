// The chip alone, no firmware: what the ESC's PDI side does (ETG.1000.4 §6.5, §6.7; ESC
// datasheet "PDI access" and 0x0220): AL event requests and the IRQ line, the reads that
// clear them, PDI-writable registers, and the SyncManager hand-over between the EtherCAT side
// (datagrams) and the PDI side (pdi_read / pdi_write).
#include <gtest/gtest.h>

#include <vector>

#include "ecat/esc/esc.hpp"
#include "tests/ecat/chip_master.hpp"
#include "tests/support/fmmu_entry.hpp"

namespace rackcat::ecat::test {
namespace {

struct ChipTest : ::testing::Test, ChipMaster {
  uint32_t al_events() const { return esc.read32(0x0220); }
  uint8_t pdi8(uint16_t a) {
    uint8_t v = 0;
    esc.pdi_read(a, &v, 1);
    return v;
  }
  void pdi_write8(uint16_t a, uint8_t v) { esc.pdi_write(a, &v, 1); }
};

TEST_F(ChipTest, ResetStateIsInitWithEverySmDeactivatedForThePdi) {
  EXPECT_EQ(esc.al_status(), 0x01);
  for (int n = 0; n < 16; ++n) EXPECT_EQ(esc.read8(0x0807 + 8 * n) & 0x01, 0x01);
  EXPECT_TRUE(esc.take_reset());
  EXPECT_FALSE(esc.take_reset());
}

TEST_F(ChipTest, AlControlRaisesAnEventThePdiReadClears) {
  EXPECT_FALSE(esc.pdi_irq());
  esc.pdi_write(0x0204, std::vector<uint8_t>{0x01, 0, 0, 0}.data(), 4);
  apwr(0x0120, {0x02});
  EXPECT_EQ(al_events() & 0x01, 0x01u);
  EXPECT_TRUE(esc.pdi_irq());
  // The chip does not change state by itself: AL status stays what the PDI wrote.
  EXPECT_EQ(esc.al_status(), 0x01);
  EXPECT_EQ(pdi8(0x0120), 0x02);
  EXPECT_EQ(al_events() & 0x01, 0x00u);
  EXPECT_FALSE(esc.pdi_irq());
}

TEST_F(ChipTest, PdiWritesOnlyItsRegisters) {
  esc.pdi_write(0x0130, std::vector<uint8_t>{0x12, 0x00}.data(), 2);
  esc.pdi_write(0x0134, std::vector<uint8_t>{0x1D, 0x00}.data(), 2);
  EXPECT_EQ(esc.read16(0x0130), 0x0012);
  EXPECT_EQ(esc.read16(0x0134), 0x001D);
  EXPECT_EQ(esc.read16(0x0210) & 0x0008, 0x0008);  // AL status event for the master
  pdi_write8(0x0010, 0x55);                        // station address: ECAT only
  pdi_write8(0x0120, 0x08);                        // AL control: ECAT only
  EXPECT_EQ(esc.read8(0x0010), 0x00);
  EXPECT_EQ(esc.read8(0x0120), 0x01);
  const auto r = aprd(0x0130, 2);  // the master reads AL status: event cleared
  EXPECT_EQ(r.first[0], 0x12);
  EXPECT_EQ(esc.read16(0x0210) & 0x0008, 0x0000);
}

TEST_F(ChipTest, PdiDeactivatedSmBlocksTheMaster) {
  sm(0, 0x1000, 16, 0x26);
  EXPECT_EQ(apwr(0x1000, std::vector<uint8_t>(16, 1)), 1);
  pdi8(0x1000);
  esc.pdi_read(0x1000, std::vector<uint8_t>(16).data(), 16);  // free it again
  pdi_write8(0x0807, 0x01);
  EXPECT_EQ(apwr(0x1000, std::vector<uint8_t>(16, 1)), 0);
}

TEST_F(ChipTest, MailboxWrittenByTheMasterIsReadAndFreedByThePdi) {
  sm(0, 0x1000, 16, 0x26);  // mailbox, ECAT writes, AL event enabled
  std::vector<uint8_t> msg(16, 0xA5);
  EXPECT_EQ(apwr(0x1000, msg), 1);
  EXPECT_EQ(al_events() & 0x0100, 0x0100u);   // SM0 event for the firmware
  EXPECT_EQ(esc.read8(0x0805) & 0x08, 0x08);  // full
  EXPECT_EQ(apwr(0x1000, msg), 0);            // a full mailbox refuses the master
  std::vector<uint8_t> got(16, 0);
  esc.pdi_read(0x1000, got.data(), 8);  // first byte: event cleared, still full
  EXPECT_EQ(al_events() & 0x0100, 0x0000u);
  EXPECT_EQ(esc.read8(0x0805) & 0x08, 0x08);
  esc.pdi_read(0x1008, got.data() + 8, 8);  // last byte: empty again
  EXPECT_EQ(got, msg);
  EXPECT_EQ(esc.read8(0x0805) & 0x08, 0x00);
  EXPECT_EQ(apwr(0x1000, msg), 1);
}

TEST_F(ChipTest, MailboxWrittenByThePdiIsHandedOverOnItsLastByte) {
  sm(1, 0x1080, 16, 0x22);                // mailbox, ECAT reads
  EXPECT_EQ(aprd(0x1080, 16).second, 0);  // empty: no data for the master
  std::vector<uint8_t> msg(16, 0x3C);
  esc.pdi_write(0x1080, msg.data(), 15);
  EXPECT_EQ(esc.read8(0x080D) & 0x08, 0x00);  // not yet
  esc.pdi_write(0x108F, msg.data() + 15, 1);
  EXPECT_EQ(esc.read8(0x080D) & 0x08, 0x08);
  std::vector<uint8_t> other(16, 0x11);
  esc.pdi_write(0x1080, other.data(), 16);  // full: the PDI write is refused
  const auto r = aprd(0x1080, 16);
  EXPECT_EQ(r.second, 1);
  EXPECT_EQ(r.first, msg);
  EXPECT_EQ(al_events() & 0x0200, 0x0200u);  // read by the master: SM1 event
  esc.pdi_write(0x1080, other.data(), 1);    // first byte clears it
  EXPECT_EQ(al_events() & 0x0200, 0x0000u);
}

TEST_F(ChipTest, BufferedInputsWrittenByThePdiAreWhatTheMasterReads) {
  sm(3, 0x1180, 6, 0x20);
  const std::vector<uint8_t> in{1, 2, 3, 4, 5, 6};
  esc.pdi_write(0x1180, in.data(), 6);
  EXPECT_EQ(esc.read8(0x081D) & 0x01, 0x01);  // buffer written
  EXPECT_EQ(aprd(0x1180, 6).first, in);
  EXPECT_EQ(aprd(0x1180, 6).first, in);  // buffered: readable again, no empty state
}

TEST_F(ChipTest, SmActivationChangeRaisesAnEventTheActivationReadClears) {
  sm(1, 0x1080, 16, 0x22);
  pdi8(0x080E);
  EXPECT_EQ(al_events() & 0x10, 0x00u);
  apwr(0x080E, {0x03});  // the master toggles the repeat request
  EXPECT_EQ(al_events() & 0x10, 0x10u);
  pdi8(0x080E);
  EXPECT_EQ(al_events() & 0x10, 0x00u);
}

TEST_F(ChipTest, Sync0RaisesAnEventTheStatusReadClears) {
  esc.fire_sync(0, 1234);
  EXPECT_EQ(al_events() & 0x04, 0x04u);
  EXPECT_EQ(pdi8(0x098E) & 0x01, 0x01);
  EXPECT_EQ(al_events() & 0x04, 0x00u);
  EXPECT_EQ(esc.read8(0x098E) & 0x01, 0x00);
}

TEST_F(ChipTest, WatchdogExpiryIsAnEventNotAStateChange) {
  sm(2, 0x1100, 4, 0x64);
  apwr(0x1100, {1, 2, 3, 4});  // triggers the watchdog
  clock.advance(200'000'000);
  esc.service(clock.now_ns());
  EXPECT_EQ(esc.read8(0x0440) & 0x01, 0x00);
  EXPECT_EQ(al_events() & 0x40, 0x40u);
  EXPECT_EQ(esc.al_status(), 0x01);  // the firmware decides what follows
  pdi8(0x0440);
  EXPECT_EQ(al_events() & 0x40, 0x00u);
}

// A logical datagram covering only the first bytes of an SM buffer opens the buffer and leaves
// it open; the one that writes its last byte completes it (ETG.1000.4 §6.7.2: the buffer is
// handed over on the last byte, whatever access brings it), raising the SM's AL event.
TEST_F(ChipTest, LrwCoveringPartOfAnOutputBufferDoesNotCompleteIt) {
  using rackcat::testing::fmmu_entry;
  sm(2, 0x1100, 4, 0x64);  // buffered, ECAT writes, AL event, watchdog trigger
  sm(3, 0x1200, 2, 0x20);  // buffered, ECAT reads, AL event
  apwr(0x0600, fmmu_entry(0x500, 4, 0, 7, 0x1100, 0, 2));
  apwr(0x0610, fmmu_entry(0x504, 2, 0, 7, 0x1200, 0, 1));
  const std::vector<uint8_t> in{0x5A, 0xA5};
  esc.pdi_write(0x1200, in.data(), 2);
  // Logical 0x500-0x502: three of SM2's four bytes, none of SM3's.
  auto r = datagram(Command::Lrw, 0x0500, 0, {1, 2, 3});
  EXPECT_EQ(r.second, 2);
  EXPECT_EQ(r.first, (std::vector<uint8_t>{1, 2, 3}));
  EXPECT_EQ(esc.read8(0x0815) & 0x01, 0x00);  // not written yet
  EXPECT_EQ(esc.read8(0x0815) & 0x80, 0x80);  // write buffer open
  EXPECT_EQ(al_events() & 0x0400, 0x0000u);
  // Logical 0x503-0x505: SM2's last byte and SM3's whole buffer.
  r = datagram(Command::Lrw, 0x0503, 0, {4, 0xEE, 0xEE});
  EXPECT_EQ(r.second, 3);
  EXPECT_EQ(r.first, (std::vector<uint8_t>{4, 0x5A, 0xA5}));
  EXPECT_EQ(esc.read8(0x0815) & 0x81, 0x01);  // completed, no longer open
  EXPECT_EQ(al_events() & 0x0400, 0x0400u);
  EXPECT_EQ(esc.read32(0x1100), 0x04030201u);
  EXPECT_EQ(esc.read8(0x081D) & 0x02, 0x02);  // SM3 read by the master
}

// LRW with a read FMMU and write FMMUs on the same logical bytes: every read returns the old
// memory and every write takes the bytes the master sent, not what a read put there
// (ETG.1000.4 §5.4.3); a write FMMU beside them gets its own byte.
TEST_F(ChipTest, LrwReadAndWriteFmmusOnTheSameLogicalBytes) {
  using rackcat::testing::fmmu_entry;
  apwr(0x0600, fmmu_entry(0x600, 2, 0, 7, 0x1300, 0, 1));
  apwr(0x0610, fmmu_entry(0x600, 2, 0, 7, 0x1400, 0, 2));
  apwr(0x0620, fmmu_entry(0x602, 1, 0, 7, 0x1500, 0, 2));
  apwr(0x1300, {0x12, 0x34});
  const auto r = datagram(Command::Lrw, 0x0600, 0, {0xAB, 0xCD, 0xEF});
  EXPECT_EQ(r.second, 3);
  EXPECT_EQ(r.first, (std::vector<uint8_t>{0x12, 0x34, 0xEF}));
  EXPECT_EQ(esc.read16(0x1400), 0xCDAB);
  EXPECT_EQ(esc.read8(0x1500), 0xEF);
  EXPECT_EQ(esc.read16(0x1300), 0x3412);
}

// The FMMUs are configured before the SyncManagers they map (the ESC remembers which SM an FMMU
// meets, so an SM set up, moved or deactivated later must still rule the access, ETG.1000.4
// §6.7): the SM2 buffer completes only with its last byte, and an SM3 the PDI deactivates
// blocks the read (no data, no working counter).
TEST_F(ChipTest, LrwFollowsSyncManagersConfiguredAfterTheFmmus) {
  using rackcat::testing::fmmu_entry;
  apwr(0x0600, fmmu_entry(0x500, 4, 0, 7, 0x1100, 0, 2));
  apwr(0x0610, fmmu_entry(0x504, 2, 0, 7, 0x1200, 0, 1));
  // No SM yet: plain memory, both FMMUs count.
  auto r = datagram(Command::Lrw, 0x0500, 0, {1, 2, 3, 4, 0xEE, 0xEE});
  EXPECT_EQ(r.second, 3);
  sm(2, 0x1100, 4, 0x64);  // buffered, ECAT writes, AL event, watchdog trigger
  sm(3, 0x1200, 2, 0x20);  // buffered, ECAT reads, AL event
  esc.pdi_write(0x1200, std::vector<uint8_t>{0x5A, 0xA5}.data(), 2);
  r = datagram(Command::Lrw, 0x0500, 0, {5, 6, 7});  // three of SM2's four bytes
  EXPECT_EQ(r.second, 2);
  EXPECT_EQ(esc.read8(0x0815) & 0x81, 0x80);  // open, not written
  EXPECT_EQ(al_events() & 0x0400, 0x0000u);
  r = datagram(Command::Lrw, 0x0503, 0, {8, 0xEE, 0xEE});
  EXPECT_EQ(r.second, 3);
  EXPECT_EQ(r.first, (std::vector<uint8_t>{8, 0x5A, 0xA5}));
  EXPECT_EQ(esc.read8(0x0815) & 0x81, 0x01);
  EXPECT_EQ(al_events() & 0x0400, 0x0400u);
  EXPECT_EQ(esc.read32(0x1100), 0x08070605u);
  // The PDI deactivates SM3 (0x081F bit 0): the input FMMU no longer reads.
  pdi_write8(0x081F, 0x01);
  r = datagram(Command::Lrd, 0x0504, 0, {0xEE, 0xEE});
  EXPECT_EQ(r.second, 0);
  EXPECT_EQ(r.first, (std::vector<uint8_t>{0xEE, 0xEE}));
  // SM3 moved away by the master (enabled elsewhere): the FMMU's bytes are plain memory again.
  sm(3, 0x1300, 2, 0x20);
  r = datagram(Command::Lrd, 0x0504, 0, {0xEE, 0xEE});
  EXPECT_EQ(r.second, 1);
  EXPECT_EQ(r.first, (std::vector<uint8_t>{0x5A, 0xA5}));
}

// One write FMMU over two SyncManagers' buffers: one LWR completes both (each SM sees its first
// and last byte), and a second SM placed inside the first one's buffer makes them share bytes.
TEST_F(ChipTest, LwrThroughOneFmmuOverTwoSyncManagers) {
  using rackcat::testing::fmmu_entry;
  sm(2, 0x1100, 2, 0x24);  // buffered, ECAT writes, AL event
  sm(4, 0x1102, 3, 0x24);
  apwr(0x0600, fmmu_entry(0x800, 5, 0, 7, 0x1100, 0, 2));
  auto r = datagram(Command::Lwr, 0x0800, 0, {1, 2, 3, 4, 5});
  EXPECT_EQ(r.second, 1);
  EXPECT_EQ(esc.read8(0x0815) & 0x01, 0x01);
  EXPECT_EQ(esc.read8(0x0825) & 0x01, 0x01);
  EXPECT_EQ(al_events() & 0x1400, 0x1400u);
  EXPECT_EQ(esc.read8(0x1104), 5);
  // SM4 now shares SM2's last byte: a write of the FMMU's first three bytes completes SM2's
  // buffer and opens SM4's without completing it.
  sm(4, 0x1101, 4, 0x24);
  r = datagram(Command::Lwr, 0x0800, 0, {9, 9, 9});
  EXPECT_EQ(r.second, 1);
  EXPECT_EQ(esc.read8(0x0815) & 0x80, 0x00);  // SM2 complete
  EXPECT_EQ(esc.read8(0x0825) & 0x80, 0x80);  // SM4 open
  EXPECT_EQ(esc.read8(0x1102), 9);
}

// Byte-aligned mappings of every short length (the copies without a library call) and a long
// one: each byte lands where the FMMU maps it, nothing beside it changes.
TEST_F(ChipTest, ByteAlignedMappingsOfEveryShortLength) {
  using rackcat::testing::fmmu_entry;
  for (uint16_t len = 1; len <= 20; ++len) {
    apwr(0x0600, fmmu_entry(0x10000, len, 0, 7, 0x2001, 0, 2));
    apwr(0x0610, fmmu_entry(0x20000, len, 0, 7, 0x2001, 0, 1));
    std::vector<uint8_t> guard(len + 2, 0xC3);
    apwr(0x2000, guard);
    std::vector<uint8_t> out(len);
    for (uint16_t i = 0; i < len; ++i) out[i] = static_cast<uint8_t>(0x10 + i);
    auto w = datagram(Command::Lwr, 0x0000, 1, out);  // logical 0x10000
    EXPECT_EQ(w.second, 1) << len;
    const auto back = aprd(0x2000, static_cast<uint16_t>(len + 2)).first;
    EXPECT_EQ(back.front(), 0xC3) << len;
    EXPECT_EQ(back.back(), 0xC3) << len;
    EXPECT_EQ(std::vector<uint8_t>(back.begin() + 1, back.end() - 1), out) << len;
    auto r = datagram(Command::Lrd, 0x0000, 2, std::vector<uint8_t>(len, 0));
    EXPECT_EQ(r.second, 1) << len;
    EXPECT_EQ(r.first, out) << len;
  }
}

}  // namespace
}  // namespace rackcat::ecat::test
