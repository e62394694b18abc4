// One mailbox protocol (CoE, FoE, EoE, ...) as the MailboxServer dispatches to it by the
// mailbox header's Type field (ETG.1000.4 §5.6 Table 29; ETG.1000.6 §5.2).
//
// A protocol sees only mailbox data: the bytes after the 6-byte mailbox header of a request,
// and the room after the header of SM1 for its reply. The server owns the frame: it has
// checked the header (Length within SM0, channel 0, a protocol registered for the Type in the
// current state), dropped double writes, and it writes the reply's header (Length, Type =
// the protocol's, the counter Cnt) or, when the protocol answers with a mailbox error, the
// error reply (base/mailbox_error.hpp). Calls run on the firmware's thread and must not
// allocate.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "base/esm_state.hpp"
#include "base/mailbox_error.hpp"
#include "base/mailbox_header.hpp"

namespace rackcat::ecat {

// One request as the server hands it to the protocol of its Type.
struct MailboxRequest {
  std::span<const uint8_t> data;  // the header's Length bytes after the mailbox header
  size_t capacity = 0;   // data bytes SM0 holds (its size minus the header): a full segment
  uint16_t address = 0;  // the header's Address (ETG.1000.4 §5.6: the source station)
  uint8_t priority = 0;  // the header's Priority (0..3)
  EsmState state = EsmState::Init;
};

class MailboxProtocol {
 public:
  virtual ~MailboxProtocol() = default;

  // A request of this protocol's type written by the master into SM0. Write at most
  // reply.size() bytes of reply data (SM1 after the mailbox header) and return their number,
  // 0 for no reply, or a mailbox error (mailbox::Answer::error) the server sends instead.
  virtual mailbox::Answer on_request(const MailboxRequest& request, std::span<uint8_t> reply) = 0;
  // An unsolicited message (e.g. CoE Emergency, further SDO Information fragments), asked for
  // whenever SM1 is free: its data bytes in `reply`, 0 when there is none.
  virtual size_t poll(std::span<uint8_t> /*reply*/) { return 0; }
  // The mailbox starts over (the ESM went to INIT): forget transfers in progress.
  virtual void reset() {}
};

}  // namespace rackcat::ecat
