// The event status bits and the exception tree of guide section 3, computed from the causes
// the rack reports (RIM states, fans, wiring faults) and published into the dictionary:
//
//   0x2000:0A  device events (CPU fan), latched until 0xFBF1 while the cause is gone
//   0x2rr1:08  bits 1..0 active RIM state; bits 31..2 latched until 0xFBF1 (guide §3.3)
//   0xF382:n / 0xF384:n  module n's safe / unsafe wiring faults, bit = channel (active)
//   0xF386 / 0xF388      bit 0 device, bit rr RIM rr: warnings / errors present (active), an
//                        event counts when its bit is set in the event mask 0x2000:09 /
//                        0x2rr1:07 (1 = reported, like the 0xF3Ax masks)
//   0xF380  bit 1 manufacturer warning = any(0xF382:n & 0xF3A2:n) or (0xF386 & 0xF3A6),
//           bit 3 manufacturer error   = any(0xF384:n & 0xF3A4:n) or (0xF388 & 0xF3A8);
//           bits 0/2 (device warning/error) stay 0: 0xF381/0xF383 are not implemented (§3.4)
//   0xF39x  the latched counterparts: every bit that was active since the last 0xFBF1;
//           0xFBF1 clears those whose cause is gone.
//
// Each change of an active cause raises a CoE Emergency (events.hpp emcy::).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "modules/rack/events.hpp"

namespace rackcat::modules {

struct EmergencySink {
  // error code, error register, the 5 manufacturer bytes:
  // [0] RIM (0 = control module), [1] module number (0 = none), [2] event bit (0xFF = none),
  // [3..4] channel mask (little-endian).
  std::function<void(uint16_t, uint8_t, const uint8_t (&)[5])> raise;
};

class ExceptionTree {
 public:
  ExceptionTree(coe::ObjectDictionary& od, size_t modules, EmergencySink sink);

  // Causes (call on the device thread, then update()).
  void set_rim_state(uint8_t rim, RimState state, bool comm_error);
  void set_rim_events(uint8_t rim, uint32_t active_event_bits);  // fans, MCM (bits >= 8)
  void set_device_events(uint32_t active_bits);
  void set_module_faults(uint16_t module, uint32_t safe_bits, uint32_t unsafe_bits);

  // Recompute and publish; raises emergencies for changed causes.
  void update();
  // 0xFBF1: latched = what is still active; publishes.
  void reset_latched();

  RimState rim_state(uint8_t rim) const { return rims_[rim].state; }
  uint32_t rim_event_status(uint8_t rim) const;  // the 0x2rr1:08 value
  uint32_t device_event_status() const { return device_.latched | device_.active; }
  uint32_t summary(bool latched) const { return latched ? summary_latched_ : summary_active_; }
  uint32_t global_warnings(bool latched) const { return latched ? gw_latched_ : gw_active_; }
  uint32_t global_errors(bool latched) const { return latched ? ge_latched_ : ge_active_; }
  uint32_t module_warnings(uint16_t m, bool latched) const;
  uint32_t module_errors(uint16_t m, bool latched) const;

 private:
  struct Events {
    uint32_t active = 0;
    uint32_t latched = 0;
    uint32_t reported = 0;  // active bits already announced by emergency
  };
  struct Rim {
    RimState state = RimState::Online;
    bool comm_error = false;
    uint32_t other = 0;  // fan / MCM causes
    Events ev;
  };
  struct ModuleFaults {
    Events warn, err;
  };

  uint32_t rim_active(const Rim& r) const;
  uint32_t mask_of(uint16_t index, uint8_t sub) const;
  void publish();
  void announce();

  coe::ObjectDictionary& od_;
  EmergencySink sink_;
  Rim rims_[6];
  Events device_;
  std::vector<ModuleFaults> modules_;  // index = module number
  uint32_t gw_active_ = 0, ge_active_ = 0, gw_latched_ = 0, ge_latched_ = 0;
  uint32_t summary_active_ = 0, summary_latched_ = 0;
};

}  // namespace rackcat::modules
