// The firmware's reports in the process's event log (base/event_log.hpp): ESM transitions,
// AL status codes set (refusals, local errors, fallbacks; ETG.1000.6 §5.3, Table 11),
// process-data watchdog expiries (ETG.1000.4 §6.5.3) and mailbox error replies (ETG.1000.6
// §5.2.3). Each report is one push into the preallocated queue (nothing when the log is off),
// so it is safe inside a transition; apps/event_logger formats them on its own thread.
#pragma once

#include <cstdint>

#include "base/event_log.hpp"
#include "ecat/registers.hpp"
#include "ecat/slave/esm_observer.hpp"
#include "ecat/slave/firmware.hpp"

namespace rackcat::ecat {

class EsmEventLog final : public EsmObserver {
 public:
  // Reports what `firmware` does (it must outlive the log; install with
  // firmware.set_observer(&log)). The station address 0x0010 says which slave reports; the
  // firmware reads it through its PDI (a read without side effects).
  explicit EsmEventLog(Firmware& firmware) : firmware_(firmware) {}

  void on_transition(EsmState from, EsmState to) override {
    if (!base::event_log().enabled()) return;
    base::log_event({.kind = base::EventKind::EsmTransition,
                     .a = static_cast<uint8_t>(from),
                     .b = static_cast<uint8_t>(to),
                     .c = firmware_.al_control(),
                     .code = firmware_.status_code(),
                     .station = station()});
  }
  void on_al_error(EsmState from, EsmState state, EsmState /*requested*/, uint8_t al_control,
                   uint16_t code) override {
    if (!base::event_log().enabled()) return;
    base::log_event({.kind = base::EventKind::EsmError,
                     .a = static_cast<uint8_t>(from),
                     .b = static_cast<uint8_t>(state),
                     .c = al_control,
                     .code = code,
                     .station = station()});
  }
  void on_watchdog_expired(EsmState state, uint8_t counter) override {
    if (!base::event_log().enabled()) return;
    base::log_event({.kind = base::EventKind::WatchdogExpired,
                     .a = static_cast<uint8_t>(state),
                     .station = station(),
                     .value = counter});
  }
  void on_mailbox_error(uint16_t detail) override {
    if (!base::event_log().enabled()) return;
    base::log_event({.kind = base::EventKind::MailboxError, .code = detail, .station = station()});
  }

 private:
  uint16_t station() { return firmware_.pdi().read16(reg::kStationAddress); }
  Firmware& firmware_;
};

}  // namespace rackcat::ecat
