// Working memory reserved at start-up and held only as far as it is used: one private
// anonymous mapping, zero-filled by the kernel, that takes a page of RAM when it is first
// written. The SDO server keeps its segmented-transfer and SDO Information buffers here
// (sdo_server.hpp): sized for the largest object the slave can transfer, as before, but a
// slave whose master never moves a segmented value or asks for a description costs no RAM for
// them (issue 16: per-slave memory proportional to what the slave uses).
//
// Nothing is allocated after construction: writing a page for the first time is a page fault
// the kernel serves (once per page), not an allocation on the request path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace rackcat::coe {

class LazyBuffer {
 public:
  LazyBuffer() = default;
  // Reserves `bytes` (rounded up to whole pages; 0 reserves nothing). Throws std::bad_alloc
  // when the kernel refuses the mapping.
  explicit LazyBuffer(size_t bytes);
  ~LazyBuffer();
  LazyBuffer(LazyBuffer&& other) noexcept;
  LazyBuffer& operator=(LazyBuffer&& other) noexcept;
  LazyBuffer(const LazyBuffer&) = delete;
  LazyBuffer& operator=(const LazyBuffer&) = delete;

  uint8_t* data() { return data_; }
  const uint8_t* data() const { return data_; }
  // The bytes asked for (the mapping may be larger: whole pages).
  size_t size() const { return size_; }
  std::span<uint8_t> span() { return {data_, size_}; }

 private:
  void release();

  uint8_t* data_ = nullptr;
  size_t size_ = 0;
  size_t mapped_ = 0;
};

}  // namespace rackcat::coe
