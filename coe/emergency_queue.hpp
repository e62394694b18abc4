// A fixed-size ring of pending CoE Emergency messages (ETG.1000.6 §5.6.4: error code,
// error register, 5 bytes of manufacturer data). No allocation: queuing may happen on the
// cyclic path or from a module's fault handler.
#pragma once

#include <array>
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
  // Queues a message; when full the oldest one is dropped (the newest fault is the one a
  // master most needs) and overruns() counts it.
  void push(const Emergency& e) {
    if (count_ == N) {
      head_ = (head_ + 1) % N;
      --count_;
      ++overruns_;
    }
    slots_[(head_ + count_) % N] = e;
    ++count_;
  }
  bool pop(Emergency& out) {
    if (count_ == 0) return false;
    out = slots_[head_];
    head_ = (head_ + 1) % N;
    --count_;
    return true;
  }
  size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  static constexpr size_t capacity() { return N; }
  size_t overruns() const { return overruns_; }
  void clear() { head_ = count_ = 0; }

 private:
  std::array<Emergency, N> slots_{};
  size_t head_ = 0;
  size_t count_ = 0;
  size_t overruns_ = 0;
};

}  // namespace rackcat::coe
