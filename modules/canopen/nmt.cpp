#include "modules/canopen/nmt.hpp"

namespace rackcat::modules::canopen {

CanFrame nmt_frame(NmtCommand command, uint8_t node) {
  const uint8_t bytes[2] = {static_cast<uint8_t>(command), node};
  return CanFrame::make(cob::kNmt, bytes);
}

CanFrame heartbeat_frame(uint8_t node, NmtState state) {
  const uint8_t byte = static_cast<uint8_t>(state);
  return CanFrame::make(cob::kHeartbeat + node, {&byte, 1});
}

CanFrame NmtSlave::boot() {
  state_ = NmtState::PreOperational;
  return heartbeat_frame(node_, NmtState::BootUp);
}

NmtSlave::Reset NmtSlave::on_frame(const CanFrame& frame) {
  // CiA 301 §7.2.8.3.1: exactly two data bytes; node-ID 0 addresses every node.
  if (frame.id != cob::kNmt || frame.len != 2) {
    return Reset::None;
  }
  if (frame.data[1] != 0 && frame.data[1] != node_) {
    return Reset::None;
  }
  switch (static_cast<NmtCommand>(frame.data[0])) {
    case NmtCommand::Start:
      state_ = NmtState::Operational;
      return Reset::None;
    case NmtCommand::Stop:
      state_ = NmtState::Stopped;
      return Reset::None;
    case NmtCommand::EnterPreOperational:
      state_ = NmtState::PreOperational;
      return Reset::None;
    case NmtCommand::ResetNode:
      state_ = NmtState::BootUp;
      return Reset::Node;
    case NmtCommand::ResetCommunication:
      state_ = NmtState::BootUp;
      return Reset::Communication;
  }
  return Reset::None;  // an unknown command specifier changes nothing
}

bool HeartbeatProducer::poll(Micros now, uint8_t node, NmtState state, CanFrame& out) {
  if (period_ <= 0 || now < next_) {
    return false;
  }
  // Keep the grid: a late call does not shift every following heartbeat.
  next_ += period_;
  if (next_ <= now) {
    next_ = now + period_;
  }
  out = heartbeat_frame(node, state);
  return true;
}

void HeartbeatConsumer::watch(uint8_t node, Micros timeout_us) {
  nodes_[node] = Node{timeout_us};
}

HeartbeatConsumer::Event HeartbeatConsumer::on_frame(const CanFrame& frame, Micros now) {
  if (cob::function(frame.id) != cob::kHeartbeat || frame.len < 1) {
    return Event::None;
  }
  auto it = nodes_.find(cob::node(frame.id));
  if (it == nodes_.end()) {
    return Event::None;
  }
  Node& n = it->second;
  const auto state = static_cast<NmtState>(frame.data[0] & 0x7F);
  const bool was_alive = n.alive;
  const NmtState before = n.state;
  n.alive = true;
  n.last_seen = now;
  if (state == NmtState::BootUp) {
    n.booted = true;
    n.state = NmtState::PreOperational;  // the node enters PRE-OPERATIONAL after boot-up
    return Event::BootUp;
  }
  n.booted = false;
  n.state = state;
  return (!was_alive || before != state) ? Event::StateChanged : Event::None;
}

std::optional<uint8_t> HeartbeatConsumer::poll_lost(Micros now) {
  for (auto& [id, n] : nodes_) {
    if (n.alive && n.timeout > 0 && now - n.last_seen > n.timeout) {
      n.alive = false;
      return id;
    }
  }
  return std::nullopt;
}

const HeartbeatConsumer::Node* HeartbeatConsumer::node(uint8_t id) const {
  auto it = nodes_.find(id);
  return it == nodes_.end() ? nullptr : &it->second;
}

}  // namespace rackcat::modules::canopen
