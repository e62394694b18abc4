// A fixed-size ring of pending CoE Emergency messages (ETG.1000.6 §5.6.4: error code,
// error register, 5 bytes of manufacturer data). No allocation, no lock: one producer (the
// device or a module's fault handler, possibly on its own thread) and one consumer (the
// mailbox side calling SdoServer::poll) may run concurrently.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace rackcat::coe {

struct Emergency {
  uint16_t error_code = 0;        // CiA 301 / ETG.1000.6 emergency error code
  uint8_t error_register = 0;     // object 0x1001
  std::array<uint8_t, 5> data{};  // manufacturer-specific
};

template <size_t N>
class EmergencyQueue {
  static_assert(N > 0);

 public:
  // Producer side. A full queue keeps what it holds (the consumer owns the oldest slot, so
  // dropping it is not lock-free) and counts the lost message in overruns(); returns false.
  bool push(const Emergency& e) {
    const size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == N) {
      overruns_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[tail % N] = e;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  // Consumer side.
  bool pop(Emergency& out) {
    const size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) {
      return false;
    }
    out = slots_[head % N];
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  size_t size() const {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
  }
  bool empty() const { return size() == 0; }
  static constexpr size_t capacity() { return N; }
  size_t overruns() const { return overruns_.load(std::memory_order_relaxed); }

 private:
  std::array<Emergency, N> slots_{};
  std::atomic<size_t> head_{0};
  std::atomic<size_t> tail_{0};
  std::atomic<size_t> overruns_{0};
};

}  // namespace rackcat::coe
