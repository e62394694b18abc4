// The ESC's address space held as far as it is used (ecat/esc/esc_memory.*): unwritten process
// RAM reads 0 as before, written RAM keeps its bytes, a reset ('R','E','S' to 0x0040, ESC
// datasheet) gives power-on content again, and an ESC in INIT keeps only its register page
// resident, not 64 KiB.
#include <unistd.h>

#include <fstream>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "ecat/esc/esc_memory.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

size_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  size_t size = 0;
  size_t resident = 0;
  statm >> size >> resident;
  return resident * static_cast<size_t>(sysconf(_SC_PAGESIZE));
}

TEST(EscMemory, UnwrittenBytesReadZeroAndWrittenOnesStay) {
  EscMemory m;
  for (size_t a = 0; a < EscMemory::kSize; a += 0x0FFF) EXPECT_EQ(m[a], 0) << a;
  m[0x0120] = 0x11;
  m[0x1000] = 0xA5;
  m[0xFFFF] = 0x5A;
  EXPECT_EQ(m.view()[0x1000], 0xA5);
  EXPECT_EQ(m[0xFFFF], 0x5A);
  m.reset();
  EXPECT_EQ(m[0x0120], 0);
  EXPECT_EQ(m[0x1000], 0);
  EXPECT_EQ(m[0xFFFF], 0);
}

TEST(EscMemory, ProcessRamReadsZeroOnTheWireUntilWrittenAndAfterAnEscReset) {
  Line line(1);
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(0x1001));
  auto r = line.master->send(Command::Fprd, 0x1001, 0x8000, std::vector<uint8_t>(16, 0xEE));
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data, std::vector<uint8_t>(16, 0x00));
  EXPECT_EQ(line.master->fpwr(0x1001, 0x8000, {1, 2, 3}).wkc, 1);
  r = line.master->send(Command::Fprd, 0x1001, 0x8000, std::vector<uint8_t>(3, 0));
  EXPECT_EQ(r.data, (std::vector<uint8_t>{1, 2, 3}));
  // ESC reset (0x0040 'R','E','S' in three frames): power-on content, station address too.
  for (uint8_t c : {'R', 'E', 'S'}) line.master->send(Command::Bwr, 0, 0x0040, {c});
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(0x1001));
  r = line.master->send(Command::Fprd, 0x1001, 0x8000, std::vector<uint8_t>(3, 0xEE));
  EXPECT_EQ(r.data, std::vector<uint8_t>(3, 0x00));
}

TEST(EscMemory, AnEscInInitKeepsItsRegisterPagesNotSixtyFourKib) {
  // 64 ESCs with their firmware and test devices: with the whole address space resident they
  // took 64 x 64 KiB = 4 MiB more; now the register page and the small objects around it.
  const size_t before = resident_bytes();
  Line line(64);
  const size_t after = resident_bytes();
  ASSERT_GE(after, before);
  EXPECT_LT(after - before, 64u * 24 * 1024) << (after - before) / 64 << " bytes per slave";
}

}  // namespace
}  // namespace rackcat::ecat::test
