#include "apps/rack_slave/rack_slave.hpp"

#include <algorithm>
#include <utility>

#include "apps/rack_slave/mailbox_events.hpp"
#include "ecat/slave/mailbox_server.hpp"
#include "esi/rack.hpp"

namespace rackcat::apps {
namespace {
mdp::RackConfig for_position(mdp::RackConfig config, int position) {
  config.control.serial += static_cast<uint32_t>(position);
  return config;
}
}  // namespace

RackSlave::RackSlave(mdp::RackConfig config, const std::string& state_dir, int position)
    : RackSlave(std::move(config), mdp::StateDirectory::open(state_dir), position) {}

RackSlave::RackSlave(mdp::RackConfig config, const std::shared_ptr<mdp::StateDirectory>& state_dir,
                     int position) {
  mdp::DeviceOptions options;
  options.state = position == 0 ? state_dir : state_dir->child("slave-" + std::to_string(position));
  device_.emplace(for_position(std::move(config), position), options);
  rack_ = std::make_unique<modules::Rack>(*device_);
  device_->add_listener(&reset_listener_, mdp::Device::ListenerScope::EventsOnly);
  sii_ = esi::build_sii(*device_).bytes;
}

RackSlave::~RackSlave() {
  device_->remove_listener(&reset_listener_);
  rack_.reset();  // detaches from the device before the device goes
}

void RackSlave::device_reset() {
  // Only marks the work: the SII image is rebuilt by finish_device_reset(), outside the frame.
  sii_stale_ = true;
  restart_pending_ = true;
}

void RackSlave::finish_device_reset() {
  if (!sii_stale_) return;
  sii_stale_ = false;
  // Rebuilt in place when the size is unchanged, so a view of the image stays valid.
  std::vector<uint8_t> image = esi::build_sii(*device_).bytes;
  if (image.size() == sii_.size()) {
    std::copy(image.begin(), image.end(), sii_.begin());
  } else {
    sii_ = std::move(image);
  }
}

uint16_t RackSlave::on_state_request(EsmState from, EsmState to) {
  if (const uint16_t code = device_->request_state(from, to)) return code;
  return rack_->check_state_request(from, to);
}

void RackSlave::on_state_changed(EsmState from, EsmState to) {
  device_->state_changed(from, to);
}

ecat::ProcessDataSizes RackSlave::process_data_sizes() const {
  return {device_->output_bytes(), device_->input_bytes()};
}

void RackSlave::add_mailbox_protocols(ecat::MailboxServer& server) {
  server.add(mailbox::Type::CoE, coe_mailbox_);
  server.add(mailbox::Type::FoE, foe_mailbox_,
             ecat::MailboxServer::kMailboxStates | ecat::MailboxServer::kBoot);
}

mailbox::Answer RackSlave::FoeMailbox::on_request(const ecat::MailboxRequest& request,
                                                  std::span<uint8_t> reply) {
  return slave.device_->foe_request(request.data, request.capacity, reply);
}

size_t RackSlave::FoeMailbox::poll(std::span<uint8_t> reply) {
  // Timeouts, a commit's end, and a parameters.bin read's deferred first Data (file_access.hpp).
  return slave.device_->foe_poll(reply);
}

mailbox::Answer RackSlave::CoeMailbox::on_request(const ecat::MailboxRequest& request,
                                                  std::span<uint8_t> reply) {
  const mailbox::Answer answer = slave.device_->coe_request(request.data, reply);
  log_coe_reply(reply.first(answer.length));
  return answer;
}

bool RackSlave::mailbox_pending() const {
  return restart_pending_ || device_->mailbox_pending();
}

size_t RackSlave::CoeMailbox::poll(std::span<uint8_t> reply) {
  RackSlave& self = slave;
  // SM1 is free: the master has read the answer to the reset command, so the restart no
  // longer swallows it.
  if (self.restart_pending_) {
    self.restart_pending_ = false;
    if (self.restart_) self.restart_();
    return 0;
  }
  const size_t n = self.device_->coe_poll(reply);
  log_coe_reply(reply.first(n));
  return n;
}

bool RackSlave::update_inputs(std::span<uint8_t> inputs) {
  return device_->read_inputs(inputs);
}

void RackSlave::on_outputs(std::span<const uint8_t> outputs) {
  device_->write_outputs(outputs);
}

void RackSlave::on_sync(int which, uint64_t system_time_ns) {
  device_->sync_event(which, system_time_ns);
}

void RackSlave::on_watchdog_expired() {
  device_->watchdog_expired();
}

}  // namespace rackcat::apps
