// Mailbox hand-over on SM0/SM1 through the PDI, header checks, double writes, the counter,
// the repeat request and dispatch by type (ETG.1000.4 §5.6, §6.7.3; ETG.1000.6 §5.2).
#include "ecat/slave/mailbox_server.hpp"

#include <algorithm>
#include <cstring>

#include "base/little_endian.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// Mailbox error codes (ETG.1000.6 §5.2.3 Table 29, "Detail") the server itself produces.
constexpr uint16_t kErrorInvalidChannel = 0x0003;
constexpr uint16_t kErrorUnsupportedProtocol = 0x0002;
constexpr uint16_t kErrorInvalidSize = 0x0008;
constexpr uint16_t kErrorService = 0x0001;  // mailbox command "error"

constexpr uint16_t kSm1 = reg::sm::base(1);

constexpr uint8_t next_counter(uint8_t c) {
  return static_cast<uint8_t>(c >= 7 ? 1 : c + 1);
}

}  // namespace

bool MailboxServer::add(uint8_t type, MailboxProtocol& protocol, uint8_t states) {
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

MailboxProtocol* MailboxServer::find(uint8_t type, EsmState state) const {
  for (size_t i = 0; i < protocol_count_; ++i) {
    const Entry& e = protocols_[i];
    if (e.type == type && (e.states & state_bit(state)) != 0) return e.protocol;
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
  counter_ = next_counter(counter_);
  reply_[5] = static_cast<uint8_t>((reply_[5] & 0x8F) | (counter_ << 4));
  pdi_.write(out_start_, std::span<const uint8_t>(reply_.data(), out_length_));
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
    pdi_.write(out_start_, std::span<const uint8_t>(last_.data(), out_length_));
  }
  pdi_.write8(static_cast<uint16_t>(kSm1 + reg::kSmPdiControlOffset),
              static_cast<uint8_t>((pdi_control & ~reg::sm::kPdiDeactivate) ^ reg::sm::kRepeatAck));
}

size_t MailboxServer::mailbox_error(uint16_t detail, uint16_t address) {
  // ETG.1000.6 §5.2.3: header with Type 0, then service 0x0001 and the detail code.
  if (observer_ != nullptr) observer_->on_mailbox_error(detail);
  if (out_length_ < kHeaderSize + 4) return 0;
  le::put16(&reply_[0], 4);
  le::put16(&reply_[2], address);
  reply_[4] = 0;
  reply_[5] = 0;  // type 0 (error); counter set by send()
  le::put16(&reply_[6], kErrorService);
  le::put16(&reply_[8], detail);
  return kHeaderSize + 4;
}

size_t MailboxServer::dispatch(std::span<const uint8_t> request, EsmState state) {
  const uint16_t length = le::get16(&request[0]);
  const uint16_t address = le::get16(&request[2]);
  if (length > request.size() - kHeaderSize) return mailbox_error(kErrorInvalidSize, address);
  const auto msg = request.first(kHeaderSize + length);

  // A double write: the same non-zero counter and the same bytes as the previous request.
  // The reply to the first copy is already on its way; a second one would be taken for the
  // answer to the master's next request. A master that lost a reply uses the repeat request.
  const uint8_t counter = (msg[5] >> 4) & 0x07;
  if (counter != 0 && counter == last_request_counter_ && msg.size() == last_request_len_ &&
      std::memcmp(msg.data(), last_request_.data(), msg.size()) == 0) {
    return 0;
  }
  last_request_counter_ = counter;
  last_request_len_ = msg.size();
  std::memcpy(last_request_.data(), msg.data(), msg.size());

  if ((msg[4] & 0x3F) != 0) return mailbox_error(kErrorInvalidChannel, address);
  MailboxProtocol* protocol = find(msg[5] & 0x0F, state);
  if (protocol == nullptr) return mailbox_error(kErrorUnsupportedProtocol, address);
  // The protocol gets the whole SM0 buffer, as the master wrote it: its size is the capacity
  // a protocol's segmented transfers are sized by.
  return protocol->on_request(request, std::span<uint8_t>(reply_.data(), out_length_), state);
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
    pdi_.read(in_start_, std::span<uint8_t>(request_.data(), in_length_));
    n = dispatch(std::span<const uint8_t>(request_.data(), in_length_), state);
  }
  for (size_t i = 0; n == 0 && i < protocol_count_; ++i) {
    const Entry& e = protocols_[(next_poll_ + i) % protocol_count_];
    if ((e.states & state_bit(state)) == 0) continue;
    n = e.protocol->poll(std::span<uint8_t>(reply_.data(), out_length_));
    if (n != 0) next_poll_ = (next_poll_ + i + 1) % protocol_count_;
  }
  if (n != 0) send(std::min<size_t>(n, out_length_));
}

}  // namespace rackcat::ecat
