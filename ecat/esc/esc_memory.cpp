#include "ecat/esc/esc_memory.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <new>

namespace rackcat::ecat {

namespace {

size_t page_size() {
  const long p = sysconf(_SC_PAGESIZE);
  return p > 0 ? static_cast<size_t>(p) : 4096;
}

}  // namespace

EscMemory::EscMemory() {
  // Private anonymous memory reads as zero and takes a page only when written. Not a huge
  // page: the mappings of many ESCs may merge into one area, where one 2 MiB page would hold
  // what 64 KiB pages of many slaves never needed.
  void* p = mmap(nullptr, kSize, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  data_ = static_cast<uint8_t*>(p);
#ifdef MADV_NOHUGEPAGE
  madvise(data_, kSize, MADV_NOHUGEPAGE);  // advice only: a refusal changes no behaviour
#endif
}

EscMemory::~EscMemory() {
  munmap(data_, kSize);
}

void EscMemory::reset() {
  const size_t page = page_size();
  const size_t keep = (kRegisterBytes + page - 1) / page * page;  // the register page(s)
  std::memset(data_, 0, keep);
  // MADV_DONTNEED on private anonymous memory: the pages read as zero afterwards (madvise(2)).
  if (keep < kSize && madvise(data_ + keep, kSize - keep, MADV_DONTNEED) != 0) {
    std::memset(data_ + keep, 0, kSize - keep);  // still zero, only resident
  }
}

}  // namespace rackcat::ecat
