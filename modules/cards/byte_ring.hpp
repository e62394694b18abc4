// A fixed-capacity byte FIFO between two threads (UART line <-> slot-card FIFO). One consumer
// thread pops; producers serialise among themselves with their own lock if there are several.
// Indices are free-running, capacity is a power of two. No allocation after construction.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace rackcat::modules {

class ByteRing {
 public:
  explicit ByteRing(size_t capacity_pow2)
      : buf_(std::make_unique<uint8_t[]>(capacity_pow2)), mask_(capacity_pow2 - 1) {}

  size_t capacity() const { return mask_ + 1; }
  size_t size() const {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  size_t space() const { return capacity() - size(); }

  // Producer side: copies what fits, returns the count.
  size_t push(const uint8_t* data, size_t n) {
    const size_t head = head_.load(std::memory_order_relaxed);
    const size_t tail = tail_.load(std::memory_order_acquire);
    n = std::min(n, capacity() - (head - tail));
    for (size_t i = 0; i < n; ++i) buf_[(head + i) & mask_] = data[i];
    head_.store(head + n, std::memory_order_release);
    return n;
  }

  // Consumer side.
  size_t pop(uint8_t* out, size_t n) {
    const size_t tail = tail_.load(std::memory_order_relaxed);
    const size_t head = head_.load(std::memory_order_acquire);
    n = std::min(n, head - tail);
    for (size_t i = 0; i < n; ++i) out[i] = buf_[(tail + i) & mask_];
    tail_.store(tail + n, std::memory_order_release);
    return n;
  }
  // Consumer side: copy without consuming.
  size_t peek(uint8_t* out, size_t n) const {
    const size_t tail = tail_.load(std::memory_order_relaxed);
    const size_t head = head_.load(std::memory_order_acquire);
    n = std::min(n, head - tail);
    for (size_t i = 0; i < n; ++i) out[i] = buf_[(tail + i) & mask_];
    return n;
  }
  // Consumer side: drop everything.
  void clear() { tail_.store(head_.load(std::memory_order_acquire), std::memory_order_release); }

 private:
  std::unique_ptr<uint8_t[]> buf_;
  size_t mask_;
  std::atomic<size_t> head_{0};
  std::atomic<size_t> tail_{0};
};

}  // namespace rackcat::modules
