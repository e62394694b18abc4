// Hears what the firmware does, for logging and diagnostics: every state change and every AL
// status code the ESM sets (ETG.1000.6 §5.3, Table 11), process-data watchdog expiries
// (ETG.1000.4 §6.5.3) and the mailbox error replies the mailbox server sends (ETG.1000.6
// §5.2.3). Called on the firmware's thread, inside
// the transition: an observer must not allocate, block or format; it copies the few values
// it needs (e.g. into a lock-free ring) and returns.
#pragma once

#include <cstdint>

#include "base/esm_state.hpp"

namespace rackcat::ecat {

class EsmObserver {
 public:
  virtual ~EsmObserver() = default;
  // The state changed (requested transition, error fallback, local error or restart).
  virtual void on_transition(EsmState /*from*/, EsmState /*to*/) {}
  // The ESM set the error flag with `code` (0x0134): a refused request (`state` is the state
  // it stays in, `requested` the state asked for) or a local error / fallback (`requested` ==
  // `state`, the state it is in after falling from `from`). `al_control` is the master's last
  // AL control byte (0x0120) as the firmware read it.
  virtual void on_al_error(EsmState /*from*/, EsmState /*state*/, EsmState /*requested*/,
                           uint8_t /*al_control*/, uint16_t /*code*/) {}
  // The master acknowledged the error flag (or requested INIT): the code is back to 0.
  virtual void on_error_cleared(EsmState /*state*/) {}
  // The chip reported an expired process-data watchdog (0x0440 bit 0 low) in `state`;
  // `counter` is the chip's expiry counter 0x0442.
  virtual void on_watchdog_expired(EsmState /*state*/, uint8_t /*counter*/) {}
  // The mailbox server answered a request with a mailbox error reply (`detail`, ETG.1000.6
  // §5.2.3 Table 29: 0x0002 unsupported protocol, 0x0008 invalid size, ...).
  virtual void on_mailbox_error(uint16_t /*detail*/) {}
};

}  // namespace rackcat::ecat
