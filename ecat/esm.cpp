// The EtherCAT state machine (ETG.1000.6 §5.3) as the µC behind the PDI runs it: AL control
// requests, the transition table, the checks that produce AL status codes, the error flag
// and its acknowledge.
#include <array>

#include "base/event_log.hpp"
#include "ecat/al_status_code.hpp"
#include "ecat/esc.hpp"
#include "ecat/le.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// What a requested transition needs before it is taken (ETG.1000.6 Table 8 "state
// transitions" and Table 9 "local management services").
enum class Check : uint8_t {
  None,         // allowed: same state or a step down
  Invalid,      // 0x0011
  Mailbox,      // INIT -> PREOP: SM0/SM1 against SII words 0x18-0x1B (0x0016)
  Bootstrap,    // INIT -> BOOT: SII words 0x14-0x17 (0x0013, 0x0015)
  ProcessData,  // PREOP -> SAFEOP: SM configuration, SM2/SM3 vs PDO sizes, DC (0x0017,
                // 0x001D, 0x001E, 0x0030)
  Operational,  // SAFEOP -> OP: SYNC still running when synchronised (0x002C)
};

constexpr int index_of(AlState s) {
  switch (s) {
    case AlState::Init:
      return 0;
    case AlState::PreOp:
      return 1;
    case AlState::Boot:
      return 2;
    case AlState::SafeOp:
      return 3;
    case AlState::Op:
      return 4;
  }
  return 0;
}

using C = Check;
// Rows: from INIT, PREOP, BOOT, SAFEOP, OP; columns: to the same order.
constexpr std::array<std::array<Check, 5>, 5> kTransitions{{
    {C::None, C::Mailbox, C::Bootstrap, C::Invalid, C::Invalid},
    {C::None, C::None, C::Invalid, C::ProcessData, C::Invalid},
    {C::None, C::Invalid, C::None, C::Invalid, C::Invalid},
    {C::None, C::None, C::Invalid, C::None, C::Operational},
    {C::None, C::None, C::Invalid, C::None, C::None},
}};

constexpr bool valid_state(uint8_t v) {
  return v == 0x01 || v == 0x02 || v == 0x03 || v == 0x04 || v == 0x08;
}

constexpr uint8_t kErrorFlag = 0x10;
constexpr uint16_t kEventAlStatus = 0x0008;

bool ranges_overlap(uint32_t a, uint32_t alen, uint32_t b, uint32_t blen) {
  return a < b + blen && b < a + alen;
}

}  // namespace

void Esc::esm_control_written() {
  al_control_pending_ = false;
  mem_[reg::kAlEventRequest] &= static_cast<uint8_t>(~0x01);
  const uint8_t control = mem_[reg::kAlControl];
  const uint8_t requested = control & 0x0F;
  const bool acknowledge = control & kErrorFlag;
  if (al_error()) {
    // With the error flag set, only an acknowledged request (state | 0x10) or INIT is taken;
    // anything else leaves state and code as they are (ETG.1000.6 §5.3.2).
    if (!acknowledge && requested != static_cast<uint8_t>(AlState::Init)) return;
    mem_[reg::kAlStatus] &= static_cast<uint8_t>(~kErrorFlag);
    le::put16(&mem_[reg::kAlStatusCode], al_code::kNoError);
    esm_write_status();
  }
  if (!valid_state(requested)) {
    esm_error(state_, al_code::kUnknownState);
    return;
  }
  const auto to = static_cast<AlState>(requested);
  if (to == state_) return;
  uint16_t code = esm_check_transition(state_, to);
  if (code == 0) code = app_.on_state_request(state_, to);
  if (code != 0) {
    esm_error(state_, code);
    return;
  }
  esm_enter(to);
}

uint16_t Esc::esm_check_transition(AlState from, AlState to) {
  switch (kTransitions[index_of(from)][index_of(to)]) {
    case Check::None:
      return 0;
    case Check::Invalid:
      return al_code::kInvalidStateChange;
    case Check::Mailbox:
      return esm_check_mailbox(false);
    case Check::Bootstrap:
      return esm_check_mailbox(true);
    case Check::ProcessData:
      return esm_check_process_data();
    case Check::Operational:
      return dc_synchronised_ && !sync0_running_ ? al_code::kFatalSyncError : 0;
  }
  return al_code::kInvalidStateChange;
}

