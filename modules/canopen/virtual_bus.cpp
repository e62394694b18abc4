#include "modules/canopen/virtual_bus.hpp"

namespace rackcat::modules::canopen {

VirtualCanBus::Endpoint& VirtualCanBus::attach() {
  endpoints_.push_back(std::make_unique<Endpoint>(*this));
  return *endpoints_.back();
}

bool VirtualCanBus::Endpoint::send(const CanFrame& frame) {
  if (!connected_ || status_.bus_off) {
    ++status_.tx_dropped;
    return false;
  }
  ++status_.tx_frames;
  bus_.log_.push_back(frame);
  for (auto& e : bus_.endpoints_) {
    if (e.get() != this && e->connected_) {
      e->rx_.push_back(frame);
    }
  }
  return true;
}

bool VirtualCanBus::Endpoint::receive(CanFrame& frame) {
  if (rx_.empty()) {
    return false;
  }
  frame = rx_.front();
  rx_.pop_front();
  ++status_.rx_frames;
  return true;
}

void VirtualCanBus::Endpoint::set_error_state(bool bus_off, bool error_passive) {
  if (bus_off != status_.bus_off || error_passive != status_.error_passive) {
    ++status_.error_frames;
  }
  status_.bus_off = bus_off;
  status_.error_passive = error_passive;
}

}  // namespace rackcat::modules::canopen
