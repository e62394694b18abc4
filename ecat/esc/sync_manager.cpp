// SyncManager semantics on the EtherCAT side (ETG.1000.4 §6.7): mailbox mode (one buffer,
// full flag, hand-over on the last byte) and buffered mode (three buffers, consistent images),
// the PDI deactivate bit, and the events each hand-over raises: ECAT event request 0x0210
// bits 4-11 for the master, AL event request 0x0220 bits 8-23 for the firmware. The PDI side
// of the same buffers is in pdi.cpp.

#include <algorithm>

#include "base/little_endian.hpp"
#include "base/short_copy.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace sm = reg::sm;

namespace {

// The status bits that make SyncManager n's events pending (ETG.1000.4 §6.7; ESC datasheet
// 0x0210, 0x0220), 0 when the event is off: ECAT event request bits 4-11 mirror SMs 0-7 whose
// ECAT event is enabled (control bit 4): a buffer the master reads that the PDI has filled, one
// it writes that the PDI has emptied. AL event request bits 8-23 mirror SMs 0-15 whose AL
// event is enabled (control bit 5): a buffer the master has written, or read, pending for the
// PDI until the PDI accesses its first byte. A disabled SM raises neither.
uint8_t ecat_event_status(uint8_t control, bool enabled) {
  if (!enabled || (control & 0x10) == 0) return 0;
  return sm::ecat_writes(control) ? sm::kStatusRead : sm::kStatusWritten;
}
uint8_t al_event_status(uint8_t control, bool enabled) {
  if (!enabled || (control & sm::kControlAlEvent) == 0) return 0;
  return sm::ecat_writes(control) ? sm::kStatusWritten : sm::kStatusRead;
}

// Sets SM n's two event bits from its `status`: one read-modify-write of each little-endian
// register (16-bit 0x0210, 32-bit 0x0220), whichever byte SM n's bit is in.
void write_sm_events(uint8_t* memory, int n, uint8_t ecat_status, uint8_t al_status,
                     uint8_t status) {
  if (n < 8) {
    const auto bit = static_cast<uint16_t>(1u << (4 + n));
    const uint16_t ecat = le::get16(&memory[reg::kEcatEventRequest]);
    le::put16(&memory[reg::kEcatEventRequest],
              static_cast<uint16_t>((status & ecat_status) != 0 ? ecat | bit : ecat & ~bit));
  }
  const uint32_t bit = 1u << (8 + n);
  const uint32_t al = le::get32(&memory[reg::kAlEventRequest]);
  le::put32(&memory[reg::kAlEventRequest], (status & al_status) != 0 ? al | bit : al & ~bit);
}

}  // namespace

void Esc::reload_sm(int n) {
  const uint16_t base = sm::base(n);
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
  s.ecat_event_status = ecat_event_status(s.control, s.enabled);
  s.al_event_status = al_event_status(s.control, s.enabled);
  activate_seen_[n] = activate;
  if (s.enabled) {
    sm_enabled_mask_ |= static_cast<uint16_t>(1u << n);
  } else {
    sm_enabled_mask_ &= static_cast<uint16_t>(~(1u << n));
  }
  // What the buffer accesses look up: the lowest byte of any enabled SM's buffer (accesses
  // below it meet none), and the SMs that share no byte with another (pdi_read_buffer).
  sm_first_byte_ = reg::kAddressSpace;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
    sm_first_byte_ = std::min<uint32_t>(sm_first_byte_, sm_[__builtin_ctz(mask)].start);
  }
  sm_alone_mask_ = 0;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
    const int k = __builtin_ctz(mask);
    const SmState& t = sm_[k];
    uint16_t meeting = 0;
    for_each_sm_meeting(t.start, static_cast<uint32_t>(t.start) + t.length,
                        [&](int m) { meeting = static_cast<uint16_t>(meeting | (1u << m)); });
    if (meeting == (1u << k)) sm_alone_mask_ = static_cast<uint16_t>(sm_alone_mask_ | meeting);
  }
  if (s.enabled != was_enabled || s.active != was_active) {
    // (De)activation empties the buffers (ESC datasheet 0x0805).
    mem_[base + reg::kSmStatusOffset] = sm::is_mailbox(s.control) ? 0x00 : sm::kStatusNoBuffer;
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
  update_sm_events(n);
  refresh_fmmu_meetings();  // the FMMUs' SMs may have moved
}

