// SyncManager semantics on the EtherCAT side (ETG.1000.4 §6.7): mailbox mode (one buffer,
// full flag, hand-over on the last byte) and buffered mode (three buffers, consistent images),
// the PDI deactivate bit, and the events each hand-over raises: ECAT event request 0x0210
// bits 4-11 for the master, AL event request 0x0220 bits 8-23 for the firmware. The PDI side
// of the same buffers is in pdi.cpp.

#include "base/little_endian.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

using reg::sm::ecat_writes;
using reg::sm::is_mailbox;
using reg::sm::kStatusFull;
using reg::sm::kStatusNoBuffer;
using reg::sm::kStatusRead;
using reg::sm::kStatusWritten;

inline uint16_t sm_base(int n) {
  return static_cast<uint16_t>(reg::kSm + reg::kSmSize * n);
}

}  // namespace

void Esc::reload_sm(int n) {
  const uint16_t base = sm_base(n);
  SmState& s = sm_[n];
  const bool was_enabled = s.enabled;
  const SmState before = s;
  const bool was_active = s.active;
  const uint8_t old_activate = activate_seen_[n];
  s.start = le::get16(&mem_[base]);
  s.length = le::get16(&mem_[base + 2]);
  s.control = mem_[base + reg::kSmControlOffset];
  const uint8_t activate = mem_[base + reg::kSmActivateOffset];
  // A buffer running past the end of the address space does not work as a SyncManager.
  s.enabled = (activate & 0x01) && s.length != 0 &&
              static_cast<uint32_t>(s.start) + s.length <= reg::kAddressSpace;
  s.active = s.enabled && (mem_[base + reg::kSmPdiControlOffset] & 0x01) == 0;
  activate_seen_[n] = activate;
  if (s.enabled) {
    sm_enabled_mask_ |= static_cast<uint16_t>(1u << n);
  } else {
    sm_enabled_mask_ &= static_cast<uint16_t>(~(1u << n));
  }
  if (s.enabled != was_enabled || s.active != was_active) {
    // (De)activation empties the buffers (ESC datasheet 0x0805).
    mem_[base + reg::kSmStatusOffset] = is_mailbox(s.control) ? 0x00 : kStatusNoBuffer;
    s.next_buffer = 0;
  }
  // AL event request bit 4: the SM activation register 0x0806+8n changed (enable, or the
  // mailbox repeat request of ETG.1000.4 §6.7.3), or the SM was (de)activated; cleared when
  // the PDI reads an activation register (pdi.cpp). The firmware re-checks the SMs then.
  const bool config_changed = before.enabled != s.enabled || before.start != s.start ||
                              before.length != s.length || before.control != s.control;
  if (activate != old_activate || s.active != was_active || config_changed) {
    mem_[reg::kAlEventRequest] |= 0x10;
  }
  // A SyncManager without a trigger source stops the process-data watchdog from being
  // retriggered; an SM2 the firmware deactivated (PREOP and below) takes it out of play.
  if (!s.active && (s.control & 0x40) && n == 2) watchdog_armed_ = false;
  update_ecat_event(n);
  update_al_event(n);
}

bool Esc::sm_allows_read(uint16_t address, uint16_t len) {
  if (sm_enabled_mask_ == 0) return true;
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= mask - 1) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    const uint32_t s_end = static_cast<uint32_t>(s.start) + s.length;
    if (!(address < s_end && s.start < end)) continue;
    // A SyncManager deactivated by the PDI blocks its buffer: no data, no WKC.
    if (!s.active) return false;
    const uint8_t status = mem_[sm_base(n) + reg::kSmStatusOffset];
    if (is_mailbox(s.control) && !ecat_writes(s.control) && (status & kStatusFull) == 0) {
      return false;  // empty mailbox: no data, no WKC
    }
  }
  return true;
}

