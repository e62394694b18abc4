// The narrow interface between the slave firmware (ecat/slave) and the device behind it.
//
// What a device needs from the EtherCAT side: its SII EEPROM content, the mailbox protocols
// it serves (registered with the firmware's MailboxServer), the process-data images (SM2
// outputs, SM3 inputs) and the AL control requests it may refuse with an AL status code
// (ETG.1000.6 §5.3 "ESM"). ecat/ never sees the object dictionary; the device never sees a
// register. The firmware calls it the same way behind the emulated ESC or a real one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "base/esm_state.hpp"

namespace rackcat::ecat {

class MailboxServer;

// Sizes the device expects for the process-data SyncManagers with its current PDO
// assignment (0x1C12/0x1C13). The ESM compares SM2/SM3 against them on PREOP->SAFEOP and
// refuses with AL status 0x001D/0x001E when they differ (ETG.1000.6 Table 11).
struct ProcessDataSizes {
  uint16_t outputs = 0;  // bytes, SM2 (RxPDO, master -> slave)
  uint16_t inputs = 0;   // bytes, SM3 (TxPDO, slave -> master)
};

class Application {
 public:
  virtual ~Application() = default;

  // SII EEPROM image, byte-addressed little-endian words; must outlive the ESC. Writes by the
  // master through the SII interface go to the ESC's own copy, saved through on_eeprom_write.
  // The firmware reads its mailbox sizes here too (ETG.2010 Table 2, words 0x14-0x1B).
  virtual std::span<const uint8_t> eeprom() const = 0;
  virtual void on_eeprom_write(uint16_t /*word_address*/, std::span<const uint8_t> /*data*/) {}

  // A valid AL control request the firmware's own checks accept (SM checks passed). Return 0
  // to accept, or an AL status code (e.g. 0x0070 module list mismatch) to refuse: the ESM
  // then sets the error flag and that code. Called on the firmware's thread.
  virtual uint16_t on_state_request(EsmState from, EsmState to) = 0;
  // The state changed (accepted request, error fallback such as SM watchdog, or INIT reset).
  virtual void on_state_changed(EsmState from, EsmState to) = 0;

  virtual ProcessDataSizes process_data_sizes() const = 0;

  // The mailbox protocols the device serves: register each with server.add(type, protocol).
  // Called once, when the firmware starts. A device without mailbox registers none.
  virtual void add_mailbox_protocols(MailboxServer& /*server*/) {}
  // Whether a registered protocol may have an unsolicited message (an Emergency, a finished
  // background job's reply, a transfer to time out) that needs the firmware to run although
  // the ESC raised no event: the firmware sleeps on its IRQ line otherwise. Cheap and
  // thread-safe enough to be asked after every frame. The default (always) polls the
  // protocols after every frame that passes the slave.
  virtual bool mailbox_pending() const { return true; }

  // Process data. update_inputs fills the SM3 image the firmware then hands to the master
  // (after each SM2 write, or at SYNC0 when synchronised); on_outputs delivers a complete,
  // consistent SM2 buffer after the master wrote it, in OP. Both run on the cyclic path: no
  // allocation, no blocking.
  //
  // update_inputs returns true when the image may differ from the one last handed over, false
  // when the device left it untouched because it is provably identical to that image. On
  // false the firmware does not write SM3 again (except for the first image after entering
  // SAFEOP, which always goes out). That is invisible to the master on a real ESC too: a
  // 3-buffer SM3 keeps serving the newest complete buffer to every read (ETG.1000.4 §6.7.2),
  // so the bytes on the wire are the same. What does differ is that no buffer is handed over:
  // the buffer-state bits of the SM3 status register (0x0805+8*3, bits 4-5) stay, and no SM3
  // event follows for the PDI.
  virtual bool update_inputs(std::span<uint8_t> inputs) = 0;
  virtual void on_outputs(std::span<const uint8_t> outputs) = 0;

  // SYNC0/SYNC1 events from the distributed-clock unit (ETG.1000.4 §6.8.3).
  virtual void on_sync(int /*which*/, uint64_t /*system_time_ns*/) {}

  // The process-data watchdog expired (ESM falls to SAFEOP with 0x001B): outputs to safe state.
  virtual void on_watchdog_expired() {}
};

}  // namespace rackcat::ecat
