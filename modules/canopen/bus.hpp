// The transport under the RIM link: one CAN controller as seen by one node. Two
// implementations: VirtualCanBus (in-process, deterministic, canopen_virtual_bus.hpp) and
// SocketCanBus (PF_CAN raw sockets on any Linux CAN interface, canopen_socketcan.hpp).
#pragma once

#include <cstdint>

#include "modules/canopen/frame.hpp"

namespace rackcat::modules::canopen {

// What the controller reports besides frames (SocketCAN error frames, linux/can/error.h).
struct BusStatus {
  uint64_t rx_frames = 0;
  uint64_t tx_frames = 0;
  uint64_t tx_dropped = 0;     // the send queue was full (no ACK, controller stopped)
  uint64_t error_frames = 0;   // every error frame read
  bool bus_off = false;        // the controller left the bus (TEC > 255)
  bool error_passive = false;  // TEC or REC above 127
};

class CanBus {
 public:
  virtual ~CanBus() = default;
  // Queues one frame; false when the controller cannot take it (counted in tx_dropped).
  virtual bool send(const CanFrame& frame) = 0;
  // The next received data frame, without blocking; error frames are consumed and counted
  // on the way. False when nothing is pending.
  virtual bool receive(CanFrame& frame) = 0;
  // Blocks up to timeout_us for a frame to arrive (the virtual bus returns at once).
  virtual void wait(Micros timeout_us) = 0;
  virtual const BusStatus& status() const = 0;
};

}  // namespace rackcat::modules::canopen
