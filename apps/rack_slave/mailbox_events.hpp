// Reports the mailbox replies that signal a problem to the event log (base/event_log.hpp):
// mailbox error replies (mailbox type 0, ETG.1000.4 §5.6 Table 29) and SDO aborts (CoE,
// ETG.1000.6 §5.6.2.7: service 2/3, command specifier 0x80). Reads a few bytes of the reply,
// allocates nothing; the log rate-limits both kinds.
#pragma once

#include <cstdint>
#include <span>

#include "base/event_log.hpp"

namespace rackcat::apps {

inline void log_mailbox_reply(std::span<const uint8_t> reply) {
  if (!base::event_log().enabled() || reply.size() < 8) return;
  auto u16 = [&](size_t at) { return static_cast<uint16_t>(reply[at] | (reply[at + 1] << 8)); };
  const uint8_t type = reply[5] & 0x0F;  // mailbox header: length, address, channel, type
  if (type == 0x00 && reply.size() >= 10 && u16(6) == 0x0001) {
    base::log_event({.kind = base::EventKind::MailboxError, .code = u16(8)});
    return;
  }
  // CoE header (number, service in bits 15..12), then the SDO command byte.
  if (type == 0x03 && reply.size() >= 16) {
    const unsigned service = u16(6) >> 12;
    if ((service == 2 || service == 3) && (reply[8] & 0xE0) == 0x80) {
      const uint32_t abort =
          static_cast<uint32_t>(u16(12)) | (static_cast<uint32_t>(u16(14)) << 16);
      base::log_event(
          {.kind = base::EventKind::SdoAbort, .a = reply[11], .index = u16(9), .value = abort});
    }
  }
}

}  // namespace rackcat::apps
