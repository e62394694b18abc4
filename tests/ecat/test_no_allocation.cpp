// The cyclic path allocates nothing: allocations of this thread are counted
// (tests/support/allocation_counter.hpp) around 1000 cyclic LRW + FRMW frames to a
// 16-slave segment in OP with DC SYNC0 running, and around mailbox-free register traffic.
#include <gtest/gtest.h>

#include <optional>

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
  // The test device records SYNC events in a vector: give it room so only the ESC is measured.
  for (size_t k = 0; k < 16; ++k) line.app(k).syncs.reserve(2000);

  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  size_t wkc_ok = 0;
  for (int i = 0; i < 1000; ++i) {
    std::copy(frame.begin(), frame.end(), work.begin());
    line.clock.advance(250'000);
    line.segment->process(work);
    line.segment->service();
    if (work[16 + 10 + 16 * 10] == 48) ++wkc_ok;
  }
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(wkc_ok, 1000u);
  EXPECT_GE(line.app(0).syncs.size(), 249u);
}

TEST(NoAllocation, MalformedFramesAllocateNothing) {
  Line line(4);
  auto bad = hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 70 10 02 01 00 00 80 0f 64 00 00 00");
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  rackcat::testing::CountAllocations count;
  for (int i = 0; i < 100; ++i) line.segment->process(bad);
  EXPECT_EQ(count.allocations(), 0u);
}

}  // namespace
}  // namespace rackcat::ecat::test
