// Register access rules (ESC datasheet section II): read-only identification and status,
// write masks, clear-on-write counters, reset values, the ESC reset sequence.
#include <gtest/gtest.h>

#include "ecat/registers.hpp"
#include "tests/ecat/chip_master.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

constexpr uint16_t kStation = 0x1001;

struct RegisterTest : ::testing::Test {
  RegisterTest() : line(1) { line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation)); }
  Line line;
};

TEST_F(RegisterTest, IdentificationIsReadOnly) {
  EXPECT_EQ(line.master->fpwr(kStation, 0x0000, std::vector<uint8_t>(10, 0xFF)).wkc, 1);
  const auto id = line.master->fprd(kStation, 0x0000, 10).data;
  EXPECT_EQ(id, (std::vector<uint8_t>{0x11, 0x00, 0x02, 0x00, 0x10, 0x10, 0x3C, 0x0F, 0x0C, 0x01}));
}

TEST_F(RegisterTest, AlStatusAndCodeAreReadOnly) {
  line.master->fpwr(kStation, 0x0130, {0x08, 0x00, 0x00, 0x00, 0x1B, 0x00});
  EXPECT_EQ(line.master->fprd16(kStation, 0x0130), 0x0001);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0134), 0x0000);
}

TEST_F(RegisterTest, ResetValues) {
  EXPECT_EQ(line.master->fprd32(kStation, 0x0100), 0x00070001u);  // DL control
  EXPECT_EQ(line.master->fprd16(kStation, 0x0400), 0x09C2);       // watchdog divider
  EXPECT_EQ(line.master->fprd16(kStation, 0x0410), 0x03E8);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0420), 0x03E8);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0440), 0x01);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0120), 0x0001);  // AL control
  EXPECT_EQ(line.master->fprd16(kStation, 0x0982), 0x03E8);  // SYNC pulse length from SII word 2
  EXPECT_EQ(line.master->fprd8(kStation, 0x0140), 0x05);     // PDI control from SII word 0
}

TEST_F(RegisterTest, PdiControlAndAliasAreReadOnlyForEtherCat) {
  line.master->fpwr8(kStation, 0x0140, 0x04);
  line.master->fpwr16(kStation, 0x0012, 0x7777);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0140), 0x05);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0012), 0x0000);
}

TEST_F(RegisterTest, WriteMasksKeepReservedBits) {
  line.master->fpwr8(kStation, 0x0103, 0xFF);  // only bit 0 (alias enable) exists
  EXPECT_EQ(line.master->fprd8(kStation, 0x0103), 0x01);
  line.master->fpwr(kStation, 0x0606, {0xFF, 0xFF});  // FMMU start/stop bit: 3 bits each
  EXPECT_EQ(line.master->fprd16(kStation, 0x0606), 0x0707);
}

TEST_F(RegisterTest, ErrorCountersClearOnWrite) {
  auto bad = hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 70 10 02 01 00 00 80 0f 64 00 00 00");
  line.segment->process(bad);
  line.segment->process(bad);
  EXPECT_EQ(line.master->fprd8(kStation, 0x030C), 2);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0300), 2);
  // Writing any RX error counter clears 0x0300-0x030B; 0x030C clears on its own write.
  line.master->fpwr8(kStation, 0x0301, 0x55);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0300), 0);
  EXPECT_EQ(line.master->fprd8(kStation, 0x030C), 2);
  line.master->fpwr8(kStation, 0x030C, 0x55);
  EXPECT_EQ(line.master->fprd8(kStation, 0x030C), 0);
}

TEST_F(RegisterTest, EscResetSequenceRestoresPowerOnState) {
  line.master->fpwr8(kStation, 0x0F80, 0x77);
  line.master->fpwr8(kStation, 0x0040, 'R');
  line.master->fpwr8(kStation, 0x0040, 'E');
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0x77);
  line.master->fpwr8(kStation, 0x0040, 'S');
  EXPECT_EQ(line.esc(0).station_address(), 0);
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0x00);
  EXPECT_EQ(line.esc(0).read8(0x0000), 0x11);
}

TEST_F(RegisterTest, BrokenResetSequenceDoesNothing) {
  line.master->fpwr8(kStation, 0x0040, 'R');
  line.master->fpwr8(kStation, 0x0040, 'X');
  line.master->fpwr8(kStation, 0x0040, 'S');
  EXPECT_EQ(line.esc(0).station_address(), kStation);
}

TEST_F(RegisterTest, ProcessRamIsPlainMemory) {
  std::vector<uint8_t> data(256);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i);
  EXPECT_EQ(line.master->fpwr(kStation, 0x8000, data).wkc, 1);
  EXPECT_EQ(line.master->fprd(kStation, 0x8000, 256).data, data);
}

TEST_F(RegisterTest, WatchdogCounterClearsOnWrite) {
  Line l(1);
  l.to_op();
  l.clock.advance(200'000'000);
  l.segment->service();
  EXPECT_EQ(l.master->fprd8(kStation, 0x0442), 1);
  l.master->fpwr8(kStation, 0x0442, 0);
  EXPECT_EQ(l.master->fprd8(kStation, 0x0442), 0);
}

}  // namespace
}  // namespace rackcat::ecat::test