uint16_t Esc::esm_check_mailbox(bool bootstrap) const {
  // SII words 0x14-0x17 (bootstrap) or 0x18-0x1B (standard): receive mailbox offset and
  // size (SM0), send mailbox offset and size (SM1) (ETG.2010 Table 2).
  const size_t word = bootstrap ? 0x14 : 0x18;
  auto sii_word = [&](size_t w) -> uint16_t {
    return 2 * w + 1 < sii_.size() ? le::get16(&sii_[2 * w]) : 0;
  };
  const uint16_t rx_offset = sii_word(word), rx_size = sii_word(word + 1);
  const uint16_t tx_offset = sii_word(word + 2), tx_size = sii_word(word + 3);
  if (bootstrap && (rx_size == 0 || tx_size == 0)) return al_code::kBootstrapNotSupported;
  if (!bootstrap && rx_size == 0 && tx_size == 0) return 0;  // a device without mailbox
  const uint16_t code =
      bootstrap ? al_code::kInvalidBootMailboxConfig : al_code::kInvalidMailboxConfig;
  const SmState& rx = sm_[0];
  const SmState& tx = sm_[1];
  // Mailbox mode (control bits 1:0 = 10b), SM0 ECAT writes (bits 3:2 = 01b), SM1 ECAT reads.
  if (!rx.enabled || rx.start != rx_offset || rx.length != rx_size || (rx.control & 0x0F) != 0x06) {
    return code;
  }
  if (!tx.enabled || tx.start != tx_offset || tx.length != tx_size || (tx.control & 0x0F) != 0x02) {
    return code;
  }
  if (ranges_overlap(rx.start, rx.length, tx.start, tx.length)) return code;
  return 0;
}

uint16_t Esc::esm_check_process_data() const {
  // 0x0017: every enabled SyncManager lies in process RAM and no two overlap.
  for (int i = 0; i < kSyncManagers; ++i) {
    const SmState& a = sm_[i];
    if (!a.enabled) continue;
    if (a.start < reg::kProcessRam ||
        static_cast<uint32_t>(a.start) + a.length > reg::kAddressSpace) {
      return al_code::kInvalidSmConfig;
    }
    for (int j = i + 1; j < kSyncManagers; ++j) {
      const SmState& b = sm_[j];
      if (b.enabled && ranges_overlap(a.start, a.length, b.start, b.length)) {
        return al_code::kInvalidSmConfig;
      }
    }
  }
  // 0x001D / 0x001E: SM2 (outputs) and SM3 (inputs) match the PDO assignment's sizes, in
  // buffered mode with the right direction; a device without outputs (inputs) needs SM2
  // (SM3) disabled (ETG.1000.6 Table 11).
  const ProcessDataSizes sizes = app_.process_data_sizes();
  const SmState& out = sm_[2];
  if (sizes.outputs != 0) {
    if (!out.enabled || out.length != sizes.outputs || (out.control & 0x0F) != 0x04) {
      return al_code::kInvalidOutputConfig;
    }
  } else if (out.enabled) {
    return al_code::kInvalidOutputConfig;
  }
  const SmState& in = sm_[3];
  if (sizes.inputs != 0) {
    if (!in.enabled || in.length != sizes.inputs || (in.control & 0x0F) != 0x00) {
      return al_code::kInvalidInputConfig;
    }
  } else if (in.enabled) {
    return al_code::kInvalidInputConfig;
  }
  return esm_check_dc();
}

uint16_t Esc::esm_check_dc() const {
  // 0x0030: SYNC outputs need the cyclic unit (bit 0), SYNC1 needs SYNC0, and SYNC0 needs a
  // cycle time (0 would be a single shot, no cycle to follow).
  const uint8_t activation = mem_[reg::kDcActivation];
  const bool cyclic = activation & 0x01;
  const bool sync0 = activation & 0x02;
  const bool sync1 = activation & 0x04;
  if ((sync0 || sync1) && !cyclic) return al_code::kInvalidDcSyncConfig;
  if (sync1 && !sync0) return al_code::kInvalidDcSyncConfig;
  if (sync0 && le::get32(&mem_[reg::kDcSync0Cycle]) == 0) return al_code::kInvalidDcSyncConfig;
  return 0;
}

