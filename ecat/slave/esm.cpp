// The EtherCAT state machine (ETG.1000.6 §5.3) as the firmware runs it behind the PDI: AL
// control requests (0x0120), the transition table, the checks that produce AL status codes
// (ETG.1000.6 Table 11), the error flag and its acknowledge, and what each state opens: SM0/SM1
// from PREOP (or BOOT), SM2/SM3 from SAFEOP, by the PDI deactivate bits 0x0807+8n.
#include <array>

#include "ecat/al_status_code.hpp"
#include "ecat/registers.hpp"
#include "ecat/slave/firmware.hpp"

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

constexpr int index_of(EsmState s) {
  switch (s) {
    case EsmState::Init:
      return 0;
    case EsmState::PreOp:
      return 1;
    case EsmState::Boot:
      return 2;
    case EsmState::SafeOp:
      return 3;
    case EsmState::Op:
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

constexpr uint8_t kErrorFlag = 0x10;

bool ranges_overlap(uint32_t a, uint32_t alen, uint32_t b, uint32_t blen) {
  return a < b + blen && b < a + alen;
}

}  // namespace

uint16_t Firmware::sii_word(size_t word) const {
  const std::span<const uint8_t> sii = app_.eeprom();
  return 2 * word + 1 < sii.size() ? le::get16(&sii[2 * word]) : 0;
}

void Firmware::esm_control_written() {
  // Reading AL control clears AL event request bit 0.
  const uint8_t control = pdi_.read8(reg::kAlControl);
  al_control_ = control;
  const uint8_t requested = control & 0x0F;
  const bool acknowledge = control & kErrorFlag;
  if (error_) {
    // With the error flag set, only an acknowledged request (state | 0x10) or INIT is taken;
    // anything else leaves state and code as they are (ETG.1000.6 §5.3.2).
    if (!acknowledge && requested != static_cast<uint8_t>(EsmState::Init)) return;
    esm_clear_error();
  }
  if (!is_esm_state(requested)) {
    esm_error(state_, al_code::kUnknownState, state_);
    return;
  }
  const auto to = static_cast<EsmState>(requested);
  if (to == state_) return;
  read_sms();
  uint16_t code = esm_check_transition(state_, to);
  if (code == 0) code = app_.on_state_request(state_, to);
  if (code != 0) {
    esm_error(state_, code, to);
    return;
  }
  esm_enter(to);
}

uint16_t Firmware::esm_check_transition(EsmState from, EsmState to) {
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
      return dc_synchronised_ && !sync0_active() ? al_code::kFatalSyncError : 0;
  }
  return al_code::kInvalidStateChange;
}

