// The cyclic path allocates nothing: global operator new is replaced by a counting version
// (counting only on the thread that asks for it) around 1000 cyclic LRW + FRMW frames to a
// 16-slave segment in OP with DC SYNC0 running, and around mailbox-free register traffic.
#include <gtest/gtest.h>

#include <cstdlib>
#include <new>

#include "tests/ecat/test_master.hpp"

namespace {
thread_local bool g_counting = false;
thread_local size_t g_allocations = 0;
}  // namespace

void* operator new(size_t size) {
  if (g_counting) ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t size) {
  return operator new(size);
}
void* operator new(size_t size, const std::nothrow_t&) noexcept {
  if (g_counting) ++g_allocations;
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](size_t size, const std::nothrow_t& t) noexcept {
  return operator new(size, t);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, size_t) noexcept {
  std::free(p);
}

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

  g_allocations = 0;
  g_counting = true;
  size_t wkc_ok = 0;
  for (int i = 0; i < 1000; ++i) {
    std::copy(frame.begin(), frame.end(), work.begin());
    line.clock.advance(250'000);
    line.segment->process(work);
    line.segment->service();
    if (work[16 + 10 + 16 * 10] == 48) ++wkc_ok;
  }
  g_counting = false;
  EXPECT_EQ(g_allocations, 0u);
  EXPECT_EQ(wkc_ok, 1000u);
  EXPECT_GE(line.app(0).syncs.size(), 249u);
}

TEST(NoAllocation, MalformedFramesAllocateNothing) {
  Line line(4);
  auto bad = hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 70 10 02 01 00 00 80 0f 64 00 00 00");
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 100; ++i) line.segment->process(bad);
  g_counting = false;
  EXPECT_EQ(g_allocations, 0u);
}

}  // namespace
}  // namespace rackcat::ecat::test
