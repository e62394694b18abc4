// The control module's side of the RIM link: for each RIM of the rack file it consumes the
// heartbeat, checks identity (0x1018:01/02) and card list (0x2001) over SDO against the rack
// file, starts the node (NMT Start), takes its TPDOs as input values and sends its outputs in
// RPDOs, and maps all of it to the RIM communication state of 0x2rr1:08 (guide Table 16):
//   ONLINE     heartbeat, OPERATIONAL, identity and card list match the rack file
//   CONNECTED  heartbeat, but PRE-OPERATIONAL/STOPPED, or identity/card list do not match
//              (a RIM on the wrong node-ID or one that is not configured)
//   OFFLINE    no heartbeat within the consumer time (communication error)
//   ERROR      the controller is bus-off or error-passive, `max_sdo_failures` SDO timeouts
//              in a row, or the RIM reported a CAN communication EMCY (0x81xx) that no
//              error-reset EMCY (0x0000) has cleared yet
// Every change is reported through the state callback (modules::Rack::set_rim_state when
// attached to a rack, canopen_rack_link.hpp). Drive it from one thread with step(now).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "coe/emergency_queue.hpp"
#include "modules/canopen/bus.hpp"
#include "modules/canopen/nmt.hpp"
#include "modules/canopen/sdo_client.hpp"
#include "modules/rack/events.hpp"
#include "modules/rim/profile.hpp"

namespace rackcat::modules::canopen {

struct RimMasterOptions {
  Micros heartbeat_timeout_us = 150'000;  // consumer time: 3 producer periods of 50 ms
  Micros sdo_timeout_us = 100'000;
  Micros sdo_retry_us = 200'000;  // pause before checking a RIM again after a failure
  int max_sdo_failures = 3;
  Micros pdo_period_us = 1'000;  // RPDO cycle to ONLINE RIMs
  // The control module's own heartbeat (node-ID kControlModuleNode), which the RIMs consume.
  Micros heartbeat_period_us = 50'000;
};

using RimStateFn = std::function<void(uint8_t rim, RimState state, bool comm_error)>;
using RimEmergencyFn = std::function<void(uint8_t rim, const coe::Emergency& e)>;

class RimMaster {
 public:
  // Watches `rims` (empty: every RIM of the rack file). Throws std::invalid_argument for a
  // RIM the rack file lacks.
  RimMaster(const mdp::RackConfig& rack, CanBus& bus, RimMasterOptions options = {},
            std::vector<uint8_t> rims = {});

  void on_state(RimStateFn fn) { on_state_ = std::move(fn); }
  void on_emergency(RimEmergencyFn fn) { on_emergency_ = std::move(fn); }

  // Handles pending frames, timeouts, the SDO checks, and sends RPDOs that are due.
  void step(Micros now);

  RimState state(uint8_t rim) const;
  // Why the RIM is not ONLINE, for logs ("identity mismatch: product code 0x...").
  const std::string& reason(uint8_t rim) const;
  // Last received value of an input channel (0 before the first TPDO); nullptr if unknown.
  // The address is stable: modules::Rack reads it through a RemoteInputSource.
  const double* input_ptr(uint8_t rim, uint8_t slot, uint8_t channel) const;
  // The output channel's value is read from `value` at every RPDO (nullptr unbinds: 0).
  bool bind_output(uint8_t rim, uint8_t slot, uint8_t channel, const double* value);
  // Time of the last TPDO from the RIM (-1 before the first).
  Micros last_input_time(uint8_t rim) const;
  const RimProfile* profile(uint8_t rim) const;
  std::vector<uint8_t> rims() const;

 private:
  enum class Phase : uint8_t { Absent, Checking, Verified, Mismatch, Failed };
  struct Link {
    RimProfile profile;
    std::unique_ptr<SdoClient> sdo;
    Phase phase = Phase::Absent;
    size_t check_step = 0;
    int sdo_failures = 0;
    Micros retry_at = 0;
    bool comm_emcy = false;
    bool lost = false;  // the heartbeat stopped (OFFLINE through a communication error)
    RimState state = RimState::Offline;
    bool comm_error = false;
    std::string reason = "no heartbeat yet";
    std::vector<double> inputs;
    std::vector<const double*> outputs;
    std::vector<uint8_t> tx, rx;  // the RIM's transmit / receive streams
    Micros last_input = -1;
    Micros next_rpdo = 0;
  };

  void handle(const CanFrame& f, Micros now);
  void start_check(Link& l, Micros now);
  void next_check(Link& l, Micros now);
  void check_done(Link& l, Micros now);
  void sdo_failed(Link& l, Micros now, bool timeout);
  void evaluate(Link& l);
  void send_rpdos(Link& l);
  Link* link(uint8_t rim);
  const Link* link(uint8_t rim) const;

  CanBus& bus_;
  RimMasterOptions options_;
  HeartbeatConsumer heartbeat_;
  HeartbeatProducer own_heartbeat_;
  std::map<uint8_t, Link> links_;
  RimStateFn on_state_;
  RimEmergencyFn on_emergency_;
};

}  // namespace rackcat::modules::canopen
