#include "ecat/host/huge_heap.hpp"

#include <sys/mman.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace rackcat::ecat {
namespace {

// MADV_COLLAPSE (Linux 6.1, include/uapi/asm-generic/mman-common.h); older C library headers
// lack the name.
#ifndef MADV_COLLAPSE
constexpr int kMadvCollapse = 25;
#else
constexpr int kMadvCollapse = MADV_COLLAPSE;
#endif

constexpr uintptr_t kHugePage = uintptr_t{2} << 20;  // x86-64 PMD page

struct Range {
  uintptr_t start = 0;
  uintptr_t end = 0;
};

// The [heap] line of /proc/self/maps: "start-end perms offset dev inode [heap]".
bool find_heap(Range& heap) {
  std::FILE* maps = std::fopen("/proc/self/maps", "re");
  if (maps == nullptr) return false;
  char line[512];
  bool found = false;
  while (!found && std::fgets(line, sizeof line, maps) != nullptr) {
    if (std::strstr(line, "[heap]") == nullptr) continue;
    unsigned long start = 0;
    unsigned long end = 0;
    found = std::sscanf(line, "%lx-%lx", &start, &end) == 2 && start < end;
    heap = {start, end};
  }
  if (std::fclose(maps) != 0) return false;
  return found;
}

}  // namespace

HugeHeapResult advise_huge_heap() {
  HugeHeapResult result;
  Range heap;
  if (!find_heap(heap)) {
    result.error = ENOENT;
    return result;
  }
  const uintptr_t first = (heap.start + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t last = heap.end & ~(kHugePage - 1);
  if (first >= last) return result;  // no whole 2 MiB range: nothing to gain
  // NOLINTNEXTLINE(performance-no-int-to-ptr): the address comes from the kernel's own map
  auto* const start = reinterpret_cast<void*>(first);
  const size_t length = last - first;
  if (madvise(start, length, MADV_HUGEPAGE) != 0) {
    result.error = errno;  // THP "never", or a kernel without it
    return result;
  }
  result.advised_bytes = length;
  // EINVAL before Linux 6.1, EAGAIN/ENOMEM when no huge page was free: khugepaged collapses
  // the advised ranges in the background then.
  result.collapsed = madvise(start, length, kMadvCollapse) == 0;
  return result;
}

bool grow_heap_in_huge_page_steps() {
#if defined(__GLIBC__)
  // mallopt returns 1 on success, 0 on error (glibc manual, "Malloc Tunable Parameters").
  return mallopt(M_TOP_PAD, static_cast<int>(kHugePage)) == 1;
#else
  return false;
#endif
}

}  // namespace rackcat::ecat