namespace rackcat::ecat::test {
namespace {

TEST_F(RegisterTest, RegisterWriteProtectionNeedsEnableInTheSameFrame) {
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0021, 0x01), 1);
  // Registers are protected, user RAM and process RAM are not.
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0138, 0x55), 0);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0138), 0x00);
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0F80, 0x66), 1);
  EXPECT_EQ(line.master->fpwr8(kStation, 0x8000, 0x77), 1);
  // Enable, then write, in one frame.
  FrameBuilder b;
  b.add(Command::Fpwr, kStation, 0x0020, {0x01});
  b.add(Command::Fpwr, kStation, 0x0138, {0x55});
  const auto r = line.master->send_frame(b);
  EXPECT_EQ(r[1].wkc, 1);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0138), 0x55);
  // The enable lasts one frame only.
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0138, 0x00), 0);
  // Switching the protection off needs the enable too: 0x0020 and 0x0021 in one write.
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0021, 0x00), 0);
  EXPECT_EQ(line.master->fpwr(kStation, 0x0020, {0x01, 0x00}).wkc, 1);
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0138, 0x00), 1);
}

TEST(WatchdogRegisters, PeriodAndStatusFollowTheRegisters) {
  // Process-data watchdog (ESC datasheet 0x0400/0x0420/0x0440): each completed SM2 write with
  // the trigger bit arms it for (divider + 2) x 40 ns x time; expiry clears 0x0440 bit 0, the
  // next trigger sets it again. A new divider or time applies from the next trigger on.
  ChipMaster chip;
  chip.sm(2, 0x1100, 4, 0x64);  // buffered, ECAT writes, AL event, watchdog trigger
  const uint64_t reset_period = (0x09C2 + 2) * 40ull * 1000;
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);
  EXPECT_EQ(chip.esc.next_event_ns(), chip.clock.now_ns() + reset_period);
  ASSERT_EQ(chip.apwr(reg::kWatchdogDivider, {0x30, 0x00}), 1);
  ASSERT_EQ(chip.apwr(reg::kWatchdogTimeProcessData, {0x0A, 0x00}), 1);
  EXPECT_EQ(chip.esc.next_event_ns(), chip.clock.now_ns() + reset_period);  // not retriggered
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);
  const uint64_t period = (0x30 + 2) * 40ull * 10;
  EXPECT_EQ(chip.esc.next_event_ns(), chip.clock.now_ns() + period);
  chip.clock.advance(period);
  chip.esc.service(chip.clock.now_ns());
  EXPECT_EQ(chip.esc.read8(reg::kWatchdogStatusProcessData) & 0x01, 0x00);
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);
  EXPECT_EQ(chip.esc.read8(reg::kWatchdogStatusProcessData) & 0x01, 0x01);
  // Time 0 disables it.
  ASSERT_EQ(chip.apwr(reg::kWatchdogTimeProcessData, {0x00, 0x00}), 1);
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);
  EXPECT_EQ(chip.esc.next_event_ns(), UINT64_MAX);
}

// The next-event bound a segment keeps (Esc::set_next_event_bound) is lowered by a newly armed
// watchdog and by a retrigger that moves the deadline earlier (a shorter period); a retrigger
// that moves it later leaves the bound early, never late.
TEST(WatchdogRegisters, ArmingLowersTheNextEventBound) {
  ChipMaster chip;
  uint64_t bound = UINT64_MAX;
  chip.esc.set_next_event_bound(&bound);
  chip.sm(2, 0x1100, 4, 0x64);  // buffered, ECAT writes, AL event, watchdog trigger
  const uint64_t reset_period = (0x09C2 + 2) * 40ull * 1000;
  const uint64_t armed_at = chip.clock.now_ns();
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);
  EXPECT_EQ(bound, armed_at + reset_period);
  chip.clock.advance(1'000'000);
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);  // later deadline: the bound stays early
  EXPECT_EQ(bound, armed_at + reset_period);
  EXPECT_LE(bound, chip.esc.next_event_ns());
  ASSERT_EQ(chip.apwr(reg::kWatchdogTimeProcessData, {0x0A, 0x00}), 1);
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);  // earlier deadline: lowered
  EXPECT_EQ(bound, chip.clock.now_ns() + (0x09C2 + 2) * 40ull * 10);
  EXPECT_EQ(bound, chip.esc.next_event_ns());
  chip.clock.advance(1'000'000);
  chip.esc.service(chip.clock.now_ns());  // expired: disarmed
  EXPECT_EQ(chip.esc.next_event_ns(), UINT64_MAX);
  bound = UINT64_MAX;                             // what the segment's service() computes then
  ASSERT_EQ(chip.apwr(0x1100, {1, 2, 3, 4}), 1);  // armed again
  EXPECT_EQ(bound, chip.esc.next_event_ns());
  EXPECT_LT(bound, UINT64_MAX);
}

TEST_F(RegisterTest, EscWriteProtectionCoversAllMemory) {
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0031, 0x01), 1);
  EXPECT_EQ(line.master->fpwr8(kStation, 0x8000, 0x77), 0);
  EXPECT_EQ(line.master->fprd8(kStation, 0x8000), 0x00);
  FrameBuilder b;
  b.add(Command::Fpwr, kStation, 0x0030, {0x01});
  b.add(Command::Fpwr, kStation, 0x8000, {0x77});
  b.add(Command::Fpwr, kStation, 0x0031, {0x00});
  line.master->send_frame(b);
  EXPECT_EQ(line.master->fprd8(kStation, 0x8000), 0x77);
  EXPECT_EQ(line.master->fpwr8(kStation, 0x8001, 0x01), 1);  // protection off again
}

}  // namespace
}  // namespace rackcat::ecat::test
