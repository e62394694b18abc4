// Reports the CoE replies that signal a problem to the event log (base/event_log.hpp): SDO
// aborts (ETG.1000.6 §5.6.2.7: CoE service 2/3, command specifier 0x80). Mailbox error replies
// are the firmware's MailboxServer's and reach the log through its EsmObserver. Reads a few
// bytes of the reply's mailbox data, allocates nothing; the log rate-limits.
#pragma once

#include <cstdint>
#include <span>

#include "base/event_log.hpp"
#include "base/little_endian.hpp"

namespace rackcat::apps {

inline void log_coe_reply(std::span<const uint8_t> data) {
  if (!base::event_log().enabled() || data.size() < 10) return;
  // CoE header (number, service in bits 15..12), then the SDO command byte, index, subindex
  // and the abort code.
  const unsigned service = le::get16(&data[0]) >> 12;
  if ((service == 2 || service == 3) && (data[2] & 0xE0) == 0x80) {
    base::log_event({.kind = base::EventKind::SdoAbort,
                     .a = data[5],
                     .index = le::get16(&data[3]),
                     .value = le::get32(&data[6])});
  }
}

}  // namespace rackcat::apps
