// The CoE SDO server of one slave (ETG.1000.6 §5.6): takes a whole mailbox request (mailbox
// header included) and writes the whole reply mailbox. It knows nothing of the ESC: the
// device registers it as the firmware's CoE mailbox protocol (handle() for requests, poll()
// for unsolicited messages).
//
// Services: SDO upload/download (expedited, normal, segmented, complete access both ways),
// SDO Information (OD list of all six list types, object and entry descriptions, fragmented),
// Emergency (queued, sent by poll()), SDO aborts (CoE service 2, command 0x80, 10 bytes) and
// mailbox errors (mailbox type 0). Mailbox counter: every message the server sends carries its
// own counter 1..7; a request repeating the master's previous non-zero counter (and bytes) is
// a double write (ETG.1000.4 §5.6) and is dropped: no reply, not executed twice.
//
// One server per slave; its transfer state is per server, so several slaves run side by side.
// Construction sizes every buffer; handle() and poll() allocate nothing.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "coe/abort_code.hpp"
#include "coe/access.hpp"
#include "coe/emergency_queue.hpp"
#include "coe/mailbox_error.hpp"
#include "coe/mailbox_header.hpp"
#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

class SdoServer {
 public:
  // Largest mailbox kept to recognise double writes (an SM of up to 1486 bytes fits a frame).
  static constexpr size_t kMaxMailbox = 1486;
  static constexpr size_t kEmergencySlots = 16;

  // `od` must outlive the server. Sizes the transfer buffers from the dictionary's largest
  // object; call prepare() again if objects are added later.
  explicit SdoServer(ObjectDictionary& od);

  // One mailbox request -> one reply (header included). `reply` is the send mailbox (SM1);
  // its size bounds every reply and sets the segment / fragment size. Returns the reply length,
  // or 0 when no reply is due (an abort request from the master, a too-small reply buffer).
  size_t handle(std::span<const uint8_t> request, std::span<uint8_t> reply, EsmState state);
  // The next unsolicited message (Emergency first, then further SDO Information fragments),
  // or 0. Call when SM1 is free.
  size_t poll(std::span<uint8_t> reply);
  bool has_pending() const { return !emergencies_.empty() || info_.kind != InfoKind::None; }

  // Queues an Emergency (CoE service 1). Never allocates and takes no lock: one thread may
  // queue while the mailbox thread calls handle()/poll(). A full queue (kEmergencySlots)
  // keeps its messages and counts the new one in emergency_overruns(); returns false then.
  bool queue_emergency(uint16_t error_code, uint8_t error_register,
                       std::array<uint8_t, 5> data = {});
  bool queue_emergency(const Emergency& e) { return emergencies_.push(e); }
  size_t pending_emergencies() const { return emergencies_.size(); }
  size_t emergency_overruns() const { return emergencies_.overruns(); }

  // Drops transfer, fragment and double-write state (e.g. the ESM went back to INIT: the mailbox
  // restarts and so does the master's counter). Queued emergencies stay. handle(), poll() and
  // reset() belong to one thread (the mailbox side).
  void reset();
  // Re-sizes the transfer buffers after objects were added (start-up only: allocates).
  void prepare();

  const ObjectDictionary& dictionary() const { return od_; }

  // The counter for a message another mailbox protocol of this slave sends (FoE): one
  // sequence 1..7 for every message the slave sends (ETG.1000.4 §5.6).
  uint8_t next_counter() {
    counter_ = next_mailbox_counter(counter_);
    return counter_;
  }

 private:
  enum class TransferKind : uint8_t { None, Upload, Download };
  struct Transfer {
    TransferKind kind = TransferKind::None;
    uint16_t index = 0;
    uint8_t subindex = 0;
    bool complete_access = false;
    uint8_t toggle = 0;  // expected toggle bit of the next segment request (0 or kToggle)
    size_t size = 0;     // total bytes
    size_t done = 0;     // bytes sent / received
  };
  enum class InfoKind : uint8_t { None, List, Buffer };
  struct InfoTransfer {
    InfoKind kind = InfoKind::None;
    uint8_t opcode = 0;  // response opcode
    uint16_t list_type = 0;
    size_t total = 0;          // bytes of the whole response payload
    size_t sent = 0;           // bytes already sent
    size_t cursor = 0;         // List: next dictionary position to scan
    size_t fragment_size = 0;  // payload bytes per fragment (even)
    uint16_t fragments_left = 0;
  };

