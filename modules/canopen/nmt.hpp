// CANopen network management (CiA 301 §7.3.2): the NMT slave state machine of a node, the
// NMT command frame, and heartbeat (CiA 301 §7.2.8.3.2.2: COB-ID 0x700 + node-ID, one byte
// = NMT state; the boot-up message is the same COB-ID with state 0x00).
#pragma once

#include <cstdint>
#include <map>
#include <optional>

#include "modules/canopen/frame.hpp"

namespace rackcat::modules::canopen {

// Heartbeat state byte values (CiA 301 Table 53).
enum class NmtState : uint8_t {
  BootUp = 0x00,  // Initialisation: only ever seen in the boot-up message
  Stopped = 0x04,
  Operational = 0x05,
  PreOperational = 0x7F,
};

// NMT command specifiers (CiA 301 §7.2.8.3.1, Table 52).
enum class NmtCommand : uint8_t {
  Start = 0x01,
  Stop = 0x02,
  EnterPreOperational = 0x80,
  ResetNode = 0x81,
  ResetCommunication = 0x82,
};

// NMT command frame: COB-ID 0, data = command, node-ID (0 = all nodes).
CanFrame nmt_frame(NmtCommand command, uint8_t node);
CanFrame heartbeat_frame(uint8_t node, NmtState state);

// The NMT slave of one node. After power-on or a reset the node sends its boot-up message
// and enters PRE-OPERATIONAL by itself (CiA 301 Figure 48).
class NmtSlave {
 public:
  enum class Reset : uint8_t { None, Node, Communication };

  explicit NmtSlave(uint8_t node_id) : node_(node_id) {}

  // Initialisation finished: returns the boot-up message; the state is PRE-OPERATIONAL.
  CanFrame boot();
  // An NMT frame (COB-ID 0) addressed to this node or to all; other frames are ignored.
  // Returns the reset the application must perform (then call boot() again).
  Reset on_frame(const CanFrame& frame);
  NmtState state() const { return state_; }
  uint8_t node_id() const { return node_; }

 private:
  uint8_t node_;
  NmtState state_ = NmtState::BootUp;
};

// Heartbeat producer (0x1017: producer heartbeat time in ms, 0 = off).
class HeartbeatProducer {
 public:
  explicit HeartbeatProducer(Micros period_us) : period_(period_us) {}
  void set_period(Micros period_us) { period_ = period_us; }
  Micros period() const { return period_; }
  // Restart the period (after boot-up the first heartbeat follows one period later).
  void restart(Micros now) { next_ = now + period_; }
  // True (and the frame in `out`) when a heartbeat is due at `now`.
  bool poll(Micros now, uint8_t node, NmtState state, CanFrame& out);

 private:
  Micros period_;
  Micros next_ = 0;
};

// Heartbeat consumer (0x1016 semantics): watches the heartbeats of a set of nodes; a node
// whose heartbeat does not come within its consumer time is lost ("heartbeat event").
class HeartbeatConsumer {
 public:
  struct Node {
    Micros timeout = 0;
    bool alive = false;   // a heartbeat or boot-up came within the timeout
    bool booted = false;  // the last message was a boot-up (the node reset)
    NmtState state = NmtState::BootUp;
    Micros last_seen = 0;
  };
  enum class Event : uint8_t { None, BootUp, StateChanged };

  void watch(uint8_t node, Micros timeout_us);
  // A frame from the bus; returns what it means for the node it came from (None for frames
  // that are not heartbeats of a watched node).
  Event on_frame(const CanFrame& frame, Micros now);
  // Nodes whose timeout expired since the last call go to alive = false; returns the first
  // such node, or nullopt. Call until nullopt.
  std::optional<uint8_t> poll_lost(Micros now);
  const Node* node(uint8_t id) const;

 private:
  std::map<uint8_t, Node> nodes_;
};

}  // namespace rackcat::modules::canopen