void Esc::esm_sm_changed() {
  // ETG.1000.6 §5.3: the SyncManager settings checked on the way up must stay valid. A master
  // that disables or moves SM2/SM3 in SAFEOP/OP sends the slave back to PREOP with 0x001D /
  // 0x001E; SM0/SM1 changed in PREOP or above send it to INIT with 0x0016.
  const uint8_t changed = sm_changed_;
  sm_changed_ = 0;
  const bool mailbox_state =
      state_ == AlState::PreOp || state_ == AlState::SafeOp || state_ == AlState::Op;
  if ((changed & 0x03) && mailbox_state && esm_check_mailbox(false) != 0) {
    esm_error(AlState::Init, al_code::kInvalidMailboxConfig);
    return;
  }
  if ((changed & 0x0C) && (state_ == AlState::SafeOp || state_ == AlState::Op)) {
    const uint16_t code = esm_check_process_data();
    if (code != 0) esm_error(AlState::PreOp, code);
  }
}

void Esc::esm_log(base::EventKind kind, uint8_t from, uint8_t to, uint16_t code) const {
  base::log_event({.kind = kind,
                   .a = from,
                   .b = to,
                   .c = mem_[reg::kAlControl],
                   .code = code,
                   .station = le::get16(&mem_[reg::kStationAddress])});
}

void Esc::esm_enter(AlState to) {
  const AlState from = state_;
  if (to == AlState::Init) {
    for (int n = 0; n < kSyncManagers; ++n) set_sm_pdi_deactivated(n, true);
    last_reply_len_ = 0;
    repeat_pending_ = false;
  }
  if (to == AlState::PreOp || to == AlState::Boot) {
    if (from == AlState::Init) {
      set_sm_pdi_deactivated(0, false);
      set_sm_pdi_deactivated(1, false);
      mailbox_work_ = true;
    } else {
      set_sm_pdi_deactivated(2, true);
      set_sm_pdi_deactivated(3, true);
    }
  }
  if (to == AlState::Init || to == AlState::PreOp || to == AlState::Boot) {
    dc_synchronised_ = false;
    watchdog_armed_ = false;
  }
  if (to == AlState::SafeOp && from == AlState::PreOp) {
    outputs_.assign(sm_[2].enabled ? sm_[2].length : 0, 0);
    set_sm_pdi_deactivated(2, false);
    set_sm_pdi_deactivated(3, false);
    dc_synchronised_ = sync0_running_;
  }
  state_ = to;
  if (to == AlState::Op && sm_[2].enabled && (sm_[2].control & 0x40)) {
    watchdog_trigger(pass_.port0_ns);  // the watchdog starts counting with OP
  }
  esm_write_status();
  esm_log(base::EventKind::EsmTransition, static_cast<uint8_t>(from), static_cast<uint8_t>(to),
          le::get16(&mem_[reg::kAlStatusCode]));
  app_.on_state_changed(from, to);
}

void Esc::application_error(AlState fall_to, uint16_t code) {
  // Only a step down the table is taken (OP -> SAFEOP/PREOP/INIT, BOOT -> INIT, ...); anything
  // else (a "fall" to BOOT, to the same or a higher state) keeps the state and sets the error.
  constexpr int kRank[5] = {0, 1, 1, 2, 3};  // INIT, PREOP, BOOT, SAFEOP, OP
  const int from = index_of(state_);
  const int to = index_of(fall_to);
  const bool step_down = kRank[to] < kRank[from] && kTransitions[from][to] == Check::None;
  esm_error(step_down ? fall_to : state_, code);
}

void Esc::application_restart() {
  mem_[reg::kAlStatus] &= static_cast<uint8_t>(~kErrorFlag);
  le::put16(&mem_[reg::kAlStatusCode], 0);
  if (state_ != AlState::Init) {
    esm_enter(AlState::Init);
  } else {
    esm_write_status();
  }
}

void Esc::esm_error(AlState stay_or_fall_to, uint16_t code) {
  esm_log(base::EventKind::EsmError, static_cast<uint8_t>(state_),
          static_cast<uint8_t>(stay_or_fall_to), code);
  if (stay_or_fall_to != state_) esm_enter(stay_or_fall_to);
  mem_[reg::kAlStatus] |= kErrorFlag;
  le::put16(&mem_[reg::kAlStatusCode], code);
  esm_write_status();
}

void Esc::esm_write_status() {
  const uint8_t status =
      static_cast<uint8_t>(static_cast<uint8_t>(state_) | (mem_[reg::kAlStatus] & kErrorFlag));
  mem_[reg::kAlStatus] = status;
  mem_[reg::kAlStatus + 1] = 0;
  le::put16(&mem_[reg::kEcatEventRequest],
            le::get16(&mem_[reg::kEcatEventRequest]) | kEventAlStatus);
}

}  // namespace rackcat::ecat