void Esc::sm_after_read(uint16_t address, uint16_t len) {
  if (sm_enabled_mask_ == 0) return;
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= mask - 1) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    const uint32_t s_end = static_cast<uint32_t>(s.start) + s.length;
    // Only reading the last byte completes a read (ETG.1000.4 §6.7.2).
    if (ecat_writes(s.control) || !(address < s_end && end >= s_end)) continue;
    uint8_t& status = mem_[sm_base(n) + reg::kSmStatusOffset];
    if (is_mailbox(s.control)) {
      status = static_cast<uint8_t>((status & ~(kStatusFull | kStatusWritten)) | kStatusRead);
    } else {
      status = static_cast<uint8_t>((status & ~kStatusWritten) | kStatusRead);
    }
    update_ecat_event(n);
    update_al_event(n);
  }
}

bool Esc::sm_allows_write(uint16_t address, uint16_t len) {
  if (sm_enabled_mask_ == 0) return true;
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= mask - 1) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    const uint32_t s_end = static_cast<uint32_t>(s.start) + s.length;
    if (!(address < s_end && s.start < end)) continue;
    if (!s.active || !ecat_writes(s.control)) return false;
    // A full mailbox refuses the write: WKC stays 0 and the master retries.
    if (is_mailbox(s.control) && (mem_[sm_base(n) + reg::kSmStatusOffset] & kStatusFull)) {
      return false;
    }
  }
  return true;
}

void Esc::sm_after_write(uint16_t address, uint16_t len) {
  if (sm_enabled_mask_ == 0) return;
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= mask - 1) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    const uint32_t s_end = static_cast<uint32_t>(s.start) + s.length;
    // Writing the last byte hands the buffer over (ETG.1000.4 §6.7.1, §6.7.2).
    if (!ecat_writes(s.control) || !(address < s_end && end >= s_end)) continue;
    uint8_t& status = mem_[sm_base(n) + reg::kSmStatusOffset];
    if (is_mailbox(s.control)) {
      status = static_cast<uint8_t>((status & ~kStatusRead) | kStatusFull | kStatusWritten);
      update_ecat_event(n);
      update_al_event(n);
      continue;
    }
    // Buffered: the written buffer becomes the newest; report its index in bits 5:4.
    status = static_cast<uint8_t>((status & ~(kStatusNoBuffer | kStatusRead)) |
                                  (sm_[n].next_buffer << 4) | kStatusWritten);
    sm_[n].next_buffer = static_cast<uint8_t>((sm_[n].next_buffer + 1) % 3);
    update_ecat_event(n);
    update_al_event(n);
    if (s.control & 0x40) watchdog_trigger(pass_.port0_ns);
  }
}

void Esc::update_ecat_event(int n) {
  // ECAT event request bits 4-11 mirror SyncManagers 0-7 whose ECAT event is enabled
  // (control bit 4): a read buffer the PDI has filled, a write buffer the PDI has emptied.
  if (n >= 8) return;
  const SmState& s = sm_[n];
  bool pending = false;
  if (s.enabled && (s.control & 0x10)) {
    const uint8_t status = mem_[sm_base(n) + reg::kSmStatusOffset];
    pending = ecat_writes(s.control) ? (status & kStatusRead) : (status & kStatusWritten);
  }
  uint16_t events = le::get16(&mem_[reg::kEcatEventRequest]);
  const auto bit = static_cast<uint16_t>(0x0010 << n);
  events = static_cast<uint16_t>(pending ? (events | bit) : (events & ~bit));
  le::put16(&mem_[reg::kEcatEventRequest], events);
}

void Esc::update_al_event(int n) {
  // AL event request bits 8-23 mirror SyncManagers 0-15 whose AL event is enabled (control
  // bit 5): a buffer the master has written (ECAT writes) or read (ECAT reads) is pending for
  // the PDI until the PDI accesses the buffer's first byte (pdi.cpp).
  const SmState& s = sm_[n];
  bool pending = false;
  if (s.enabled && (s.control & 0x20)) {
    const uint8_t status = mem_[sm_base(n) + reg::kSmStatusOffset];
    pending = ecat_writes(s.control) ? (status & kStatusWritten) : (status & kStatusRead);
  }
  uint32_t events = le::get32(&mem_[reg::kAlEventRequest]);
  const uint32_t bit = 0x100u << n;
  events = pending ? (events | bit) : (events & ~bit);
  le::put32(&mem_[reg::kAlEventRequest], events);
}

}  // namespace rackcat::ecat
