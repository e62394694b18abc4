// The time of one firmware round: the emulated slaves of a segment run their firmware one after
// the other after each frame (ecat::Segment::after_frame), and what their applications read as
// "now" (signal sources, the input latch time 0xF6F0, the rack's plants) is the time that round
// began, read once for all of them instead of once or twice per slave. Outside a round (SDO
// requests, the control API, tests driving a device directly) now() reads the clock.
//
// The round is what a real segment's slaves share: their inputs are latched on one event (the
// frame, or SYNC0 - ETG.1000.6 §5.3 "Synchronisation"), so a slave's sample differs from its
// neighbour's by the round's duration at most, and every input stays at most one master cycle
// old. Per thread: each device thread has its own rounds.
#pragma once

#include <chrono>

namespace rackcat::base {

class RoundTime {
 public:
  using Clock = std::chrono::steady_clock;

  // The start of the current round on this thread, else Clock::now().
  static Clock::time_point now() noexcept { return active_ ? at_ : Clock::now(); }

  // Opens a round for its lifetime (reads the clock once). Nested scopes keep the outer
  // round's time.
  class Scope {
   public:
    Scope() noexcept : outer_(active_) {
      if (!outer_) {
        at_ = Clock::now();
        active_ = true;
      }
    }
    ~Scope() {
      if (!outer_) active_ = false;
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    bool outer_;
  };

 private:
  static inline thread_local bool active_ = false;
  static inline thread_local Clock::time_point at_{};
};

}  // namespace rackcat::base
