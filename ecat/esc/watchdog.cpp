// Process-data watchdog (ETG.1000.4 §6.5.3, ESC datasheet 0x0400-0x0443): retriggered by every
// completed write of a SyncManager with watchdog trigger enabled (SM2 in practice); on expiry
// the status bit 0x0440.0 drops, the counter 0x0442 counts and AL event request bit 6 rises.
// What follows (outputs to the safe state, OP -> SAFEOP with 0x001B) is the firmware's part.
#include "base/little_endian.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

void Esc::derive_watchdog_period() {
  // One watchdog tick is (divider + 2) x 40 ns (25 MHz); the reset values give 100 µs x 1000.
  const uint64_t tick = (static_cast<uint64_t>(le::get16(&mem_[reg::kWatchdogDivider])) + 2) * 40;
  watchdog_period_ns_ = tick * le::get16(&mem_[reg::kWatchdogTimeProcessData]);
}

void Esc::watchdog_trigger(uint64_t now_ns) {
  if (!watchdog_running_) {
    watchdog_running_ = true;
    mem_[reg::kWatchdogStatusProcessData] |= 0x01;
  }
  if (watchdog_period_ns_ == 0) {  // time 0 disables the watchdog
    watchdog_armed_ = false;
    return;
  }
  const uint64_t deadline = now_ns + watchdog_period_ns_;
  // The next-event bound (set_next_event_bound) is at or before the armed deadline; a
  // retrigger that moves it later leaves the bound valid, so only a newly armed or earlier
  // deadline looks at the other timers (the SYNC units' state is not on the cyclic lines).
  const bool earlier = !watchdog_armed_ || deadline < watchdog_deadline_;
  watchdog_armed_ = true;
  watchdog_deadline_ = deadline;
  if (earlier) timers_changed();
}

void Esc::watchdog_expired() {
  watchdog_armed_ = false;
  watchdog_running_ = false;
  mem_[reg::kWatchdogStatusProcessData] &= static_cast<uint8_t>(~0x01);
  if (mem_[reg::kWatchdogCounterProcessData] != 0xFF) ++mem_[reg::kWatchdogCounterProcessData];
  mem_[reg::kAlEventRequest] |= 0x40;
}

}  // namespace rackcat::ecat
