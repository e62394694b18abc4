// Mailbox hand-over on SM0/SM1 through the PDI, header checks, double writes, the counter,
// the repeat request and dispatch by type (ETG.1000.4 §5.6, §6.7.3; ETG.1000.6 §5.2).
#include "ecat/slave/mailbox_server.hpp"

#include <algorithm>
#include <cstring>

#include "base/little_endian.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

constexpr uint16_t kSm1 = reg::sm::base(1);

}  // namespace

bool MailboxServer::add(mailbox::Type mailbox_type, MailboxProtocol& protocol, uint8_t states) {
  const auto type = static_cast<uint8_t>(mailbox_type);
  for (size_t i = 0; i < protocol_count_; ++i) {
    if (protocols_[i].type == type) {
      protocols_[i] = {type, states, &protocol};
      return true;
    }
  }
  if (protocol_count_ == protocols_.size()) return false;
  protocols_[protocol_count_++] = {type, states, &protocol};
  return true;
}

uint8_t MailboxServer::state_bit(EsmState s) {
  switch (s) {
    case EsmState::PreOp:
      return kPreOp;
    case EsmState::SafeOp:
      return kSafeOp;
    case EsmState::Op:
      return kOp;
    case EsmState::Boot:
      return kBoot;
    case EsmState::Init:
      break;
  }
  return 0;
}

const MailboxServer::Entry* MailboxServer::find(uint8_t type, EsmState state) const {
  for (size_t i = 0; i < protocol_count_; ++i) {
    const Entry& e = protocols_[i];
    if (e.type == type && (e.states & state_bit(state)) != 0) return &e;
  }
  return nullptr;
}

void MailboxServer::start(uint16_t in_start, uint16_t in_length, uint16_t out_start,
                          uint16_t out_length) {
  in_start_ = in_start;
  in_length_ = in_length;
  out_start_ = out_start;
  out_length_ = out_length;
  // Sized once for the configured SyncManagers (a state transition, not the cyclic path).
  if (request_.size() < in_length) request_.resize(in_length, 0);
  if (last_request_.size() < in_length) last_request_.resize(in_length, 0);
  if (reply_.size() < out_length) reply_.resize(out_length, 0);
  if (last_.size() < out_length) last_.resize(out_length, 0);
  running_ = true;
}

void MailboxServer::stop() {
  running_ = false;
  last_len_ = 0;
  last_request_counter_ = 0;
  last_request_len_ = 0;
  for (size_t i = 0; i < protocol_count_; ++i) protocols_[i].protocol->reset();
}

bool MailboxServer::sm1_free() {
  return (pdi_.read8(static_cast<uint16_t>(kSm1 + reg::kSmStatusOffset)) & reg::sm::kStatusFull) ==
         0;
}

void MailboxServer::send(size_t length) {
  // Our own counter in every message we send (ETG.1000.4 §5.6 "Cnt"), then the whole SM1
  // buffer: writing its last byte hands it to the master.
  counter_ = mailbox::next_counter(counter_);
  reply_[5] = static_cast<uint8_t>((reply_[5] & 0x8F) | (counter_ << 4));
  pdi_.write_buffer(1, out_start_, std::span<const uint8_t>(reply_.data(), out_length_));
  std::memcpy(last_.data(), reply_.data(), out_length_);
  last_len_ = length;
}

void MailboxServer::serve_repeat() {
  // ETG.1000.4 §6.7.3: the master toggled the repeat request (0x080E bit 1) because it lost
  // the last message. The firmware empties SM1 by deactivating it for a moment (0x080F bit 0),
  // writes the last message again and toggles the repeat acknowledge (0x080F bit 1).
  const uint8_t pdi_control = pdi_.read8(static_cast<uint16_t>(kSm1 + reg::kSmPdiControlOffset));
  if (last_len_ != 0) {
    pdi_.write8(static_cast<uint16_t>(kSm1 + reg::kSmPdiControlOffset),
                static_cast<uint8_t>(pdi_control | reg::sm::kPdiDeactivate));
    pdi_.write8(static_cast<uint16_t>(kSm1 + reg::kSmPdiControlOffset),
                static_cast<uint8_t>(pdi_control & ~reg::sm::kPdiDeactivate));
    pdi_.write_buffer(1, out_start_, std::span<const uint8_t>(last_.data(), out_length_));
  }
  pdi_.write8(static_cast<uint16_t>(kSm1 + reg::kSmPdiControlOffset),
              static_cast<uint8_t>((pdi_control & ~reg::sm::kPdiDeactivate) ^ reg::sm::kRepeatAck));
}

