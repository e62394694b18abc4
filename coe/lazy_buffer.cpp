#include "coe/lazy_buffer.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <new>
#include <utility>

namespace rackcat::coe {

namespace {

size_t page_size() {
  const long p = sysconf(_SC_PAGESIZE);
  return p > 0 ? static_cast<size_t>(p) : 4096;
}

}  // namespace

LazyBuffer::LazyBuffer(size_t bytes) : size_(bytes) {
  if (bytes == 0) return;
  const size_t page = page_size();
  mapped_ = (bytes + page - 1) / page * page;
  // Private anonymous memory reads as zero and takes a page only when written (mmap(2)). Not
  // a huge page: the buffers of many slaves may merge into one area, where one 2 MiB page
  // would hold what none of them wrote.
  void* p = mmap(nullptr, mapped_, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) {
    mapped_ = 0;
    size_ = 0;
    throw std::bad_alloc();
  }
  data_ = static_cast<uint8_t*>(p);
#ifdef MADV_NOHUGEPAGE
  madvise(data_, mapped_, MADV_NOHUGEPAGE);  // advice only: a refusal changes no behaviour
#endif
}

LazyBuffer::~LazyBuffer() {
  release();
}

LazyBuffer::LazyBuffer(LazyBuffer&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)),
      mapped_(std::exchange(other.mapped_, 0)) {}

LazyBuffer& LazyBuffer::operator=(LazyBuffer&& other) noexcept {
  if (this != &other) {
    release();
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    mapped_ = std::exchange(other.mapped_, 0);
  }
  return *this;
}

void LazyBuffer::release() {
  if (data_ != nullptr) munmap(data_, mapped_);
  data_ = nullptr;
  size_ = 0;
  mapped_ = 0;
}

}  // namespace rackcat::coe
