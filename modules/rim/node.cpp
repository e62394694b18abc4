#include "modules/rim/node.hpp"

#include "modules/canopen/emcy.hpp"

namespace rackcat::modules::canopen {

RimNode::RimNode(const mdp::RackConfig& rack, uint8_t rim, CanBus& bus, RimNodeOptions options)
    : profile_(rim_profile(rack, rim)),
      bus_(bus),
      options_(options),
      od_(rim_dictionary(profile_, static_cast<uint16_t>(options.heartbeat_period_us / 1000),
                         static_cast<uint16_t>(options.control_module_timeout_us / 1000))),
      sdo_(od_),
      can_sdo_(sdo_, rim),
      nmt_(rim),
      heartbeat_(options.heartbeat_period_us),
      outputs_(profile_.outputs.size(), 0.0),
      tx_(profile_.tpdo_count() * kPdoBytes, 0),
      rx_(profile_.rpdo_count() * kPdoBytes, 0) {
  for (size_t i = 0; i < profile_.inputs.size(); ++i) {
    sources_.push_back(std::make_unique<ConstantSource>(0.0));
  }
  if (options.control_module_timeout_us > 0) {
    control_module_.watch(kControlModuleNode, options.control_module_timeout_us);
  }
  // 0x1017 written over SDO changes the producer period at once (CiA 301 §7.5.2.32).
  od_.find(0x1017)->edit_hooks().after_write = [this](coe::Object& o, int) {
    heartbeat_.set_period(static_cast<Micros>(o.get_u(0)) * 1000);
  };
}

void RimNode::start(Micros now) {
  t0_ = now;
  boot(now);
}

void RimNode::boot(Micros now) {
  sdo_.reset();
  de_energise();
  bus_.send(nmt_.boot());
  heartbeat_.restart(now);
  next_pdo_ = now;
}

void RimNode::de_energise() {
  std::fill(outputs_.begin(), outputs_.end(), 0.0);
  std::fill(rx_.begin(), rx_.end(), 0);
  stream_to_objects(od_, profile_, false, rx_);
}

void RimNode::step(Micros now) {
  CanFrame f;
  while (bus_.receive(f)) {
    control_module_.on_frame(f, now);
    handle(f, now);
  }
  if (control_module_.poll_lost(now)) {
    // The control module is gone: outputs to the de-energised level (CiA 301 0x1029:01 = 0:
    // OPERATIONAL -> PRE-OPERATIONAL) and tell the bus why.
    ++counters_.control_module_losses;
    if (nmt_.state() == NmtState::Operational) {
      nmt_.on_frame(nmt_frame(NmtCommand::EnterPreOperational, profile_.rim));
    }
    de_energise();
    pending_emcy_.push_back({0x8130, 0x11, {kControlModuleNode, 0, 0, 0, 0}});
  }
  for (const coe::Emergency& e : pending_emcy_) {
    if (bus_.send(emcy_frame(profile_.rim, e))) {
      ++counters_.emergencies_sent;
    }
  }
  pending_emcy_.clear();
  if (heartbeat_.poll(now, profile_.rim, nmt_.state(), f)) {
    bus_.send(f);
  }
  if (nmt_.state() == NmtState::Operational && now >= next_pdo_) {
    send_tpdos(now);
    next_pdo_ += options_.pdo_period_us;
    if (next_pdo_ <= now) {
      next_pdo_ = now + options_.pdo_period_us;
    }
  }
}

void RimNode::handle(const CanFrame& f, Micros now) {
  if (f.id == cob::kNmt) {
    const NmtState before = nmt_.state();
    switch (nmt_.on_frame(f)) {
      case NmtSlave::Reset::Node:
      case NmtSlave::Reset::Communication:
        ++counters_.resets;
        boot(now);
        return;
      case NmtSlave::Reset::None:
        break;
    }
    if (before == NmtState::Operational && nmt_.state() != NmtState::Operational) {
      de_energise();
    }
    if (nmt_.state() == NmtState::Operational && before != NmtState::Operational) {
      next_pdo_ = now;  // first TPDOs at once
    }
    return;
  }
  // SDO: available in PRE-OPERATIONAL and OPERATIONAL, not in STOPPED (CiA 301 Table 56).
  if (nmt_.state() != NmtState::Stopped) {
    CanFrame reply;
    bool has_reply = false;
    const EsmState access = nmt_.state() == NmtState::Operational ? EsmState::Op : EsmState::PreOp;
    if (can_sdo_.handle(f, access, reply, has_reply)) {
      ++counters_.sdo_requests;
      if (has_reply) {
        bus_.send(reply);
      }
      return;
    }
  }
  if (nmt_.state() != NmtState::Operational) {
    return;  // PDOs only in OPERATIONAL
  }
  const int k = pdo_number(false, f.id, profile_.rim);
  if (k < 0 || static_cast<size_t>(k) >= profile_.rpdo_count()) {
    return;
  }
  const size_t at = static_cast<size_t>(k) * kPdoBytes;
  const size_t n = std::min<size_t>(f.len, profile_.rx_bytes - at);
  std::copy_n(f.data.begin(), n, rx_.begin() + static_cast<ptrdiff_t>(at));
  ++counters_.rpdos_received;
  for (size_t i = 0; i < profile_.outputs.size(); ++i) {
    const RimChannel& c = profile_.outputs[i];
    if (c.offset >= at && c.offset < at + n) {
      outputs_[i] = get_channel(rx_, c);
    }
  }
  stream_to_objects(od_, profile_, false, rx_);
}

void RimNode::send_tpdos(Micros now) {
  const double t = static_cast<double>(now - t0_) * 1e-6;
  for (size_t i = 0; i < profile_.inputs.size(); ++i) {
    put_channel(tx_, profile_.inputs[i], sources_[i]->sample(t));
  }
  stream_to_objects(od_, profile_, true, tx_);
  for (size_t k = 0; k < profile_.tpdo_count(); ++k) {
    const size_t at = k * kPdoBytes;
    const size_t n = std::min(kPdoBytes, profile_.tx_bytes - at);
    if (bus_.send(
            CanFrame::make(pdo_cob_id(true, k, profile_.rim), std::span(tx_).subspan(at, n)))) {
      ++counters_.tpdos_sent;
    }
  }
}

bool RimNode::set_source(uint8_t slot, uint8_t channel, std::unique_ptr<Source> source) {
  for (size_t i = 0; i < profile_.inputs.size(); ++i) {
    if (profile_.inputs[i].slot == slot && profile_.inputs[i].channel == channel) {
      sources_[i] = std::move(source);
      return true;
    }
  }
  return false;
}

const double* RimNode::output_ptr(uint8_t slot, uint8_t channel) const {
  for (size_t i = 0; i < profile_.outputs.size(); ++i) {
    if (profile_.outputs[i].slot == slot && profile_.outputs[i].channel == channel) {
      return &outputs_[i];
    }
  }
  return nullptr;
}

double RimNode::output(uint8_t slot, uint8_t channel) const {
  const double* p = output_ptr(slot, channel);
  return p ? *p : 0.0;
}

}  // namespace rackcat::modules::canopen
