// Generic ESI device: SII from the ESI (ETG.2010), CoE via coe::SdoServer (ETG.1000.6 §5.6),
// process data per the PDO assignment (ETG.1000.6 §5.6.7.4).
#include "device/generic_device.hpp"

#include <array>

#include "base/little_endian.hpp"
#include "device/pdo_checks.hpp"
#include "ecat/slave/mailbox_server.hpp"

#include "esi/describe_dictionary.hpp"
#include "esi/sii_image.hpp"

namespace rackcat::device {

void copy_bits(std::span<const uint8_t> src, size_t src_bit, std::span<uint8_t> dst, size_t dst_bit,
               size_t bits) {
  for (size_t i = 0; i < bits; ++i) {
    const size_t s = src_bit + i, d = dst_bit + i;
    if (s / 8 >= src.size() || d / 8 >= dst.size()) return;
    const bool v = (src[s / 8] >> (s % 8)) & 1;
    if (v)
      dst[d / 8] = static_cast<uint8_t>(dst[d / 8] | (1u << (d % 8)));
    else
      dst[d / 8] = static_cast<uint8_t>(dst[d / 8] & ~(1u << (d % 8)));
  }
}

namespace {
uint16_t assigned_bytes(const std::vector<esi::PdoDescription>& pdos) {
  std::vector<esi::PdoDescription> on;
  for (const auto& p : pdos)
    if (p.assigned) on.push_back(p);
  return esi::pdo_bytes(on);
}
}  // namespace

GenericDevice::GenericDevice(EsiDevice esi) : esi_(std::move(esi)) {
  sii_ = esi::encode_sii(esi_.description).bytes;
  if (esi_.has_coe) {
    install_pdo_checks(esi_.dictionary, esi_.description);
    sdo_ = std::make_unique<coe::SdoServer>(esi_.dictionary);
    image_ = std::make_unique<coe::ProcessImage>(esi_.dictionary);
    image_->compile();
    sizes_ = {static_cast<uint16_t>(image_->output_bytes()),
              static_cast<uint16_t>(image_->input_bytes())};
  } else {
    sizes_ = {assigned_bytes(esi_.description.rx_pdos), assigned_bytes(esi_.description.tx_pdos)};
  }
  outputs_.assign(sizes_.outputs, 0);
  inputs_.assign(sizes_.inputs, 0);
}

ecat::ProcessDataSizes GenericDevice::process_data_sizes() const {
  return sizes_;
}

std::vector<uint8_t> GenericDevice::outputs() const {
  std::lock_guard lock(mutex_);
  return outputs_;
}

std::vector<uint8_t> GenericDevice::inputs() const {
  std::lock_guard lock(mutex_);
  return inputs_;
}

void GenericDevice::set_input_bits(size_t bit, size_t bits, std::span<const uint8_t> source,
                                   size_t source_bit) {
  std::lock_guard lock(mutex_);
  copy_bits(source, source_bit, inputs_, bit, bits);
}

void GenericDevice::add_wire(const GenericDevice& source, size_t from_bit, size_t to_bit,
                             size_t bits) {
  wires_.push_back({&source, from_bit, to_bit, bits});
}

void GenericDevice::add_input_driver(size_t to_bit, size_t bits, std::function<uint64_t()> code) {
  drivers_.push_back({to_bit, std::min<size_t>(bits, 64), std::move(code)});
}

uint16_t GenericDevice::on_state_request(EsmState from, EsmState to) {
  if (image_ && from == EsmState::PreOp && to == EsmState::SafeOp) {
    // The assignment may have changed in PREOP: recompile (ETG.1000.6 Table 11 0x001D/0x001E
    // are the ESC's SM checks against process_data_sizes()).
    if (image_->compile() != coe::AbortCode::None) return 0x0024;  // invalid input mapping
    std::lock_guard lock(mutex_);
    sizes_ = {static_cast<uint16_t>(image_->output_bytes()),
              static_cast<uint16_t>(image_->input_bytes())};
    outputs_.assign(sizes_.outputs, 0);
    inputs_.resize(sizes_.inputs, 0);
  }
  return 0;
}

void GenericDevice::on_state_changed(EsmState, EsmState to) {
  state_ = to;
  if (to == EsmState::Init && sdo_) sdo_->reset();
  if (to == EsmState::Init && foe_) foe_->reset();
}

void GenericDevice::serve_foe(foe::FileBackend& files, foe::FoeLimits limits) {
  if (esi_.description.foe) foe_ = std::make_unique<foe::FoeServer>(files, limits);
}

void GenericDevice::add_mailbox_protocols(ecat::MailboxServer& server) {
  if (sdo_) server.add(mailbox::Type::CoE, coe_mailbox_);
  if (foe_)
    server.add(mailbox::Type::FoE, foe_mailbox_,
               ecat::MailboxServer::kMailboxStates | ecat::MailboxServer::kBoot);
}

mailbox::Answer GenericDevice::FoeMailbox::on_request(const ecat::MailboxRequest& request,
                                                      std::span<uint8_t> reply) {
  // The FoE part of the mailbox data (ETG.1000.6 §5.8); the firmware frames the reply.
  return device.foe_->handle_mailbox(request.data, request.capacity, reply);
}

size_t GenericDevice::FoeMailbox::poll(std::span<uint8_t> reply) {
  // Timeouts, a commit's end, and a read request's deferred first Data (foe_files.hpp).
  return device.foe_->poll(reply);
}

mailbox::Answer GenericDevice::CoeMailbox::on_request(const ecat::MailboxRequest& request,
                                                      std::span<uint8_t> reply) {
  if (!device.sdo_) return {};
  return device.sdo_->handle(request.data, reply, request.state);
}

size_t GenericDevice::CoeMailbox::poll(std::span<uint8_t> reply) {
  return device.sdo_ ? device.sdo_->poll(reply) : 0;
}

bool GenericDevice::update_inputs(std::span<uint8_t> inputs) {
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return true;  // the control side is writing: keep last cycle's inputs
  for (const auto& w : wires_) {
    std::unique_lock source(w.source->mutex_, std::try_to_lock);
    if (source.owns_lock()) copy_bits(w.source->outputs_, w.from_bit, inputs_, w.to_bit, w.bits);
  }
  for (const auto& d : drivers_) {
    std::array<uint8_t, 8> code{};
    le::put64(code.data(), d.code());
    copy_bits(code, 0, inputs_, d.to_bit, d.bits);
  }
  if (image_) {
    // Inputs set from outside land in the mapped objects, which the master reads via SM3.
    for (const auto& c : image_->input_copies()) {
      copy_bits(inputs_, c.pd_bit, std::span<uint8_t>(c.image, (c.image_bit + c.bits + 7) / 8),
                c.image_bit, c.bits);
    }
    image_->read_inputs(inputs);
  } else {
    const size_t n = std::min(inputs.size(), inputs_.size());
    std::copy_n(inputs_.begin(), n, inputs.begin());
  }
  return true;
}

void GenericDevice::on_outputs(std::span<const uint8_t> outputs) {
  if (image_) image_->write_outputs(outputs);
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  const size_t n = std::min(outputs.size(), outputs_.size());
  std::copy_n(outputs.begin(), n, outputs_.begin());
}

void GenericDevice::on_watchdog_expired() {
  // Outputs fall to their safe state, zero (ETG.1000.6 §5.3.2 SM watchdog).
  std::lock_guard lock(mutex_);
  std::fill(outputs_.begin(), outputs_.end(), 0);
}

}  // namespace rackcat::device
