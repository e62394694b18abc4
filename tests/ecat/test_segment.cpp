// A line of 16 slaves: position addressing, cyclic LRW + FRMW with the expected working
// counters, process data to and from every device, ports and loop control.
#include <gtest/gtest.h>

#include "base/round_time.hpp"
#include "ecat/registers.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

TEST(Segment, SixteenSlavesCyclicExchange) {
  Line line(16);
  line.to_op();
  for (size_t k = 0; k < 16; ++k) {
    ASSERT_EQ(line.fw(k).state(), EsmState::Op) << k;
    line.app(k).inputs_value = {static_cast<uint8_t>(k),       1, 2, 3, 4,
                                static_cast<uint8_t>(0xF0 | k)};
  }
  std::vector<uint8_t> outputs;
  for (size_t k = 0; k < 16; ++k) {
    for (uint8_t b = 0; b < kOutputBytes; ++b) outputs.push_back(static_cast<uint8_t>(k * 16 + b));
  }
  // The firmware produces inputs after each frame for the next one (as a real slave's µC
  // does): the new input values appear from the second cycle on.
  line.cycle(outputs);
  const auto r = line.cycle(outputs);
  // SOEM's expected WKC: 2 x output slaves + input slaves; FRMW: 1 read + 15 writes.
  EXPECT_EQ(r[0].wkc, 16 * 3);
  EXPECT_EQ(r[1].wkc, 16);
  for (size_t k = 0; k < 16; ++k) {
    const std::vector<uint8_t> mine(outputs.begin() + static_cast<long>(k * kOutputBytes),
                                    outputs.begin() + static_cast<long>((k + 1) * kOutputBytes));
    EXPECT_EQ(line.app(k).last_outputs, mine) << k;
    const size_t at = 16 * kOutputBytes + k * kInputBytes;
    EXPECT_EQ(std::vector<uint8_t>(r[0].data.begin() + static_cast<long>(at),
                                   r[0].data.begin() + static_cast<long>(at + kInputBytes)),
              line.app(k).inputs_value)
        << k;
  }
}

TEST(Segment, PositionAddressingReachesEverySlave) {
  Line line(16);
  for (uint16_t k = 0; k < 16; ++k) {
    const auto r = line.master->send(Command::Apwr, static_cast<uint16_t>(0 - k), 0x0F80,
                                     {static_cast<uint8_t>(k)});
    EXPECT_EQ(r.wkc, 1);
    EXPECT_EQ(r.adp, static_cast<uint16_t>(16 - k));
  }
  for (uint16_t k = 0; k < 16; ++k) EXPECT_EQ(line.esc(k).read8(0x0F80), k);
}

TEST(Segment, ClosedPortCutsTheLine) {
  Line line(3);
  line.to_preop();
  // Slave 1 closes port 1 (DL control 0x0101 bits 3:2 = 11b): slave 2 sees no more frames.
  line.master->fpwr8(Line::station(1), 0x0101, 0x0C);
  EXPECT_EQ(line.master->send(Command::Brd, 0, 0x0000, {0, 0}).wkc, 2);
  EXPECT_EQ(line.master->fprd16(Line::station(1), 0x0110) & 0x0400, 0x0400);  // loop closed
  line.master->fpwr8(Line::station(1), 0x0101, 0x00);
  EXPECT_EQ(line.master->send(Command::Brd, 0, 0x0000, {0, 0}).wkc, 3);
}

TEST(Segment, DlStatusChangeRaisesEvent) {
  Line line(2);
  line.to_preop();
  line.master->fprd16(Line::station(0), 0x0110);  // clears the event
  EXPECT_EQ(line.master->fprd16(Line::station(0), 0x0210) & 0x0004, 0);
  line.master->fpwr8(Line::station(0), 0x0101, 0x0C);
  EXPECT_EQ(line.master->fprd16(Line::station(0), 0x0210) & 0x0004, 0x0004);
}

TEST(Segment, SlaveAccessors) {
  Line line(2);
  EXPECT_EQ(line.segment->size(), 2u);
  EXPECT_EQ(&line.segment->slave(1).application(), &line.app(1));
  EXPECT_THROW(line.segment->slave(2), std::out_of_range);
  EXPECT_THROW(Segment({}, line.clock), std::invalid_argument);
}