uint16_t Esc::sm_meeting(uint32_t address, uint32_t end) const {
  uint16_t meeting = 0;
  for_each_sm_meeting(address, end,
                      [&](int n) { meeting = static_cast<uint16_t>(meeting | (1u << n)); });
  return meeting;
}

bool Esc::sm_allows_read(uint16_t address, uint16_t len) {
  return sm_allows_read(sm_meeting(address, static_cast<uint32_t>(address) + len));
}

bool Esc::sm_allows_read(uint16_t meeting) {
  for (uint16_t mask = meeting; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    // A SyncManager deactivated by the PDI blocks its buffer: no data, no WKC; so does an
    // empty mailbox the master reads.
    if (!s.active || (sm::is_mailbox(s.control) && !sm::ecat_writes(s.control) &&
                      (sm_status(n) & sm::kStatusFull) == 0)) {
      return false;
    }
  }
  return true;
}

void Esc::sm_after_read(uint16_t address, uint16_t len) {
  sm_after_read(sm_meeting(address, static_cast<uint32_t>(address) + len), address, len);
}

void Esc::sm_after_read(uint16_t meeting, uint16_t address, uint16_t len) {
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for (uint16_t mask = meeting; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
    const int n = __builtin_ctz(mask);
    if (!sm::ecat_writes(sm_[n].control)) sm_buffer_access(n, address, end, false);
  }
}

bool Esc::sm_takes_write(int n) const {
  // A full mailbox refuses the write until the other side has read it (ETG.1000.4 §6.7.1).
  const SmState& s = sm_[n];
  return s.active && !(sm::is_mailbox(s.control) &&
                       (mem_[sm::base(n) + reg::kSmStatusOffset] & sm::kStatusFull) != 0);
}

bool Esc::sm_allows_write(uint16_t address, uint16_t len) {
  return sm_allows_write(sm_meeting(address, static_cast<uint32_t>(address) + len));
}

bool Esc::sm_allows_write(uint16_t meeting) {
  for (uint16_t mask = meeting; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
    const int n = __builtin_ctz(mask);
    // The master writes only the buffers of SMs it writes: WKC stays 0 and it retries.
    if (!sm::ecat_writes(sm_[n].control) || !sm_takes_write(n)) return false;
  }
  return true;
}

void Esc::sm_after_write(uint16_t address, uint16_t len) {
  sm_after_write(sm_meeting(address, static_cast<uint32_t>(address) + len), address, len);
}

void Esc::sm_after_write(uint16_t meeting, uint16_t address, uint16_t len) {
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for (uint16_t mask = meeting; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    if (!sm::ecat_writes(s.control)) continue;
    sm_buffer_access(n, address, end, true);
    // A completed buffer with the watchdog trigger enabled retriggers the process-data
    // watchdog (ESC datasheet 0x0804 bit 6, 0x0420).
    if (end >= static_cast<uint32_t>(s.start) + s.length && !sm::is_mailbox(s.control) &&
        (s.control & sm::kControlWatchdog)) {
      watchdog_trigger(pass_.port0_ns);
    }
  }
}

void Esc::sm_buffer_access(int n, uint32_t address, uint32_t end, bool filler) {
  const SmState& s = sm_[n];
  sm_hand_over(n, address <= s.start, end >= static_cast<uint32_t>(s.start) + s.length, filler);
}

inline void Esc::sm_hand_over(int n, bool first, bool last, bool filler) {
  // Status 0x0805+8n (ETG.1000.4 §6.7; ESC datasheet 0x0805): bit 0 "written" is set when the
  // filler completes the buffer and cleared when the drainer reads its first byte; bit 1
  // "read" is set when the drainer completes it and cleared when the filler writes its first
  // byte; bit 6/7 say a read/write access has opened the buffer and not yet reached its last
  // byte. Completing a write hands the buffer over: a mailbox is full; in buffered mode the
  // three-buffer exchange makes it the newest (bits 5:4 = its index). Completing a read of a
  // mailbox empties it; of a buffered SM releases the buffer, so the next read opens the
  // newest one.
  SmState& s = sm_[n];
  const uint8_t open = filler ? sm::kStatusWriteOpen : sm::kStatusReadOpen;
  uint8_t status = sm_status(n);
  if (first)
    status = static_cast<uint8_t>(status & ~(filler ? sm::kStatusRead : sm::kStatusWritten));
  if (first && !last) status = static_cast<uint8_t>(status | open);
  if (last) {
    status = static_cast<uint8_t>(status & ~open);
    if (filler && sm::is_mailbox(s.control)) {
      status = static_cast<uint8_t>(status | sm::kStatusFull | sm::kStatusWritten);
    } else if (filler) {
      status = static_cast<uint8_t>((status & ~sm::kStatusNoBuffer) | (s.next_buffer << 4) |
                                    sm::kStatusWritten);
      s.next_buffer = static_cast<uint8_t>(s.next_buffer == 2 ? 0 : s.next_buffer + 1);
    } else if (sm::is_mailbox(s.control)) {
      status = static_cast<uint8_t>((status & ~(sm::kStatusFull | sm::kStatusWritten)) |
                                    sm::kStatusRead);
    } else {
      status = static_cast<uint8_t>(status | sm::kStatusRead);
    }
  }
  uint8_t* const memory = mem_.data();
  memory[sm::base(n) + reg::kSmStatusOffset] = status;
  write_sm_events(memory, n, s.ecat_event_status, s.al_event_status, status);
}

