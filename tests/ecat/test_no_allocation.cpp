// The cyclic path allocates nothing: allocations of this thread are counted
// (tests/support/allocation_counter.hpp) around 1000 cyclic LRW + FRMW frames to a
// 16-slave segment in OP with DC SYNC0 running, and around mailbox-free register traffic.
#include <gtest/gtest.h>

#include <optional>

#include "base/event_log.hpp"
#include "tests/ecat/test_master.hpp"
#include "tests/support/allocation_counter.hpp"

namespace rackcat::ecat::test {
namespace {

TEST(NoAllocation, CyclicFramesAllocateNothing) {
  Line line(16);
  line.to_op();
  // SYNC0 running too, so the frame path also services the DC unit.
  for (size_t k = 0; k < 16; ++k) {
    const uint16_t s = Line::station(k);
    line.master->fpwr64(s, 0x0990, line.master->fprd64(s, 0x0910) + 1'000'000);
    line.master->fpwr32(s, 0x09A0, 1'000'000);
    line.master->fpwr8(s, 0x0981, 0x03);
  }
  FrameBuilder b;
  b.add_logical(Command::Lrw, 0, std::vector<uint8_t>(16 * (kOutputBytes + kInputBytes), 0x5A));
  b.add(Command::Frmw, Line::station(0), 0x0910, std::vector<uint8_t>(8, 0));
  const std::vector<uint8_t> frame = b.build();
  std::vector<uint8_t> work = frame;
  line.segment->process(work);  // warm-up: first delivery sizes the test app's copy
  line.segment->after_frame();  // the firmware, once the reply is out
  // The test device records SYNC events in a vector: give it room so only the ESC is measured.
  for (size_t k = 0; k < 16; ++k) line.app(k).syncs.reserve(2000);

  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  size_t wkc_ok = 0;
  for (int i = 0; i < 1000; ++i) {
    std::copy(frame.begin(), frame.end(), work.begin());
    line.clock.advance(250'000);
    line.segment->process(work);
    line.segment->after_frame();  // the firmware, once the reply is out
    line.segment->service();
    if (work[16 + 10 + 16 * 10] == 48) ++wkc_ok;
  }
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(wkc_ok, 1000u);
  EXPECT_GE(line.app(0).syncs.size(), 249u);
}

TEST(NoAllocation, LogicalMapRebuildsAndNewRangesAllocateNothing) {
  // The logical-address map (ecat/logical_map.*) is rebuilt after FMMU writes and resolves new
  // (address, length) pairs from storage reserved when the segment was built.
  Line line(16);
  line.to_op();
  FrameBuilder disable;
  disable.add(Command::Fpwr, Line::station(3), 0x060C, {0x00});
  FrameBuilder enable;
  enable.add(Command::Fpwr, Line::station(3), 0x060C, {0x01});
  std::vector<std::vector<uint8_t>> frames = {disable.build(), enable.build()};
  for (uint32_t a = 0; a < 12; ++a) {
    FrameBuilder lrw;
    lrw.add_logical(Command::Lrw, a,
                    std::vector<uint8_t>(16 * (kOutputBytes + kInputBytes) - a, 0));
    frames.push_back(lrw.build());
  }
  std::vector<std::vector<uint8_t>> work = frames;
  // Warm-up: the test devices size their output copies at the first delivery.
  for (size_t f = 0; f < frames.size(); ++f) {
    line.segment->process(work[f]);
    line.segment->after_frame();
  }
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  for (int i = 0; i < 20; ++i) {
    for (size_t f = 0; f < frames.size(); ++f) {
      std::copy(frames[f].begin(), frames[f].end(), work[f].begin());
      line.segment->process(work[f]);
      line.segment->after_frame();
    }
  }
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
}

TEST(NoAllocation, MalformedFramesAllocateNothing) {
  Line line(4);
  auto bad = hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 70 10 02 01 00 00 80 0f 64 00 00 00");
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  rackcat::testing::CountAllocations count;
  for (int i = 0; i < 100; ++i) line.segment->process(bad);
  EXPECT_EQ(count.allocations(), 0u);
}

// With the log on (as under `rackcat run`), the ESM reports transitions and refusals through
// the preallocated event queue (base/event_log.hpp); pushing never allocates, also when the
// queue is full or the rate limit drops an event.
TEST(EventLog, EsmTransitionsAndRefusalsAreLogged) {
  base::EventLog& log = base::event_log();
  base::Event e;
  while (log.pop(e)) {
  }
  log.enable(true);
  Line line(2);
  line.to_op();
  // Back to INIT, then an invalid request (INIT -> OP: 0x0011) on every slave.
  for (size_t k = 0; k < 2; ++k) line.master->fpwr8(Line::station(k), 0x0120, 0x01);
  for (size_t k = 0; k < 2; ++k) line.master->fpwr8(Line::station(k), 0x0120, 0x08);
  log.enable(false);
  size_t transitions = 0, refusals = 0;
  while (log.pop(e)) {
    if (e.kind == base::EventKind::EsmTransition) ++transitions;
    if (e.kind == base::EventKind::EsmError && e.code == 0x0011 && e.a == 0x01 && e.b == 0x01 &&
        (e.c & 0x0F) == 0x08) {
      ++refusals;
    }
  }
  EXPECT_EQ(transitions, 2u * 4u);  // INIT->PREOP->SAFEOP->OP->INIT on each slave
  EXPECT_EQ(refusals, 2u);
}

TEST(EventLog, PushAllocatesNothingAndCountsWhatItDrops) {
  base::EventLog& log = base::event_log();
  base::Event e;
  while (log.pop(e)) {
  }
  (void)log.take_dropped();
  log.enable(true);
  size_t allocations = 0;
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  for (size_t i = 0; i < base::EventLog::kCapacity + 10; ++i) {
    log.push({.kind = base::EventKind::RimState, .a = 1});
  }
  size_t passed = 0;
  for (int i = 0; i < 100; ++i) passed += log.push({.kind = base::EventKind::SdoAbort}) ? 1 : 0;
  allocations = count->allocations();
  count.reset();
  log.enable(false);
  if (rackcat::testing::CountAllocations::available()) {
    EXPECT_EQ(allocations, 0u);
  }
  EXPECT_EQ(passed, 0u);               // the queue is full
  EXPECT_GE(log.take_dropped(), 10u);  // ... and says how much it lost
  size_t n = 0;
  while (log.pop(e)) ++n;
  EXPECT_EQ(n, base::EventLog::kCapacity);
  // Rate limit: at most kRateLimitPerSecond SDO aborts a second pass.
  log.enable(true);
  passed = 0;
  for (int i = 0; i < 100; ++i) passed += log.push({.kind = base::EventKind::SdoAbort}) ? 1 : 0;
  log.enable(false);
  EXPECT_LE(passed, 2 * base::EventLog::kRateLimitPerSecond);  // a second boundary may pass
  while (log.pop(e)) {
  }
}

TEST(NoAllocation, MailboxRoundTripsAndRepeatsAllocateNothing) {
  // The firmware's mailbox path: SM0 read through the PDI, header checks, double-write check,
  // dispatch to the protocol, counter, SM1 write, and the repeat request.
  Line line(1);
  line.to_preop();
  const uint16_t s = Line::station(0);
  std::vector<uint8_t> request(kMbxSize, 0);
  request[0] = 4;
  std::vector<uint8_t> reply(kMbxSize, 0);
  FrameBuilder write;
  FrameBuilder read;
  read.add(Command::Fprd, s, kMbxInStart, reply);
  FrameBuilder repeat_on;
  repeat_on.add(Command::Fpwr, s, 0x080E, {0x03});
  FrameBuilder repeat_off;
  repeat_off.add(Command::Fpwr, s, 0x080E, {0x01});
  std::vector<std::vector<uint8_t>> writes;
  for (uint8_t c = 1; c <= 7; ++c) {
    request[5] = static_cast<uint8_t>(c << 4 | 0x03);
    FrameBuilder w;
    w.add(Command::Fpwr, s, kMbxOutStart, request);
    writes.push_back(w.build());
  }
  const auto read_frame = read.build();
  const auto on = repeat_on.build();
  const auto off = repeat_off.build();
  std::vector<uint8_t> work(std::max(writes[0].size(), read_frame.size()));
  auto run = [&](const std::vector<uint8_t>& f) {
    std::copy(f.begin(), f.end(), work.begin());
    line.segment->process(std::span<uint8_t>(work.data(), f.size()));
    line.segment->after_frame();  // the firmware, once the reply is out
  };
  run(writes[0]);  // warm-up: the test device sizes its copy of the request
  run(read_frame);
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  for (int i = 1; i <= 500; ++i) {
    run(writes[static_cast<size_t>(i % 7)]);
    run(read_frame);
    run(i % 2 ? on : off);  // the master lost the reply: asks for it again
    run(read_frame);
  }
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(line.app(0).mailbox_requests, 501);
}

}  // namespace
}  // namespace rackcat::ecat::test
