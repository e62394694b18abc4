// The log's event queue: the layers that run on the cyclic path (ESC, device, rack) report what
// happens - ESM transitions and refusals with their AL status codes, watchdog expiry, mailbox
// errors and SDO aborts, RIM state changes, injected faults, parameter stores - as small
// fixed-size records in a preallocated lock-free queue; a logging thread (apps/event_logger)
// drains it, formats and writes. Pushing never allocates, formats, locks or makes a system
// call; when nobody drains (unit tests, offline commands) the log is disabled and a push is one
// relaxed load. A full queue drops the event and counts it; the logger reports the count.
//
// Noisy kinds (mailbox errors, SDO aborts) are rate-limited at the source: at most
// kRateLimitPerSecond per kind and second pass, the rest are counted and the next event that
// passes carries that count (Event::suppressed).
//
//   base::event_log().push(base::Event{.kind = base::EventKind::RimState, .a = rim, ...});
//
// Queue: Vyukov's bounded multi-producer queue (a sequence number per cell), so the ESC
// thread, the control API's thread and a CAN link thread may all push.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "base/cache_line.hpp"

namespace rackcat::base {

enum class EventKind : uint8_t {
  // ESM (ETG.1000.6 §5.3). a = state before, b = state after (AL status bits 3..0),
  // c = AL control as the master last wrote it (its request), code = AL status code (0x0134),
  // station = configured station address (0x0010).
  EsmTransition,
  // The ESM set the error flag: a refused request (b == a, c's state differs) or a fall back
  // (SM change, application error, watchdog). Fields as EsmTransition.
  EsmError,
  // Process-data watchdog expired (ETG.1000.4 §6.5.3). a = state, value = expiry count.
  WatchdogExpired,
  // Mailbox error reply (ETG.1000.4 §5.6 Table 29): code = error code. Rate-limited.
  MailboxError,
  // SDO abort sent (ETG.1000.6 §5.6.2.7): index, a = subindex, value = abort code. Rate-limited.
  SdoAbort,
  // RIM state change: a = RIM, b = before, c = after (modules::RimState), code = comm error.
  RimState,
  // A fault injected through the control API: b = FaultWhat, index = module (0: none),
  // a = channel or RIM, value = the value (see FaultWhat), text = source kind for Source.
  FaultInjected,
  // Stored parameters (0xFBF2 store, 0xFBF0 factory reset): code = 0 ok, 1 failed;
  // text = what.
  Store,
};

enum class FaultWhat : uint8_t {
  WiringFault,     // value = modules::WiringFault
  SensorOpen,      // value = 1 open, 0 closed
  LoopOhms,        // value = ohms
  FanRpm,          // a = RIM (0: the CPU fan), value = rpm
  McmErrors,       // a = RIM, value = 0x2rr1:08 bits
  CpuTemperature,  // value = int32 tenths of a degree Celsius
  Source,          // text = source kind
};

struct Event {
  EventKind kind = EventKind::EsmTransition;
  uint8_t a = 0;
  uint8_t b = 0;
  uint8_t c = 0;
  uint16_t code = 0;
  uint16_t index = 0;
  uint16_t station = 0;
  uint32_t value = 0;
  uint32_t suppressed = 0;  // events of this kind dropped by the rate limit before this one
  int64_t time_ns = 0;      // CLOCK_REALTIME, set by push()
  std::array<char, 24> text{};

  // Copies at most 23 characters into text (no allocation).
  void set_text(std::string_view s) {
    const size_t n = s.size() < text.size() - 1 ? s.size() : text.size() - 1;
    if (n > 0) std::memcpy(text.data(), s.data(), n);  // an empty view may have no data()
    text[n] = '\0';
  }
};

class EventLog {
 public:
  static constexpr size_t kCapacity = 1024;  // power of two
  static constexpr uint32_t kRateLimitPerSecond = 10;

  EventLog() {
    for (size_t i = 0; i < kCapacity; ++i) cells_[i].seq.store(i, std::memory_order_relaxed);
  }
  EventLog(const EventLog&) = delete;
  EventLog& operator=(const EventLog&) = delete;

  // The logging thread turns the log on when it starts and off when it stops.
  void enable(bool on) { enabled_.store(on, std::memory_order_release); }
  bool enabled() const { return enabled_.load(std::memory_order_relaxed); }

  // Any thread. False when disabled, rate-limited or full (then counted in dropped()).
  bool push(Event e) {
    if (!enabled()) return false;
    e.time_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::system_clock::now().time_since_epoch())
                    .count();
    if (e.kind == EventKind::MailboxError || e.kind == EventKind::SdoAbort) {
      if (!pass_rate_limit(limits_[e.kind == EventKind::SdoAbort ? 1 : 0], e)) return false;
    }
    size_t pos = head_.load(std::memory_order_relaxed);
    for (;;) {
      Cell& cell = cells_[pos & (kCapacity - 1)];
      const size_t seq = cell.seq.load(std::memory_order_acquire);
      const auto diff = static_cast<std::ptrdiff_t>(seq) - static_cast<std::ptrdiff_t>(pos);
      if (diff == 0) {
        if (head_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
          cell.event = e;
          cell.seq.store(pos + 1, std::memory_order_release);
          return true;
        }
      } else if (diff < 0) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      } else {
        pos = head_.load(std::memory_order_relaxed);
      }
    }
  }

  // The logging thread only (one consumer).
  bool pop(Event& out) {
    Cell& cell = cells_[tail_ & (kCapacity - 1)];
    const size_t seq = cell.seq.load(std::memory_order_acquire);
    if (static_cast<std::ptrdiff_t>(seq) - static_cast<std::ptrdiff_t>(tail_ + 1) < 0) {
      return false;
    }
    out = cell.event;
    cell.seq.store(tail_ + kCapacity, std::memory_order_release);
    ++tail_;
    return true;
  }

  // Events lost to a full queue since the last call.
  uint64_t take_dropped() { return dropped_.exchange(0, std::memory_order_relaxed); }

 private:
  struct Cell {
    std::atomic<size_t> seq{0};
    Event event;
  };
  struct RateLimit {
    std::atomic<int64_t> window{0};  // second of the current window
    std::atomic<uint32_t> passed{0};
    std::atomic<uint32_t> suppressed{0};
  };

  static bool pass_rate_limit(RateLimit& r, Event& e) {
    const int64_t second = e.time_ns / 1'000'000'000;
    if (r.window.exchange(second, std::memory_order_relaxed) != second) {
      r.passed.store(0, std::memory_order_relaxed);
    }
    if (r.passed.fetch_add(1, std::memory_order_relaxed) >= kRateLimitPerSecond) {
      r.suppressed.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    e.suppressed = r.suppressed.exchange(0, std::memory_order_relaxed);
    return true;
  }

  std::array<Cell, kCapacity> cells_;
  alignas(kCacheLine) std::atomic<size_t> head_{0};
  alignas(kCacheLine) size_t tail_ = 0;
  std::atomic<uint64_t> dropped_{0};
  std::atomic<bool> enabled_{false};
  std::array<RateLimit, 2> limits_;
};

// The process's one event log (constructed on first use; the logging thread and every layer
// share it).
inline EventLog& event_log() {
  static EventLog log;
  return log;
}

// Shorthand for the producers: push when the log is on.
inline void log_event(const Event& e) {
  EventLog& log = event_log();
  if (log.enabled()) log.push(e);
}

}  // namespace rackcat::base
