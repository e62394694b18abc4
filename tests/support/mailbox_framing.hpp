// The slave's side of the mailbox frame (ETG.1000.4 §5.6 Table 29) for tests that drive a
// mailbox protocol without the firmware: the SDO server, mdp::Device's CoE and FoE, a
// RackSlave's registered protocols. The request's header is read and its data handed to the
// protocol; the answer is framed the way ecat::MailboxServer frames it: a reply header
// (Length, Address 0, the protocol's Type, the slave's counter 1..7) or a mailbox error reply.
// The header checks, double writes and the repeat request are the firmware's own and are
// tested there (tests/ecat/test_firmware.cpp, MailboxTest).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

#include "base/mailbox_error.hpp"
#include "base/mailbox_header.hpp"

namespace rackcat::testing {

class SlaveMailbox {
 public:
  static constexpr size_t kHeader = mailbox::Header::kSize;

  explicit SlaveMailbox(mailbox::Type type = mailbox::Type::CoE) : type_(type) {}

  // One request message (header included) -> the reply message written into `reply` (its
  // size plays SM1's), or 0. `handle(data, capacity, reply_data)` returns a mailbox::Answer;
  // `capacity` is what the request buffer holds after the header (SM0's data bytes).
  template <class Handle>
  size_t request(std::span<const uint8_t> message, std::span<uint8_t> reply, Handle&& handle) {
    const auto h = mailbox::Header::decode(message);
    if (!h || reply.size() <= kHeader) return 0;
    const size_t capacity = message.size() - kHeader;
    if (h->length > capacity) {
      return mailbox::write_error(reply, mailbox::Error::InvalidSize, h->address, next());
    }
    const mailbox::Answer a =
        handle(message.subspan(kHeader, h->length), capacity, reply.subspan(kHeader));
    if (a.error != mailbox::Error::None) {
      return mailbox::write_error(reply, a.error, h->address, next());
    }
    return frame(reply, a.length);
  }
  // An unsolicited message: `poll(reply_data)` returns its data length, or 0.
  template <class Poll>
  size_t poll(std::span<uint8_t> reply, Poll&& poll) {
    if (reply.size() <= kHeader) return 0;
    return frame(reply, poll(reply.subspan(kHeader)));
  }

 private:
  uint8_t next() { return counter_ = mailbox::next_counter(counter_); }
  size_t frame(std::span<uint8_t> reply, size_t length) {
    if (length == 0) return 0;
    mailbox::Header h;
    h.length = static_cast<uint16_t>(std::min(length, reply.size() - kHeader));
    h.type = static_cast<uint8_t>(type_);
    h.counter = next();
    h.encode(reply);
    return kHeader + h.length;
  }

  mailbox::Type type_;
  uint8_t counter_ = 0;
};

}  // namespace rackcat::testing
