// A long line's heap (ecat/host/huge_heap.*): grown in 2 MiB steps while the line is built, and
// with rackcat run --huge-heap in huge pages: what the line built stays byte for byte, and where
// the kernel offers transparent huge pages the heap's whole 2 MiB ranges are advised (and
// collapsed on Linux 6.1 and later).
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ecat/host/huge_heap.hpp"

namespace rackcat::ecat {
namespace {

// ASan's allocator maps its own memory: malloc has no brk heap to advise. GCC says so with
// __SANITIZE_ADDRESS__, clang with __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define RACKCAT_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RACKCAT_TEST_ASAN 1
#endif
#endif

bool sanitized() {
#ifdef RACKCAT_TEST_ASAN
  return true;
#else
  return false;
#endif
}

// "always [madvise] never": the mode in brackets.
std::string thp_mode() {
  std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(f, line);
  const auto open = line.find('[');
  const auto close = line.find(']');
  if (open == std::string::npos || close == std::string::npos || close < open) return "";
  return line.substr(open + 1, close - open - 1);
}

// AnonHugePages of the [heap] mappings (kB), from /proc/self/smaps.
size_t heap_huge_kib() {
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool in_heap = false;
  size_t total = 0;
  while (std::getline(smaps, line)) {
    if (!line.empty() && line.find('-') != std::string::npos && line.find(' ') > line.find('-') &&
        std::isxdigit(static_cast<unsigned char>(line[0])) != 0) {
      in_heap = line.find("[heap]") != std::string::npos;
    } else if (in_heap && line.rfind("AnonHugePages:", 0) == 0) {
      total += std::stoul(line.substr(14));
    }
  }
  return total;
}

TEST(HugeHeap, KeepsTheHeapsContentAndAdvisesWholeRanges) {
  if (sanitized()) GTEST_SKIP() << "ASan allocator: no malloc heap";
  const std::string mode = thp_mode();
  if (mode != "always" && mode != "madvise") GTEST_SKIP() << "transparent huge pages: " << mode;

  // A line's worth of small blocks (a tiny rack's objects are tens of bytes to a few KiB).
  std::vector<std::unique_ptr<uint8_t[]>> blocks;
  constexpr size_t kBlocks = 12 * 1024;
  constexpr size_t kBlockBytes = 1024;
  for (size_t i = 0; i < kBlocks; ++i) {
    blocks.push_back(std::make_unique<uint8_t[]>(kBlockBytes));
    for (size_t j = 0; j < kBlockBytes; ++j) blocks.back()[j] = static_cast<uint8_t>(i * 7 + j);
  }

  const HugeHeapResult result = advise_huge_heap();
  if (result.error == ENOENT) GTEST_SKIP() << "no [heap] mapping: malloc does not use brk here";
  EXPECT_EQ(result.error, 0);
  EXPECT_GE(result.advised_bytes, size_t{2} << 20);  // 12 MiB of heap holds whole ranges
  EXPECT_EQ(result.advised_bytes % (size_t{2} << 20), 0u);
  if (result.collapsed) {
    EXPECT_GE(heap_huge_kib(), result.advised_bytes / 1024);
  }

  for (size_t i = 0; i < kBlocks; ++i) {
    for (size_t j = 0; j < kBlockBytes; ++j) {
      ASSERT_EQ(blocks[i][j], static_cast<uint8_t>(i * 7 + j)) << "block " << i << " byte " << j;
    }
  }
}

TEST(HugeHeap, GrowsTheHeapInTwoMiBSteps) {
  if (sanitized()) GTEST_SKIP() << "ASan allocator: no malloc heap";
#if !defined(__GLIBC__)
  GTEST_SKIP() << "M_TOP_PAD is glibc's";
#endif
  ASSERT_TRUE(grow_heap_in_huge_page_steps());
  // Small blocks until malloc extends the heap with brk: that one extension is 2 MiB or more
  // (the default pads it by 128 KiB).
  const auto* const before = static_cast<const uint8_t*>(sbrk(0));
  std::vector<std::unique_ptr<uint8_t[]>> blocks;
  constexpr size_t kMostBlocks = 64 * 1024;  // 64 MiB: far more than any top before the call
  while (static_cast<const uint8_t*>(sbrk(0)) == before && blocks.size() < kMostBlocks) {
    blocks.push_back(std::make_unique<uint8_t[]>(1024));
  }
  const auto* const after = static_cast<const uint8_t*>(sbrk(0));
  if (after == before) GTEST_SKIP() << "malloc does not use brk here";
  EXPECT_GE(after - before, ptrdiff_t{2} << 20);
}

}  // namespace
}  // namespace rackcat::ecat