TEST(Segment, NextEventIsTheEarliestOfAllSlaves) {
  Line line(2);
  EXPECT_EQ(line.segment->next_event_ns(), UINT64_MAX);
  line.to_op();
  EXPECT_EQ(line.segment->next_event_ns(), line.clock.now_ns() + 100'000'000);
}

}  // namespace
// The firmware runs on its IRQ line (ESC datasheet 0x0220/0x0204): a frame that raises no AL
// event for a slave, whose device has nothing for the mailbox, does not run that slave's
// firmware at all; a device with an unsolicited message is served after any frame.
TEST(Segment, FirmwareRunsOnlyForSlavesWithWork) {
  Line line(3);
  line.to_preop();
  // The firmware's own PDI activation of SM0/SM1 on entering PREOP raised AL event bit 4
  // (ESC datasheet 0x0220): one more run after the next frame re-reads the SMs.
  line.master->send(Command::Brd, 0, 0x0130, {0, 0});
  for (size_t i = 0; i < 3; ++i) line.app(i).polls = 0;
  for (int k = 0; k < 5; ++k) line.master->send(Command::Brd, 0, 0x0130, {0, 0});
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(line.app(i).polls, 0) << i;
  line.app(1).pending_emergency = {0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x10};
  line.master->send(Command::Brd, 0, 0x0130, {0, 0});
  EXPECT_EQ(line.app(0).polls, 0);
  EXPECT_EQ(line.app(1).polls, 1);
  EXPECT_EQ(line.app(2).polls, 0);
  // The message is in SM1 for the master; the slave sleeps again.
  const auto r = line.master->fprd(Line::station(1), kMbxInStart, kMbxSize);
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data[5] & 0x0F, 0x03);
  line.master->send(Command::Brd, 0, 0x0130, {0, 0});
  EXPECT_EQ(line.app(1).polls, 1);
  // An AL control write is an AL event: the addressed slave's firmware runs (and answers).
  line.master->fpwr(Line::station(2), 0x0120, {0x02, 0x00});
  EXPECT_EQ(line.esc(2).al_status() & 0x0F, 0x02);
}

// The cyclic frame raises SM2/SM3 events in every slave, so every firmware runs; it exchanges
// the process data and leaves the mailbox alone (no SM1 status read, no protocol poll) unless
// the master wrote SM0 or the device has a message to send.
TEST(Segment, CyclicFramesLeaveTheMailboxAlone) {
  Line line(2);
  line.to_op();
  const std::vector<uint8_t> outputs(2 * kOutputBytes, 0x5A);
  line.cycle(outputs);
  for (size_t i = 0; i < 2; ++i) line.app(i).polls = 0;
  const int outputs_before = line.app(0).outputs_count;
  for (int k = 0; k < 5; ++k) line.cycle(outputs);
  EXPECT_EQ(line.app(0).outputs_count - outputs_before, 5);
  for (size_t i = 0; i < 2; ++i) EXPECT_EQ(line.app(i).polls, 0) << i;
  line.app(1).pending_emergency = {0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x10};
  line.cycle(outputs);
  EXPECT_EQ(line.app(0).polls, 0);
  EXPECT_EQ(line.app(1).polls, 1);
  const auto r = line.master->fprd(Line::station(1), kMbxInStart, kMbxSize);
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data[5] & 0x0F, 0x03);
}

// Timers are scheduled through one next-event bound, not a walk over every ESC per frame: the
// bound is never later than the earliest timer (a retriggered watchdog leaves it early), and
// service() at the bound makes it exact again. The watchdog still expires on time.
TEST(Segment, NextEventBoundIsEarlyNeverLate) {
  Line line(3);
  line.to_op();  // the cycles armed every slave's process-data watchdog (100 ms)
  const std::vector<uint8_t> outputs(3 * kOutputBytes, 0);
  for (int k = 0; k < 5; ++k) {
    line.clock.advance(1'000'000);
    line.cycle(outputs);  // retriggers: the watchdogs move later
    EXPECT_LE(line.segment->next_event_bound_ns(), line.segment->next_event_ns());
  }
  line.segment->service();
  EXPECT_EQ(line.segment->next_event_bound_ns(), line.segment->next_event_ns());
  EXPECT_EQ(line.segment->next_event_ns(), line.clock.now_ns() + 100'000'000);
  // No more cycles: at the deadlines (slave k's is later by the frame's way to it) the
  // watchdogs expire and the slaves fall to SAFEOP.
  line.clock.advance(100'001'000);
  ASSERT_LE(line.segment->next_event_bound_ns(), line.clock.now_ns());
  line.segment->service();
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(line.esc(i).al_status() & 0x0F, 0x04) << i;
  EXPECT_EQ(line.segment->next_event_bound_ns(), UINT64_MAX);
}

// One clock read per firmware round (base/round_time.hpp): every slave's application reads the
// time the round began; the next round reads the clock again; outside a round now() is the
// clock itself.
TEST(Segment, TheSlavesOfAFirmwareRoundShareOneTime) {
  Line line(8);
  line.to_op();
  const std::vector<uint8_t> outputs(8 * kOutputBytes, 0x5A);
  line.cycle(outputs);
  const auto first = line.app(0).inputs_time;
  for (size_t k = 1; k < 8; ++k) EXPECT_EQ(line.app(k).inputs_time, first) << k;
  const auto outside = base::RoundTime::now();
  EXPECT_GE(outside, first);
  while (base::RoundTime::now() == outside) {
  }
  line.cycle(outputs);
  const auto second = line.app(0).inputs_time;
  EXPECT_GT(second, outside);
  for (size_t k = 1; k < 8; ++k) EXPECT_EQ(line.app(k).inputs_time, second) << k;
}

}  // namespace rackcat::ecat::test
