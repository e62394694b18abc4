// The time base of the emulated ESCs. Every time-dependent behaviour (DC local time, receive
// time latches, SYNC events, the process-data watchdog) reads time through this interface so
// tests can run on a ManualClock and be deterministic.
#pragma once

#include <cstdint>

namespace rackcat::ecat {

class Clock {
 public:
  virtual ~Clock() = default;
  // Monotonic nanoseconds; the origin is arbitrary.
  virtual uint64_t now_ns() const = 0;
};

// CLOCK_MONOTONIC: what the raw-socket link uses.
class SteadyClock final : public Clock {
 public:
  uint64_t now_ns() const override;
  static const SteadyClock& instance();
};

// A clock that only moves when told to (unit tests, fuzzing, replay).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(uint64_t start_ns = 1'000'000'000) : now_(start_ns) {}
  uint64_t now_ns() const override { return now_; }
  void set(uint64_t ns) { now_ = ns; }
  void advance(uint64_t ns) { now_ += ns; }

 private:
  uint64_t now_;
};

}  // namespace rackcat::ecat
