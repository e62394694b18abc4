#include "ecat/esc/esc_memory.hpp"

#include "base/zero_pages.hpp"

#include <sys/mman.h>

#include <cstring>
#include <new>

namespace rackcat::ecat {

EscMemory::EscMemory() : data_(base::map_zero_pages(kSize)) {
  if (data_ == nullptr) throw std::bad_alloc();
}

EscMemory::~EscMemory() {
  munmap(data_, kSize);
}

void EscMemory::reset() {
  const size_t keep = base::page_rounded(kRegisterBytes);  // the register page(s)
  std::memset(data_, 0, keep);
  // MADV_DONTNEED on private anonymous memory: the pages read as zero afterwards (madvise(2)).
  if (keep < kSize && madvise(data_ + keep, kSize - keep, MADV_DONTNEED) != 0) {
    std::memset(data_ + keep, 0, kSize - keep);  // still zero, only resident
  }
}

}  // namespace rackcat::ecat
