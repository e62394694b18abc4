// The firmware's main loop: power-on and one pass over the chip's AL events (ETG.1000.4 §6.5
// "AL event request 0x0220"), in the order a microcontroller's ISR takes them.
#include "ecat/slave/firmware.hpp"

#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// AL event request 0x0220 / mask 0x0204 bits (ESC datasheet section II, 0x0220).
constexpr uint32_t kEventAlControl = 0x0001;
constexpr uint32_t kEventSync0 = 0x0004;
constexpr uint32_t kEventSync1 = 0x0008;
constexpr uint32_t kEventSmActivation = 0x0010;
constexpr uint32_t kEventWatchdog = 0x0040;
constexpr uint32_t kEventSm0 = 0x0100;
constexpr uint32_t kEventSm2 = 0x0400;
constexpr uint32_t kEventSm3 = 0x0800;
// The events the firmware takes: AL control, SYNC0/1, SM activation, watchdog, SM0, SM2, SM3.
// Not SM1 (0x0200, "mailbox read by the master"): it stays pending until the next reply is
// written, which would keep the IRQ line up between exchanges; the mailbox checks SM1's
// status when it has a message to send instead.
constexpr uint32_t kEventMask = kEventAlControl | kEventSync0 | kEventSync1 | kEventSmActivation |
                                kEventWatchdog | kEventSm0 | kEventSm2 | kEventSm3;

}  // namespace

Firmware::Firmware(PdiPort& pdi, Application& app) : pdi_(pdi), app_(app), mailbox_(pdi) {
  app_.add_mailbox_protocols(mailbox_);
  power_on();
}

void Firmware::power_on() {
  const EsmState previous = state_;
  pdi_.write32(reg::kAlEventMask, kEventMask);
  for (int n = 0; n < 16; ++n) set_sm_deactivated(n, true);
  mailbox_.stop();
  state_ = EsmState::Init;
  error_ = false;
  code_ = 0;
  dc_synchronised_ = false;
  sm_taken_ = {};
  read_sms();
  update_polling();
  esm_write_status();
  if (previous != EsmState::Init) {
    app_.on_state_changed(previous, EsmState::Init);
    if (observer_ != nullptr) observer_->on_transition(previous, EsmState::Init);
  }
}

void Firmware::read_sms() {
  // One read of SM0-SM3 (0x0800-0x081F); reading the activation bytes clears AL event bit 4.
  uint8_t regs[4 * reg::kSmSize];
  pdi_.read(reg::kSm, regs);
  for (int n = 0; n < 4; ++n) {
    const uint8_t* r = &regs[n * reg::kSmSize];
    Sm& s = sm_[n];
    s.start = le::get16(r);
    s.length = le::get16(r + 2);
    s.control = r[reg::kSmControlOffset];
    s.status = r[reg::kSmStatusOffset];
    s.activate = r[reg::kSmActivateOffset];
    s.enabled = (s.activate & reg::sm::kActivateEnable) && s.length != 0 &&
                static_cast<uint32_t>(s.start) + s.length <= reg::kAddressSpace;
  }
}

void Firmware::update_polling() {
  const auto without_event = [](const Sm& s) {
    return s.enabled && (s.control & reg::sm::kControlAlEvent) == 0;
  };
  const bool process_data = state_ == EsmState::SafeOp || state_ == EsmState::Op;
  polls_status_ = dc_synchronised_ ||
                  (process_data && (without_event(sm_taken_[2]) || without_event(sm_taken_[3]))) ||
                  (mailbox_.running() && (sm_taken_[0].control & reg::sm::kControlAlEvent) == 0);
}

void Firmware::poll() {
  const uint32_t events = pdi_.read32(reg::kAlEventRequest);
  if (events & kEventAlControl) esm_control_written();
  const bool activation = (events & kEventSmActivation) != 0;
  if (activation) {
    const std::array<Sm, 4> before = sm_;
    read_sms();
    esm_sm_changed(before);
  }
  if (events & kEventWatchdog) pd_watchdog();
  if (eeprom_pending_ && (pdi_.read8(reg::kSiiConfig) & 0x01) != 0) store_eeprom();
  if (events & kEventSync0) pd_sync(0);
  if (events & kEventSync1) pd_sync(1);
  if (state_ == EsmState::SafeOp || state_ == EsmState::Op) {
    // A SyncManager configured without AL event (control bit 5) is polled by its status: SM2
    // written by the master, SM3 read by it (ESI devices without mailbox, e.g. ControlByte 0x00).
    const bool sm2 =
        (events & kEventSm2) ||
        (sm_taken_[2].enabled && !(sm_taken_[2].control & reg::sm::kControlAlEvent) &&
         (pdi_.read8(reg::sm::base(2) + reg::kSmStatusOffset) & reg::sm::kStatusWritten));
    const bool sm3 = (events & kEventSm3) ||
                     (sm_taken_[3].enabled && !(sm_taken_[3].control & reg::sm::kControlAlEvent) &&
                      (pdi_.read8(reg::sm::base(3) + reg::kSmStatusOffset) & reg::sm::kStatusRead));
    if (sm2) pd_outputs_written();
    if (sm2 || sm3) pd_produce_inputs();
    if (dc_synchronised_ && !sync0_active()) {
      // The device follows SYNC0; without it the slave cannot keep its cycle (ETG.1000.6
      // Table 11, 0x002C).
      dc_synchronised_ = false;
      update_polling();
      esm_error(EsmState::SafeOp, 0x002C, EsmState::SafeOp);
    }
  }
  if (mailbox_.running()) {
    const bool sm0 = (events & kEventSm0) ||
                     (!(sm_taken_[0].control & reg::sm::kControlAlEvent) &&
                      (pdi_.read8(reg::sm::base(0) + reg::kSmStatusOffset) & reg::sm::kStatusFull));
    // Nothing for the mailbox unless the master wrote SM0, changed an SM (repeat request) or
    // the device has a message to send: no SM1 status read, no protocol poll on the cyclic
    // frames in between.
    if (sm0 || activation || app_.mailbox_pending()) mailbox_.service(state_, sm0, activation);
  }
  // polls_status_ follows the state, the SyncManagers taken with it, the DC supervision and the
  // mailbox's running flag: esm_enter and power_on recompute it, the DC check above too.
}

}  // namespace rackcat::ecat
