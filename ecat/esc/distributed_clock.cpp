// Distributed clocks 0x0900-0x09FF (ETG.1000.4 §6.10, §9): receive-time latches, 64-bit local
// and system time, offset, delay, the system-time difference and control loop driven by the
// master's ARMW/FRMW of 0x0910, and the SYNC0/SYNC1 cyclic unit.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "base/little_endian.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/frame.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();
// The control loop follows differences up to this size; larger ones (the master's reset write
// of 0 to 0x0910, garbage) are reported in 0x092C but do not move the clock, as the ESC's
// speed counter can only slew slowly.
constexpr int64_t kMaxFollowedDifferenceNs = 1'000'000;

}  // namespace

uint64_t Esc::local_time(uint64_t clock_ns) const {
  return clock_ns + local_offset_;
}

uint64_t Esc::system_time(uint64_t clock_ns) const {
  return local_time(clock_ns) + le::get64(&mem_[reg::kDcSystemTimeOffset]);
}

uint64_t Esc::clock_of_system_time(uint64_t system) const {
  return system - le::get64(&mem_[reg::kDcSystemTimeOffset]) - local_offset_;
}

void Esc::dc_latch_receive_times() {
  // A write to 0x0900 latches, per port, the local time at which this frame's first bit
  // arrived there; ports without a link keep their old value. 0x0918 is the time the frame
  // reached the processing unit (from port 0).
  const uint64_t t0 = local_time(pass_.port0_ns);
  le::put32(&mem_[reg::kDcReceiveTimePort0], static_cast<uint32_t>(t0));
  if (port1_link_ && forwards_to_port1()) {
    le::put32(&mem_[reg::kDcReceiveTimePort0 + 4],
              static_cast<uint32_t>(local_time(pass_.port1_ns)));
  }
  le::put64(&mem_[reg::kDcReceiveTimeProcessingUnit], t0);
  le::put16(&mem_[reg::kEcatEventRequest], le::get16(&mem_[reg::kEcatEventRequest]) | 0x0001);
}

void Esc::dc_prepare_system_time_read() {
  le::put64(&mem_[reg::kDcSystemTime], system_time(pass_.port0_ns));
}

bool Esc::write_system_time(const uint8_t* src, uint16_t len) {
  if (write_protection_active()) return protected_write(reg::kDcSystemTime, src, len);
  dc_compare_system_time(src, len);
  return true;
}

void Esc::read_system_time(uint8_t* dst, uint16_t len, bool merge_or) {
  dc_prepare_system_time_read();
  const uint8_t* src = &mem_[reg::kDcSystemTime];
  if (merge_or) {
    for (uint16_t i = 0; i < len; ++i) dst[i] |= src[i];
  } else {
    std::memcpy(dst, src, len);
  }
}

void Esc::dc_system_time_written(uint16_t address, const uint8_t* src, uint16_t len) {
  // Only a write starting at 0x0910 carries a system time: 4 bytes compare the low 32 bits,
  // 8 bytes all 64 (ESC datasheet 0x0910 "write: compare with local copy").
  if (address > reg::kDcSystemTime) return;
  const uint32_t offset = reg::kDcSystemTime - address;
  const uint32_t available = len - offset;
  if (available < 4) return;
  dc_compare_system_time(src + offset, available >= 8 ? 8 : 4);
}

void Esc::dc_compare_system_time(const uint8_t* received, uint16_t len) {
  const uint64_t local = system_time(pass_.port0_ns);
  const uint32_t delay = le::get32(&mem_[reg::kDcSystemTimeDelay]);
  int64_t diff;
  if (len >= 8) {
    const uint64_t with_delay = le::get64(received) + delay;
    diff = static_cast<int64_t>(with_delay - local);
  } else {
    const uint32_t with_delay = le::get32(received) + delay;
    diff = static_cast<int32_t>(with_delay - static_cast<uint32_t>(local));
  }
  // 0x092C: bit 31 set when the local copy is smaller than the received time, bits 30:0 the
  // magnitude.
  const uint64_t magnitude = static_cast<uint64_t>(diff < 0 ? -diff : diff);
  uint32_t reg_value = static_cast<uint32_t>(std::min<uint64_t>(magnitude, 0x7FFFFFFF));
  if (diff > 0) reg_value |= 0x80000000u;
  le::put32(&mem_[reg::kDcSystemTimeDifference], reg_value);
  if (diff != 0 && diff > -kMaxFollowedDifferenceNs && diff < kMaxFollowedDifferenceNs) {
    // First-order loop: move half-way towards the reference on every compare.
    local_offset_ += static_cast<uint64_t>(diff / 2 != 0 ? diff / 2 : diff);
    // The SYNC times are system times: in clock time they move with the local clock.
    if (sync0_running_ || sync1_running_) timers_changed();
  }
}

