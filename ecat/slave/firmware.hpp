// The slave firmware: what the microcontroller behind an ESC runs (ETG.1000.6 §5.3, §5.6;
// ETG.1000.4 §6.7). It sees the chip only through a PdiPort and the device only through
// ecat::Application:
//
//   master --EtherCAT--> [ ESC (ecat/esc) ] --PdiPort--> [ Firmware ] --Application--> device
//
//   - the ESM (esm.cpp): AL control requests, the transition table with its checks (mailbox
//     SyncManagers against the SII, SM2/SM3 against the PDO sizes, DC), the device's veto,
//     the error flag and its acknowledge, local errors and the watchdog fallback;
//   - the mailbox (mailbox_server.hpp): SM0/SM1 hand-over, counter, repeat, double writes,
//     dispatch to the protocols the device registers;
//   - process data (process_data.cpp): SM2 outputs read when the master wrote them (AL event)
//     and handed to the device in OP; SM3 inputs produced then (free run) or at SYNC0 (DC
//     synchronous) and written for the master's next read.
//
// Drive it like a microcontroller on its IRQ line: poll() whenever wants_service() says so
// (after a frame, after a timer event). A slave whose ESC raised no event and whose device has
// nothing for the mailbox is not run at all. Nothing on that path allocates.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "base/esm_state.hpp"
#include "ecat/application.hpp"
#include "ecat/pdi_port.hpp"
#include "ecat/slave/esm_observer.hpp"
#include "ecat/slave/mailbox_server.hpp"

namespace rackcat::ecat {

class Firmware {
 public:
  // `pdi` and `app` must outlive the firmware. The device registers its mailbox protocols
  // here (Application::add_mailbox_protocols); then the firmware starts as after power-on.
  Firmware(PdiPort& pdi, Application& app);
  Firmware(const Firmware&) = delete;
  Firmware& operator=(const Firmware&) = delete;

  // The microcontroller (re)starts with the chip: AL event mask, every SyncManager
  // deactivated, INIT without error. The device hears INIT if it was in another state.
  void power_on();
  // One pass over the chip's events (AL event request 0x0220): AL control, SM activation,
  // mailbox, process data, SYNC, watchdog.
  void poll();
  // Whether poll() has work (ESC datasheet 0x0220/0x0204; ETG.1000.4 §6.5): the IRQ line is up
  // (an AL event the firmware takes: AL control, SM activation, SYNC0/1, watchdog, SM0/SM2/SM3
  // written or read), a SyncManager configured without AL event (control bit 5) must be polled
  // by its status, a DC-synchronised cycle is supervised, an EEPROM store waits for the master
  // to hand over the EEPROM (0x0500), or the device has an unsolicited
  // mailbox message (Application::mailbox_pending). SM1's "read" event is not taken: the
  // mailbox looks at SM1's status itself when it has something to send, as SOES does.
  bool wants_service() const {
    return pdi_.irq() || polls_status_ || eeprom_pending_ ||
           (mailbox_.running() && app_.mailbox_pending());
  }

  // The local application reports an error (ETG.1000.6 §5.3.3, "local error"): the ESM falls
  // to `fall_to` if that is below the current state (never rises), sets the error flag and
  // `code` in 0x0134 until the master acknowledges. E.g. a RIM lost with Detect Modules
  // Override 0 in OP: SAFEOP with the device's code.
  void application_error(EsmState fall_to, uint16_t code);
  // The local application restarted (e.g. the device reset command 0xFBF0, ETG.5003.1): the
  // ESM is back in INIT with no error; the master sees INIT in 0x0130 and configures the
  // slave again. Registers the master wrote (station address, SM/FMMU settings) are kept, as
  // they are when only the microcontroller behind an ESC resets.
  void application_restart();
  // The device's EEPROM content changed (e.g. a new firmware runs after 0xFBF0): the firmware
  // writes Application::eeprom() into the SII EEPROM through the PDI side of the EEPROM
  // interface (eeprom_store.cpp), so the master's next SII read sees it. Returns false when
  // the master holds the EEPROM (0x0500 bit 0 clear; poll() retries once it is offered) or a
  // write failed. Not for the cyclic path: it reads the whole EEPROM through the interface.
  bool store_eeprom();

  EsmState state() const { return state_; }
  bool error() const { return error_; }
  uint16_t status_code() const { return code_; }
  // The master's AL control byte 0x0120 as the ESM last read it.
  uint8_t al_control() const { return al_control_; }
  PdiPort& pdi() { return pdi_; }
  MailboxServer& mailbox() { return mailbox_; }
  // One observer (logging) of the ESM, the watchdog and the mailbox; nullptr removes it.
  void set_observer(EsmObserver* observer) {
    observer_ = observer;
    mailbox_.set_observer(observer);
  }
  EsmObserver* observer() const { return observer_; }

 private:
  // The SyncManager registers 0x0800+8n as the PDI reads them.
  struct Sm {
    uint16_t start = 0;
    uint16_t length = 0;
    uint8_t control = 0;
    uint8_t status = 0;
    uint8_t activate = 0;
    bool enabled = false;  // activate bit 0, non-zero length inside the address space
  };
  void read_sms();
  // Recomputes polls_status_ after the state, the SyncManagers taken, the DC supervision or the
  // mailbox's running flag changed (esm_enter, power_on, the DC check in poll).
  void update_polling();

  // esm.cpp
  void esm_control_written();
  uint16_t esm_check_transition(EsmState from, EsmState to);
  uint16_t esm_check_mailbox(bool bootstrap) const;
  uint16_t esm_check_process_data();
  uint16_t esm_check_dc();
  void esm_sm_changed(const std::array<Sm, 4>& before);
  void esm_enter(EsmState to);
  void esm_error(EsmState stay_or_fall_to, uint16_t code, EsmState requested);
  void esm_clear_error();
  void esm_write_status();
  void set_sm_deactivated(int n, bool deactivated);
  bool sync0_active();
  uint16_t sii_word(size_t word) const;

  // process_data.cpp
  void pd_start();
  void pd_outputs_written();
  void pd_produce_inputs();
  void pd_sync(int which);
  void pd_watchdog();

  // What wants_service() and a cyclic poll() read comes first, in the order they read it, then
  // the mailbox (its running flag first): a long line's round finds each firmware on as few
  // cache lines as it fits.
  PdiPort& pdi_;
  Application& app_;
  bool polls_status_ = false;        // poll() must run without an event (see wants_service)
  bool eeprom_pending_ = false;      // store_eeprom() waits for the master to offer the EEPROM
  bool dc_synchronised_ = false;     // SYNC0 was running when SAFEOP was entered
  bool inputs_handed_over_ = false;  // SM3 was written since pd_start
  EsmState state_ = EsmState::Init;
  std::array<Sm, 4> sm_taken_{};  // SM0-SM3 as checked when the current state was entered
  std::span<uint8_t> outputs_;    // SM2 as last read, in images_
  std::span<uint8_t> inputs_;     // SM3 image the device fills, in images_
  MailboxServer mailbox_;
  // The outputs, then the inputs: one allocation (sized on PREOP -> SAFEOP), so a small device's
  // two images share a cache line.
  std::vector<uint8_t> images_;

  EsmObserver* observer_ = nullptr;
  bool error_ = false;
  uint16_t code_ = 0;
  uint8_t al_control_ = 0;  // AL control 0x0120 as last read
  std::array<Sm, 4> sm_{};  // SM0-SM3 as last read
};

}  // namespace rackcat::ecat