  // Framing (sdo_server.cpp).
  size_t finish(std::span<uint8_t> reply, size_t data_length, MailboxType type);
  size_t finish_coe(std::span<uint8_t> reply, size_t body_length, uint8_t service);
  size_t mailbox_error(std::span<uint8_t> reply, MailboxError error, uint16_t address);
  size_t abort(std::span<uint8_t> reply, uint16_t index, uint8_t subindex, AbortCode code);
  size_t dispatch(std::span<const uint8_t> request, std::span<uint8_t> reply, EsmState state);
  size_t sdo_request(std::span<const uint8_t> body, std::span<uint8_t> reply, EsmState state);
  // What every initiate request, upload or download, starts with (ETG.1000.6 Tables 35, 36,
  // 38): command byte, index, subindex; plus the object they address (nullptr when none).
  struct InitiateRequest {
    uint8_t cmd;
    uint16_t index;
    uint8_t subindex;
    bool complete_access;
    Object* obj;
  };
  // Decodes an initiate request and looks its object up; a new initiate ends any stale transfer.
  InitiateRequest begin_initiate(std::span<const uint8_t> body);
  // The abort code for an index the dictionary lacks (an empty one is no dictionary at all).
  AbortCode missing_object() const;

  // Upload (sdo_upload.cpp).
  size_t upload_initiate(std::span<const uint8_t> body, std::span<uint8_t> reply, EsmState state);
  size_t upload_segment(std::span<const uint8_t> body, std::span<uint8_t> reply);
  // Download (sdo_download.cpp).
  size_t download_initiate(std::span<const uint8_t> body, std::span<uint8_t> reply, EsmState state);
  size_t download_segment(std::span<const uint8_t> body, std::span<uint8_t> reply, EsmState state);
  AbortCode check_download_target(const Object& obj, uint8_t subindex, bool complete_access,
                                  size_t size, EsmState state) const;
  AbortCode commit_download(Object& obj, uint8_t subindex, bool complete_access,
                            std::span<const uint8_t> data, EsmState state);
  AbortCode write_entry(Object& obj, const Entry& entry, std::span<const uint8_t> data,
                        EsmState state);
  // Complete access (complete_access.cpp).
  AbortCode read_complete(Object& obj, uint8_t subindex, EsmState state, size_t& bytes);
  AbortCode write_complete(Object& obj, uint8_t subindex, std::span<const uint8_t> data,
                           EsmState state);
  // SDO Information (sdo_info.cpp).
  size_t sdo_info(std::span<const uint8_t> body, std::span<uint8_t> reply);
  size_t info_error(std::span<uint8_t> reply, AbortCode code);
  size_t start_fragments(std::span<uint8_t> reply, InfoKind kind, uint8_t opcode, size_t total,
                         size_t fragment, uint16_t list_type = 0);
  size_t info_fragment(std::span<uint8_t> reply);
  size_t list_count(uint16_t list_type) const;
  bool in_list(const Object& obj, uint16_t list_type) const;
  size_t describe_object(const Object& obj);
  size_t describe_entry(const Object& obj, const Entry& entry, uint8_t value_info);

  ObjectDictionary& od_;
  Transfer transfer_;
  InfoTransfer info_;
  std::vector<uint8_t> data_;      // segmented transfer data (upload snapshot, download bytes)
  std::vector<uint8_t> scratch_;   // candidate image / padded entry value before commit
  std::vector<uint8_t> value_;     // one entry's value during a complete-access write check
  std::vector<uint8_t> info_buf_;  // object / entry description being fragmented
  EmergencyQueue<kEmergencySlots> emergencies_;

  uint8_t counter_ = 0;  // our last counter (1..7)
  uint8_t last_request_counter_ = 0;
  size_t last_request_len_ = 0;
  std::array<uint8_t, kMaxMailbox> last_request_{};
};

}  // namespace rackcat::coe
