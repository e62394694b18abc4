// SyncManager semantics (ETG.1000.4 §6.7): mailbox mode (one buffer, full flag, hand-over on
// the last byte, repeat request) and buffered mode (three buffers, consistent images), the
// PDI deactivate bit, and the mailbox/process-data events that drive the Application.
#include <algorithm>
#include <cstring>

#include "ecat/esc.hpp"
#include "ecat/le.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// SM control byte (ETG.1000.4 Table 58): bits 1:0 mode (00 buffered, 10 mailbox), bits 3:2
// direction (00 ECAT reads / PDI writes, 01 ECAT writes / PDI reads), bit 4 ECAT event
// enable, bit 5 AL event enable, bit 6 watchdog trigger enable.
constexpr bool is_mailbox(uint8_t control) {
  return (control & 0x03) == 0x02;
}
constexpr bool ecat_writes(uint8_t control) {
  return (control & 0x0C) == 0x04;
}
// SM status byte: bit 0 "interrupt write" (buffer completely written), bit 1 "interrupt read"
// (buffer completely read), bit 3 mailbox full, bits 5:4 last written buffer (11 = none).
constexpr uint8_t kStatusWritten = 0x01;
constexpr uint8_t kStatusRead = 0x02;
constexpr uint8_t kStatusFull = 0x08;
constexpr uint8_t kStatusNoBuffer = 0x30;

constexpr int kMailboxIn = 0;   // SM0: master -> slave mailbox (ETG.1000.6 §5.6.1)
constexpr int kMailboxOut = 1;  // SM1: slave -> master mailbox
constexpr int kOutputs = 2;     // SM2: RxPDO
constexpr int kInputs = 3;      // SM3: TxPDO

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
  const bool old_repeat = s.repeat_request;
  s.start = le::get16(&mem_[base]);
  s.length = le::get16(&mem_[base + 2]);
  s.control = mem_[base + reg::kSmControlOffset];
  const uint8_t activate = mem_[base + reg::kSmActivateOffset];
  // A buffer running past the end of the address space does not work as a SyncManager.
  s.enabled = (activate & 0x01) && s.length != 0 &&
              static_cast<uint32_t>(s.start) + s.length <= reg::kAddressSpace;
  s.active = s.enabled && (mem_[base + reg::kSmPdiControlOffset] & 0x01) == 0;
  s.repeat_request = (activate & 0x02) != 0;
  if (s.enabled) {
    sm_enabled_mask_ |= static_cast<uint16_t>(1u << n);
  } else {
    sm_enabled_mask_ &= static_cast<uint16_t>(~(1u << n));
  }
  if (s.enabled != was_enabled || s.active != was_active) {
    // (De)activation empties the buffers (ESC datasheet 0x0805).
    mem_[base + reg::kSmStatusOffset] = is_mailbox(s.control) ? 0x00 : kStatusNoBuffer;
    s.next_buffer = 0;
    mem_[reg::kAlEventRequest] |= 0x10;  // SM activation register changed
    if (n == kMailboxOut && s.active) mailbox_work_ = true;
  }
  if (s.enabled && s.repeat_request != old_repeat && is_mailbox(s.control) &&
      !ecat_writes(s.control)) {
    repeat_pending_ = true;  // the master lost a reply and asks for it again
  }
  update_ecat_event(n);
  // The master reconfigured a mailbox or process-data SM under a running state: the µC
  // checks it after the frame (esm_sm_changed).
  const bool config_changed = before.enabled != s.enabled || before.start != s.start ||
                              before.length != s.length || before.control != s.control;
  if (config_changed && n < 4) sm_changed_ |= static_cast<uint8_t>(1u << n);
}

void Esc::set_sm_pdi_deactivated(int n, bool deactivated) {
  uint8_t& pdi = mem_[sm_base(n) + reg::kSmPdiControlOffset];
  pdi = static_cast<uint8_t>(deactivated ? (pdi | 0x01) : (pdi & ~0x01));
  reload_sm(n);
}

