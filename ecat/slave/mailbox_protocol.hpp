// One mailbox protocol (CoE, FoE, EoE, ...) as the MailboxServer dispatches to it by the
// mailbox header's Type field (ETG.1000.4 §5.6 Table 29; ETG.1000.6 §5.2).
//
// A protocol sees whole mailbox messages, header included, and writes whole replies. The
// server has already checked the header (length within the SyncManager, a registered type for
// the current state) and dropped double writes; it stamps the counter (Cnt) of every reply
// itself, so a protocol leaves Cnt as it likes. Calls run on the firmware's thread and must
// not allocate.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "base/esm_state.hpp"

namespace rackcat::ecat {

// Mailbox types (ETG.1000.4 §5.6 Table 29 "Type").
namespace mailbox_type {
inline constexpr uint8_t kError = 0x0;
inline constexpr uint8_t kAoE = 0x1;
inline constexpr uint8_t kEoE = 0x2;
inline constexpr uint8_t kCoE = 0x3;
inline constexpr uint8_t kFoE = 0x4;
inline constexpr uint8_t kSoE = 0x5;
inline constexpr uint8_t kVoE = 0xF;
}  // namespace mailbox_type

class MailboxProtocol {
 public:
  virtual ~MailboxProtocol() = default;

  // A request of this protocol's type written by the master into SM0: `request` is the whole
  // SM0 buffer, the 6-byte header and header.length data bytes (checked to fit) first. Write
  // at most reply.size() bytes of reply (the whole SM1 buffer, header included) and return
  // its length, or 0 for no reply.
  virtual size_t on_request(std::span<const uint8_t> request, std::span<uint8_t> reply,
                            EsmState state) = 0;
  // An unsolicited message (e.g. CoE Emergency, further SDO Information fragments), asked for
  // whenever SM1 is free; same contract, 0 when there is none.
  virtual size_t poll(std::span<uint8_t> /*reply*/) { return 0; }
  // The mailbox starts over (the ESM went to INIT): forget transfers in progress.
  virtual void reset() {}
};

}  // namespace rackcat::ecat
