// The narrow interface between the emulated ESC (ecat/) and the device behind it.
//
// This is the PDI side of a real ESC, reduced to what a slave application needs: the SII
// EEPROM content, the mailbox (SM0 in, SM1 out), the process-data buffers (SM2 outputs, SM3
// inputs) and the AL control requests the application may refuse with an AL status code
// (ETG.1000.6 §5.3 "ESM"). ecat/ never sees the object dictionary; the device never sees a
// register. The same device code could run behind a real ESC driver implementing the caller
// side of this interface.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace rackcat::ecat {

// AL states as encoded in AL control/status bits 3..0 (ETG.1000.6 Table 9).
enum class AlState : uint8_t { Init = 0x01, PreOp = 0x02, Boot = 0x03, SafeOp = 0x04, Op = 0x08 };

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
  virtual std::span<const uint8_t> eeprom() const = 0;
  virtual void on_eeprom_write(uint16_t /*word_address*/, std::span<const uint8_t> /*data*/) {}

  // A valid AL control request the ESC itself accepts (SM checks passed). Return 0 to accept,
  // or an AL status code (e.g. 0x0070 module list mismatch) to refuse: the ESC then sets the
  // error flag and that code. Called on the ESC's thread.
  virtual uint16_t on_state_request(AlState from, AlState to) = 0;
  // The state changed (accepted request, error fallback such as SM watchdog, or INIT reset).
  virtual void on_state_changed(AlState from, AlState to) = 0;

  virtual ProcessDataSizes process_data_sizes() const = 0;

  // A complete mailbox request written by the master into SM0 (mailbox header included,
  // ETG.1000.4 §5.5 / ETG.1000.6 §5.2). Write at most reply.size() bytes of reply (header
  // included) and return its length, or 0 for no reply.
  virtual size_t on_mailbox(std::span<const uint8_t> request, std::span<uint8_t> reply) = 0;
  // Unsolicited mailbox messages (CoE Emergency): called when SM1 is free; same contract.
  virtual size_t poll_mailbox(std::span<uint8_t> /*reply*/) { return 0; }

  // Process data. update_inputs fills the SM3 buffer before a frame that reads it;
  // on_outputs delivers a complete, consistent SM2 buffer after the master wrote it.
  // Both run on the cyclic path: no allocation, no blocking.
  virtual void update_inputs(std::span<uint8_t> inputs) = 0;
  virtual void on_outputs(std::span<const uint8_t> outputs) = 0;

  // SYNC0/SYNC1 events from the distributed-clock unit (ETG.1000.4 §6.8.3).
  virtual void on_sync(int /*which*/, uint64_t /*system_time_ns*/) {}

  // The process-data watchdog expired (ESM falls to SAFEOP with 0x001B): outputs to safe state.
  virtual void on_watchdog_expired() {}
};

}  // namespace rackcat::ecat
