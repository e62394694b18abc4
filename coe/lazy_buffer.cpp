#include "coe/lazy_buffer.hpp"

#include "base/zero_pages.hpp"

#include <sys/mman.h>

#include <new>
#include <utility>

namespace rackcat::coe {

LazyBuffer::LazyBuffer(size_t bytes) : size_(bytes) {
  if (bytes == 0) return;
  mapped_ = base::page_rounded(bytes);
  data_ = base::map_zero_pages(mapped_);
  if (data_ == nullptr) {
    mapped_ = 0;
    size_ = 0;
    throw std::bad_alloc();
  }
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
