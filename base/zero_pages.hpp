// Private anonymous memory that reads as zero and takes a page of RAM only when written
// (mmap(2)): the one way rackcat reserves large, mostly unused buffers per slave (an ESC's
// 64 KiB address space, an SDO server's transfer buffers), so memory follows what a slave uses
// (issue 16).
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>

namespace rackcat::base {

inline size_t page_size() {
  const long p = sysconf(_SC_PAGESIZE);
  return p > 0 ? static_cast<size_t>(p) : 4096;
}

// `bytes` rounded up to whole pages.
inline size_t page_rounded(size_t bytes) {
  const size_t page = page_size();
  return (bytes + page - 1) / page * page;
}

// Maps `bytes` (a multiple of the page size) of zero pages; nullptr if the kernel refuses.
// Release with munmap(p, bytes). Not a huge page: the mappings of many slaves may merge into one
// area, where one 2 MiB page would hold what none of them wrote.
inline uint8_t* map_zero_pages(size_t bytes) {
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) return nullptr;
#ifdef MADV_NOHUGEPAGE
  madvise(p, bytes, MADV_NOHUGEPAGE);  // advice only: a refusal changes no behaviour
#endif
  return static_cast<uint8_t*>(p);
}

}  // namespace rackcat::base