size_t MailboxServer::mailbox_error(mailbox::Error error, uint16_t address) {
  // ETG.1000.6 §5.2.3: header with Type 0, then service 0x0001 and the detail code; the
  // counter is set by send().
  if (observer_ != nullptr) observer_->on_mailbox_error(static_cast<uint16_t>(error));
  return mailbox::write_error(std::span<uint8_t>(reply_.data(), out_length_), error, address, 0);
}

size_t MailboxServer::frame(const Entry& entry, size_t data_length) {
  // The reply's header (ETG.1000.4 §5.6 Table 29): Length, Address 0, channel 0, priority 0,
  // the protocol's Type; the counter is set by send().
  if (data_length == 0) return 0;
  mailbox::Header h;
  h.length = static_cast<uint16_t>(std::min<size_t>(data_length, out_length_ - kHeaderSize));
  h.type = entry.type;
  h.encode(std::span<uint8_t>(reply_.data(), out_length_));
  return kHeaderSize + h.length;
}

size_t MailboxServer::dispatch(std::span<const uint8_t> request, EsmState state) {
  const auto header = mailbox::Header::decode(request);
  if (!header) return mailbox_error(mailbox::Error::Syntax, 0);
  if (header->length > request.size() - kHeaderSize) {
    return mailbox_error(mailbox::Error::InvalidSize, header->address);
  }
  const auto msg = request.first(kHeaderSize + header->length);

  // A double write (ETG.1000.4 §5.6, header "Cnt": detection of a double write): the same
  // non-zero counter and the same bytes as the previous request. The master resent a write
  // whose working counter it missed (SOEM does after 2 ms); the reply to the first copy is
  // already on its way and a second one would be taken for the answer to the master's next
  // request. A master that lost a reply uses the repeat request instead.
  if (header->counter != 0 && header->counter == last_request_counter_ &&
      msg.size() == last_request_len_ &&
      std::memcmp(msg.data(), last_request_.data(), msg.size()) == 0) {
    return 0;
  }
  last_request_counter_ = header->counter;
  last_request_len_ = msg.size();
  std::memcpy(last_request_.data(), msg.data(), msg.size());

  if (header->channel != 0) return mailbox_error(mailbox::Error::InvalidChannel, header->address);
  const Entry* entry = find(header->type, state);
  if (entry == nullptr) return mailbox_error(mailbox::Error::UnsupportedProtocol, header->address);
  if (out_length_ <= kHeaderSize) return 0;
  MailboxRequest r;
  r.data = msg.subspan(kHeaderSize);
  r.capacity = request.size() - kHeaderSize;
  r.address = header->address;
  r.priority = header->priority;
  r.state = state;
  const mailbox::Answer answer = entry->protocol->on_request(
      r, std::span<uint8_t>(reply_.data() + kHeaderSize, out_length_ - kHeaderSize));
  if (answer.error != mailbox::Error::None) return mailbox_error(answer.error, header->address);
  return frame(*entry, answer.length);
}

void MailboxServer::service(EsmState state, bool sm0_written, bool activation_changed) {
  if (!running_) return;
  if (activation_changed) {
    const uint8_t activate = pdi_.read8(static_cast<uint16_t>(kSm1 + reg::kSmActivateOffset));
    const uint8_t pdi_control = pdi_.read8(static_cast<uint16_t>(kSm1 + reg::kSmPdiControlOffset));
    const bool request = (activate & reg::sm::kRepeatRequest) != 0;
    const bool ack = (pdi_control & reg::sm::kRepeatAck) != 0;
    if (request != ack) {
      serve_repeat();
      return;
    }
  }
  // A request stays in SM0 (the master's next write is refused) until SM1 can take the reply.
  if (!sm1_free()) return;
  size_t n = 0;
  if (sm0_written) {
    // Reading the whole SM0 buffer (its last byte) frees it for the master's next request.
    pdi_.read_buffer(0, in_start_, std::span<uint8_t>(request_.data(), in_length_));
    n = dispatch(std::span<const uint8_t>(request_.data(), in_length_), state);
  }
  for (size_t i = 0; n == 0 && i < protocol_count_; ++i) {
    const Entry& e = protocols_[(next_poll_ + i) % protocol_count_];
    if ((e.states & state_bit(state)) == 0) continue;
    if (out_length_ <= kHeaderSize) break;
    n = frame(e, e.protocol->poll(
                     std::span<uint8_t>(reply_.data() + kHeaderSize, out_length_ - kHeaderSize)));
    if (n != 0) next_poll_ = (next_poll_ + i + 1) % protocol_count_;
  }
  if (n != 0) send(std::min<size_t>(n, out_length_));
}

}  // namespace rackcat::ecat