bool Esc::sm_allows_read(uint16_t address, uint16_t len) {
  if (sm_enabled_mask_ == 0) return true;
  const uint32_t end = static_cast<uint32_t>(address) + len;
  bool refresh_inputs = false;
  for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= mask - 1) {
    const int n = __builtin_ctz(mask);
    const SmState& s = sm_[n];
    const uint32_t s_end = static_cast<uint32_t>(s.start) + s.length;
    if (!(address < s_end && s.start < end)) continue;
    // A SyncManager deactivated by the PDI blocks its buffer: no data, no WKC.
    if (!s.active) return false;
    const uint8_t status = mem_[sm_base(n) + reg::kSmStatusOffset];
    if (is_mailbox(s.control)) {
      if (!ecat_writes(s.control) && (status & kStatusFull) == 0) return false;  // empty
    } else if (!ecat_writes(s.control) && n == kInputs && address <= s.start) {
      refresh_inputs = true;  // reading the first byte opens the newest input buffer
    }
  }
  if (refresh_inputs && (state_ == AlState::SafeOp || state_ == AlState::Op)) {
    const SmState& s = sm_[kInputs];
    app_.update_inputs(std::span<uint8_t>(&mem_[s.start], s.length));
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
      if (n == kMailboxOut) mailbox_work_ = true;  // free again: next reply may go in
    } else {
      status = static_cast<uint8_t>((status & ~kStatusWritten) | kStatusRead);
    }
    update_ecat_event(n);
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
      if (n == kMailboxIn) mailbox_work_ = true;
      update_ecat_event(n);
      continue;
    }
    // Buffered: the written buffer becomes the newest; report its index in bits 5:4.
    status = static_cast<uint8_t>((status & ~(kStatusNoBuffer | kStatusRead)) |
                                  (sm_[n].next_buffer << 4) | kStatusWritten);
    sm_[n].next_buffer = static_cast<uint8_t>((sm_[n].next_buffer + 1) % 3);
    update_ecat_event(n);
    if (n != kOutputs) continue;
    if (s.control & 0x40) watchdog_trigger(pass_.port0_ns);
    if (state_ == AlState::Op && outputs_.size() == s.length) {
      std::memcpy(outputs_.data(), &mem_[s.start], s.length);
      app_.on_outputs(outputs_);
    }
  }
}

void Esc::mailbox_service() {
  mailbox_work_ = false;
  SmState& in = sm_[kMailboxIn];
  SmState& out = sm_[kMailboxOut];
  if (!out.active || !is_mailbox(out.control) || ecat_writes(out.control)) {
    repeat_pending_ = false;
    return;
  }
  uint8_t& out_status = mem_[sm_base(kMailboxOut) + reg::kSmStatusOffset];
  auto publish = [&](size_t n) {
    out_status = static_cast<uint8_t>((out_status & ~kStatusRead) | kStatusFull | kStatusWritten);
    last_reply_.assign(&mem_[out.start], &mem_[out.start] + n);
    last_reply_len_ = n;
  };
  if (repeat_pending_) {
    // Repeat request (ETG.1000.4 §6.7.3): put the last reply back and toggle the ack bit.
    repeat_pending_ = false;
    if (last_reply_len_ != 0 && last_reply_len_ <= out.length) {
      std::memcpy(&mem_[out.start], last_reply_.data(), last_reply_len_);
      out_status = static_cast<uint8_t>((out_status & ~kStatusRead) | kStatusFull | kStatusWritten);
    }
    mem_[sm_base(kMailboxOut) + reg::kSmPdiControlOffset] ^= 0x02;
    update_ecat_event(kMailboxOut);
    return;
  }
  if (out_status & kStatusFull) return;  // the master has not read the last reply yet
  const std::span<uint8_t> reply(&mem_[out.start], out.length);
  size_t n = 0;
  const bool in_ok = in.active && is_mailbox(in.control) && ecat_writes(in.control) &&
                     (in.start + in.length <= out.start || out.start + out.length <= in.start);
  uint8_t& in_status = mem_[sm_base(kMailboxIn) + reg::kSmStatusOffset];
  if (in_ok && (in_status & kStatusFull)) {
    n = app_.on_mailbox(std::span<const uint8_t>(&mem_[in.start], in.length), reply);
    in_status = static_cast<uint8_t>((in_status & ~(kStatusFull | kStatusWritten)) | kStatusRead);
    update_ecat_event(kMailboxIn);
  }
  if (n == 0) n = app_.poll_mailbox(reply);
  if (n != 0) {
    publish(std::min<size_t>(n, out.length));
    update_ecat_event(kMailboxOut);
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

}  // namespace rackcat::ecat
