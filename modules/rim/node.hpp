// One RIM as a CANopen node (node-ID = RIM number): NMT slave, heartbeat producer, SDO server
// (coe/ through CanSdoServer) on the CiA 401 dictionary of canopen_rim_profile.hpp, TPDOs
// with its input channels every PDO period while OPERATIONAL, RPDOs driving its outputs, and
// EMCY. Outputs go to 0 (de-energised) whenever the node is not OPERATIONAL, as the rack's
// RIMs do when they lose the control module.
//
// Drive it from one thread: start(now) once, then step(now) as often as frames may arrive
// (at least once per PDO period).
#pragma once

#include <memory>
#include <vector>

#include "coe/sdo_server.hpp"
#include "modules/canopen/bus.hpp"
#include "modules/canopen/nmt.hpp"
#include "modules/canopen/sdo_server.hpp"
#include "modules/rim/profile.hpp"
#include "modules/signals/signal_source.hpp"

namespace rackcat::modules::canopen {

struct RimNodeOptions {
  Micros heartbeat_period_us = 50'000;  // 0x1017
  Micros pdo_period_us = 1'000;         // TPDO cycle while OPERATIONAL
  // 0x1016: the control module's heartbeat must come within this time once it has been seen,
  // or the RIM de-energises its outputs, enters PRE-OPERATIONAL (CiA 301 0x1029 default) and
  // sends EMCY 0x8130 (life guard / heartbeat error). 0 = not watched.
  Micros control_module_timeout_us = 500'000;
};

struct RimNodeCounters {
  uint64_t tpdos_sent = 0;
  uint64_t rpdos_received = 0;
  uint64_t sdo_requests = 0;
  uint64_t emergencies_sent = 0;
  uint64_t resets = 0;
  uint64_t control_module_losses = 0;
};

class RimNode {
 public:
  // Every input channel starts with a constant 0 source. Throws std::invalid_argument when
  // the rack has no such RIM.
  RimNode(const mdp::RackConfig& rack, uint8_t rim, CanBus& bus, RimNodeOptions options = {});

  // Power-on: boot-up message, PRE-OPERATIONAL.
  void start(Micros now);
  // Handles every pending frame, then sends the heartbeat and TPDOs that are due.
  void step(Micros now);

  // Replace an input channel's source (false: no such input channel).
  bool set_source(uint8_t slot, uint8_t channel, std::unique_ptr<Source> source);
  // The value an output channel drives now (0 when not OPERATIONAL or no data yet).
  double output(uint8_t slot, uint8_t channel) const;
  // Address of an output's value (stable), for loopback sources; nullptr when unknown.
  const double* output_ptr(uint8_t slot, uint8_t channel) const;
  // Sends an emergency (CiA 301 §7.2.7) at the next step().
  void emergency(const coe::Emergency& e) { pending_emcy_.push_back(e); }

  NmtState state() const { return nmt_.state(); }
  const RimProfile& profile() const { return profile_; }
  coe::ObjectDictionary& dictionary() { return od_; }
  const RimNodeCounters& counters() const { return counters_; }

 private:
  void handle(const CanFrame& f, Micros now);
  void boot(Micros now);
  void de_energise();
  void send_tpdos(Micros now);

  RimProfile profile_;
  CanBus& bus_;
  RimNodeOptions options_;
  coe::ObjectDictionary od_;
  coe::SdoServer sdo_;
  CanSdoServer can_sdo_;
  NmtSlave nmt_;
  HeartbeatProducer heartbeat_;
  HeartbeatConsumer control_module_;
  std::vector<std::unique_ptr<Source>> sources_;  // parallel to profile_.inputs
  std::vector<double> outputs_;                   // parallel to profile_.outputs
  std::vector<uint8_t> tx_, rx_;
  std::vector<coe::Emergency> pending_emcy_;
  Micros next_pdo_ = 0;
  Micros t0_ = 0;
  RimNodeCounters counters_;
};

}  // namespace rackcat::modules::canopen