uint16_t Firmware::esm_check_mailbox(bool bootstrap) const {
  // SII words 0x14-0x17 (bootstrap) or 0x18-0x1B (standard): receive mailbox offset and
  // size (SM0), send mailbox offset and size (SM1) (ETG.2010 Table 2).
  const size_t word = bootstrap ? 0x14 : 0x18;
  const uint16_t rx_offset = sii_word(word), rx_size = sii_word(word + 1);
  const uint16_t tx_offset = sii_word(word + 2), tx_size = sii_word(word + 3);
  if (bootstrap && (rx_size == 0 || tx_size == 0)) return al_code::kBootstrapNotSupported;
  if (!bootstrap && rx_size == 0 && tx_size == 0) return 0;  // a device without mailbox
  const uint16_t code =
      bootstrap ? al_code::kInvalidBootMailboxConfig : al_code::kInvalidMailboxConfig;
  const Sm& rx = sm_[0];
  const Sm& tx = sm_[1];
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

uint16_t Firmware::esm_check_process_data() {
  // 0x0017: every enabled SyncManager lies in process RAM and no two overlap (all 16 are
  // read here, at the transition, not on the cyclic path).
  uint8_t regs[16 * reg::kSmSize];
  pdi_.read(reg::kSm, regs);
  auto start = [&](int n) { return le::get16(&regs[n * reg::kSmSize]); };
  auto length = [&](int n) { return le::get16(&regs[n * reg::kSmSize + 2]); };
  auto enabled = [&](int n) {
    return (regs[n * reg::kSmSize + reg::kSmActivateOffset] & reg::sm::kActivateEnable) &&
           length(n) != 0 && static_cast<uint32_t>(start(n)) + length(n) <= reg::kAddressSpace;
  };
  for (int i = 0; i < 16; ++i) {
    if (!enabled(i)) continue;
    if (start(i) < reg::kProcessRam) return al_code::kInvalidSmConfig;
    for (int j = i + 1; j < 16; ++j) {
      if (enabled(j) && ranges_overlap(start(i), length(i), start(j), length(j))) {
        return al_code::kInvalidSmConfig;
      }
    }
  }
  // 0x001D / 0x001E: SM2 (outputs) and SM3 (inputs) match the PDO assignment's sizes, in
  // buffered mode with the right direction; a device without outputs (inputs) needs SM2
  // (SM3) disabled (ETG.1000.6 Table 11).
  const ProcessDataSizes sizes = app_.process_data_sizes();
  const Sm& out = sm_[2];
  if (sizes.outputs != 0) {
    if (!out.enabled || out.length != sizes.outputs || (out.control & 0x0F) != 0x04) {
      return al_code::kInvalidOutputConfig;
    }
  } else if (out.enabled) {
    return al_code::kInvalidOutputConfig;
  }
  const Sm& in = sm_[3];
  if (sizes.inputs != 0) {
    if (!in.enabled || in.length != sizes.inputs || (in.control & 0x0F) != 0x00) {
      return al_code::kInvalidInputConfig;
    }
  } else if (in.enabled) {
    return al_code::kInvalidInputConfig;
  }
  return esm_check_dc();
}

uint16_t Firmware::esm_check_dc() {
  // 0x0030: SYNC outputs need the cyclic unit (bit 0), SYNC1 needs SYNC0, and SYNC0 needs a
  // cycle time (0 would be a single shot, no cycle to follow).
  const uint8_t activation = pdi_.read8(reg::kDcActivation);
  const bool cyclic = activation & 0x01;
  const bool sync0 = activation & 0x02;
  const bool sync1 = activation & 0x04;
  if ((sync0 || sync1) && !cyclic) return al_code::kInvalidDcSyncConfig;
  if (sync1 && !sync0) return al_code::kInvalidDcSyncConfig;
  if (sync0 && pdi_.read32(reg::kDcSync0Cycle) == 0) return al_code::kInvalidDcSyncConfig;
  return 0;
}

bool Firmware::sync0_active() {
  return (pdi_.read8(reg::kDcActivation) & 0x03) == 0x03;
}

void Firmware::esm_sm_changed(const std::array<Sm, 4>& before) {
  // ETG.1000.6 §5.3: the SyncManager settings checked on the way up must stay valid. A master
  // that disables or moves SM2/SM3 in SAFEOP/OP sends the slave back to PREOP with 0x001D /
  // 0x001E; SM0/SM1 changed in PREOP or above send it to INIT with 0x0016.
  uint8_t changed = 0;
  for (int n = 0; n < 4; ++n) {
    const Sm& a = before[n];
    const Sm& b = sm_[n];
    if (a.enabled != b.enabled || a.start != b.start || a.length != b.length ||
        a.control != b.control) {
      changed |= static_cast<uint8_t>(1u << n);
    }
  }
  const bool mailbox_state =
      state_ == EsmState::PreOp || state_ == EsmState::SafeOp || state_ == EsmState::Op;
  if ((changed & 0x03) && mailbox_state && esm_check_mailbox(false) != 0) {
    esm_error(EsmState::Init, al_code::kInvalidMailboxConfig, state_);
    return;
  }
  if ((changed & 0x0C) && (state_ == EsmState::SafeOp || state_ == EsmState::Op)) {
    const uint16_t code = esm_check_process_data();
    if (code != 0) esm_error(EsmState::PreOp, code, state_);
  }
}

void Firmware::set_sm_deactivated(int n, bool deactivated) {
  const auto address = static_cast<uint16_t>(reg::sm::base(n) + reg::kSmPdiControlOffset);
  const uint8_t pdi = pdi_.read8(address);
  const auto value = static_cast<uint8_t>(deactivated ? (pdi | reg::sm::kPdiDeactivate)
                                                      : (pdi & ~reg::sm::kPdiDeactivate));
  if (value != pdi) pdi_.write8(address, value);
}

void Firmware::esm_enter(EsmState to) {
  const EsmState from = state_;
  if (to == EsmState::Init) {
    for (int n = 0; n < 16; ++n) set_sm_deactivated(n, true);
    mailbox_.stop();
  }
  if (to == EsmState::PreOp || to == EsmState::Boot) {
    if (from == EsmState::Init) {
      set_sm_deactivated(0, false);
      set_sm_deactivated(1, false);
      mailbox_.start(sm_[0].start, sm_[0].length, sm_[1].start, sm_[1].length);
    } else {
      set_sm_deactivated(2, true);
      set_sm_deactivated(3, true);
    }
  }
  if (to == EsmState::Init || to == EsmState::PreOp || to == EsmState::Boot) {
    dc_synchronised_ = false;
  }
  sm_taken_ = sm_;
  state_ = to;
  if (to == EsmState::SafeOp && from == EsmState::PreOp) {
    dc_synchronised_ = sync0_active();
    pd_start();
  }
  update_polling();
  esm_write_status();
  app_.on_state_changed(from, to);
  if (observer_ != nullptr) observer_->on_transition(from, to);
}

void Firmware::application_error(EsmState fall_to, uint16_t code) {
  // Only a step down the table is taken (OP -> SAFEOP/PREOP/INIT, BOOT -> INIT, ...); anything
  // else (a "fall" to BOOT, to the same or a higher state) keeps the state and sets the error.
  constexpr int kRank[5] = {0, 1, 1, 2, 3};  // INIT, PREOP, BOOT, SAFEOP, OP
  const int from = index_of(state_);
  const int to = index_of(fall_to);
  const bool step_down = kRank[to] < kRank[from] && kTransitions[from][to] == Check::None;
  esm_error(step_down ? fall_to : state_, code, state_);
}

void Firmware::application_restart() {
  if (error_) esm_clear_error();
  if (state_ != EsmState::Init) {
    esm_enter(EsmState::Init);
  } else {
    esm_write_status();
  }
}

void Firmware::esm_error(EsmState stay_or_fall_to, uint16_t code, EsmState requested) {
  const EsmState from = state_;
  if (stay_or_fall_to != state_) esm_enter(stay_or_fall_to);
  error_ = true;
  code_ = code;
  pdi_.write16(reg::kAlStatusCode, code);
  esm_write_status();
  if (observer_ != nullptr) observer_->on_al_error(from, state_, requested, al_control_, code);
}

void Firmware::esm_clear_error() {
  error_ = false;
  code_ = al_code::kNoError;
  pdi_.write16(reg::kAlStatusCode, al_code::kNoError);
  esm_write_status();
  if (observer_ != nullptr) observer_->on_error_cleared(state_);
}

void Firmware::esm_write_status() {
  // AL status 0x0130: state bits 3..0 and the error flag; the chip raises the master's AL
  // status event (0x0210 bit 3) on the write.
  pdi_.write16(reg::kAlStatus,
               static_cast<uint16_t>(static_cast<uint8_t>(state_) | (error_ ? kErrorFlag : 0)));
}

}  // namespace rackcat::ecat
