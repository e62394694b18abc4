// An in-process CAN bus for unit tests: every endpoint is one node's controller; a frame
// sent on one endpoint is queued at every other endpoint at once (a node does not receive its
// own frames, as SocketCAN without CAN_RAW_RECV_OWN_MSGS). Time is whatever the test passes
// to the nodes, so runs are deterministic. Single-threaded.
#pragma once

#include <deque>
#include <memory>
#include <vector>

#include "modules/canopen/bus.hpp"

namespace rackcat::modules::canopen {

class VirtualCanBus {
 public:
  class Endpoint final : public CanBus {
   public:
    explicit Endpoint(VirtualCanBus& bus) : bus_(bus) {}
    bool send(const CanFrame& frame) override;
    bool receive(CanFrame& frame) override;
    void wait(Micros) override {}
    const BusStatus& status() const override { return status_; }
    // Fault injection: the controller's error state (as SocketCAN reports it).
    void set_error_state(bool bus_off, bool error_passive);
    // Unplugged: frames neither leave nor arrive.
    void set_connected(bool connected) { connected_ = connected; }

   private:
    friend class VirtualCanBus;
    VirtualCanBus& bus_;
    std::deque<CanFrame> rx_;
    BusStatus status_;
    bool connected_ = true;
  };

  // The endpoint lives as long as the bus.
  Endpoint& attach();
  // Every frame sent so far, in order (what candump would show).
  const std::vector<CanFrame>& log() const { return log_; }

 private:
  std::vector<std::unique_ptr<Endpoint>> endpoints_;
  std::vector<CanFrame> log_;
};

}  // namespace rackcat::modules::canopen