void Esc::update_sm_events(int n) {
  uint8_t* const memory = mem_.data();
  write_sm_events(memory, n, sm_[n].ecat_event_status, sm_[n].al_event_status,
                  memory[sm::base(n) + reg::kSmStatusOffset]);
}

template <bool by_master>
bool Esc::sm_read_buffer(int n, uint8_t* dst) {
  // The SM's state is read before the copy (which may alias it for the compiler).
  const SmState& s = sm_[n];
  const bool active = s.active;
  const uint8_t control = s.control;
  const bool master_fills = sm::ecat_writes(control);
  // sm_allows_read: for the master, an SM the PDI deactivated or an empty mailbox gives no
  // data (no WKC); the PDI reads the memory as it is.
  if (by_master && (!active || (sm::is_mailbox(control) && !master_fills &&
                                (sm_status(n) & sm::kStatusFull) == 0))) {
    return false;
  }
  base::copy_bytes(dst, &mem_[s.start], s.length);
  // The side that drains the buffer (the other side fills it) opens and completes it.
  if (active && master_fills != by_master) sm_hand_over(n, true, true, false);
  return true;
}

template <bool by_master>
bool Esc::sm_write_buffer(int n, const uint8_t* src) {
  const SmState& s = sm_[n];
  const uint8_t control = s.control;
  // Only the side that fills the buffer writes it, a mailbox only once it is empty.
  if (sm::ecat_writes(control) != by_master || !sm_takes_write(n)) return false;
  base::copy_bytes(&mem_[s.start], src, s.length);
  sm_hand_over(n, true, true, true);
  // sm_after_write: a buffer the master completed retriggers the process-data watchdog.
  if (by_master && !sm::is_mailbox(control) && (control & sm::kControlWatchdog)) {
    watchdog_trigger(pass_.port0_ns);
  }
  return true;
}

int Esc::sm_exchange_buffers(int input, uint8_t* dst, int output, const uint8_t* src, bool write,
                             bool watchdog) {
  // sm_read_buffer<true> and sm_write_buffer<true> with their checks made by the plan; the
  // hand-overs inline with their constant arguments, so each is a few bit operations.
  const SmState& in = sm_[input];
  base::copy_bytes(dst, &mem_[in.start], in.length);
  sm_hand_over(input, true, true, false);
  if (!write) return 1;
  const SmState& out = sm_[output];
  base::copy_bytes(&mem_[out.start], src, out.length);
  sm_hand_over(output, true, true, true);
  if (watchdog) watchdog_trigger(pass_.port0_ns);
  return 3;
}

void Esc::exchange_datagram(uint8_t* datagram, uint16_t data_len) {
  const WholePlan& p = whole_plans_[last_plan_];
  uint8_t* const data = datagram + kDatagramHeaderSize;
  const bool write = !write_protection_active() || write_allowed(reg::kProcessRam);  // ESC-wide
  const int wkc = sm_exchange_buffers(p.input_sm, data + p.input_offset, p.output_sm,
                                      data + p.output_offset, write, p.exchange_watchdog);
  leave_datagram(datagram, data_len, static_cast<unsigned>(wkc));
}

template bool Esc::sm_read_buffer<true>(int n, uint8_t* dst);
template bool Esc::sm_read_buffer<false>(int n, uint8_t* dst);
template bool Esc::sm_write_buffer<true>(int n, const uint8_t* src);
template bool Esc::sm_write_buffer<false>(int n, const uint8_t* src);

}  // namespace rackcat::ecat