void Esc::dc_activation_written() {
  // 0x0981: bit 0 cyclic operation, bit 1 SYNC0, bit 2 SYNC1 (ETG.1000.4 Table 67).
  const uint8_t activation = mem_[reg::kDcActivation];
  const bool cyclic = activation & 0x01;
  const bool sync0 = cyclic && (activation & 0x02);
  const bool sync1 = sync0 && (activation & 0x04);
  const uint64_t now = system_time(pass_.port0_ns);
  if (sync0 && !sync0_running_) {
    uint64_t start = le::get64(&mem_[reg::kDcStartTime]);
    const uint32_t cycle = le::get32(&mem_[reg::kDcSync0Cycle]);
    if (static_cast<int64_t>(now - start) > 0 && cycle != 0) {
      // Start time already passed: begin at the next cycle boundary after it.
      start += ((now - start + cycle - 1) / cycle) * cycle;
    }
    next_sync0_ = start;
    sync0_count_ = 0;
    sync0_running_ = true;
    mem_[reg::kDcActivationStatus] |= 0x01;  // first SYNC0 pulse pending
    le::put64(&mem_[reg::kDcStartTime], next_sync0_);
  } else if (!sync0) {
    sync0_running_ = false;
    mem_[reg::kDcActivationStatus] &= static_cast<uint8_t>(~0x01);
  }
  if (sync1 && !sync1_running_) {
    const uint32_t cycle1 = le::get32(&mem_[reg::kDcSync1Cycle]);
    const uint32_t cycle0 = le::get32(&mem_[reg::kDcSync0Cycle]);
    next_sync1_ = next_sync0_ + (cycle0 != 0 && cycle1 >= cycle0 ? cycle1 % cycle0 : cycle1);
    sync1_running_ = true;
    le::put64(&mem_[reg::kDcNextSync1], next_sync1_);
  } else if (!sync1) {
    sync1_running_ = false;
  }
  timers_changed();
}

void Esc::timers_changed() {
  if (next_event_bound_ == nullptr) return;
  const uint64_t next = next_event_ns();
  if (next < *next_event_bound_) *next_event_bound_ = next;
}

void Esc::fire_sync(int which, uint64_t system_time_ns) {
  which = which == 1 ? 1 : 0;
  mem_[reg::kDcSync0Status + which] |= 0x01;
  mem_[reg::kAlEventRequest] |= static_cast<uint8_t>(which == 0 ? 0x04 : 0x08);
  // The pulse's time stays readable for the firmware: 0x0990 moves on to the next SYNC0 pulse
  // after this one, 0x0998 keeps the SYNC1 pulse that fired.
  if (which == 1) le::put64(&mem_[reg::kDcNextSync1], system_time_ns);
}

uint64_t Esc::next_sync_event_ns() const {
  uint64_t next = kNever;
  if (sync0_running_) next = clock_of_system_time(next_sync0_);
  if (sync1_running_) next = std::min(next, clock_of_system_time(next_sync1_));
  return next;
}

uint64_t Esc::next_event_ns() const {
  const uint64_t sync = next_sync_event_ns();
  return watchdog_armed_ ? std::min(sync, watchdog_deadline_) : sync;
}

void Esc::service(uint64_t now_ns) {
  const uint64_t now = system_time(now_ns);
  const uint32_t cycle0 = le::get32(&mem_[reg::kDcSync0Cycle]);
  const uint32_t cycle1 = le::get32(&mem_[reg::kDcSync1Cycle]);
  // SYNC1 scheduled by an earlier SYNC0 comes first when it is due.
  if (sync1_running_ && static_cast<int64_t>(now - next_sync1_) >= 0 &&
      (!sync0_running_ || static_cast<int64_t>(next_sync0_ - next_sync1_) > 0)) {
    fire_sync(1, next_sync1_);
    next_sync1_ = kNever;
  }
  if (sync0_running_ && static_cast<int64_t>(now - next_sync0_) >= 0) {
    uint64_t t = next_sync0_;
    if (cycle0 != 0) {
      const uint64_t missed = (now - t) / cycle0;
      t += missed * cycle0;
      sync0_count_ += missed;
    }
    mem_[reg::kDcActivationStatus] &= static_cast<uint8_t>(~0x01);
    fire_sync(0, t);
    if (sync1_running_) {
      // SYNC1 follows SYNC0 by its cycle time when shorter; otherwise every
      // (cycle1 / cycle0)-th SYNC0, shifted by the remainder (ESC datasheet 0x09A4).
      const uint64_t every = (cycle0 != 0 && cycle1 >= cycle0) ? cycle1 / cycle0 : 1;
      const uint64_t shift = (cycle0 != 0 && cycle1 >= cycle0) ? cycle1 % cycle0 : cycle1;
      if (sync0_count_ % every == 0) {
        next_sync1_ = t + shift;
        le::put64(&mem_[reg::kDcNextSync1], next_sync1_);
      }
    }
    ++sync0_count_;
    if (cycle0 == 0) {
      sync0_running_ = false;  // single shot
    } else {
      next_sync0_ = t + cycle0;
      le::put64(&mem_[reg::kDcStartTime], next_sync0_);
    }
    if (sync1_running_ && next_sync1_ != kNever && static_cast<int64_t>(now - next_sync1_) >= 0) {
      fire_sync(1, next_sync1_);
      next_sync1_ = kNever;
    }
  }
  if (watchdog_armed_ && now_ns >= watchdog_deadline_) watchdog_expired();
}

}  // namespace rackcat::ecat
