// The CoE SDO server of one slave (ETG.1000.6 §5.6): takes the data of one CoE mailbox
// request (CoE header first; the mailbox header is the firmware's MailboxServer's) and writes
// the data of the reply. It knows nothing of the ESC: the device registers it as the
// firmware's CoE mailbox protocol (handle() for requests, poll() for unsolicited messages).
//
// Services: SDO upload/download (expedited, normal, segmented, complete access both ways),
// SDO Information (OD list of all six list types, object and entry descriptions, fragmented),
// Emergency (queued, sent by poll()), SDO aborts (CoE service 2, command 0x80, 10 bytes).
// A CoE header or service it cannot serve is answered with a mailbox error code (ETG.1000.6
// §5.2.3: 0x0004 service, 0x0005 header, 0x0006 too short, 0x0007 no room) that the
// MailboxServer sends; the counter, double writes and the repeat request are the server's.
//
// One server per slave; its transfer state is per server, so several slaves run side by side.
// Construction sizes every buffer; handle() and poll() allocate nothing. The buffers that live
// from one request to the next (segmented transfer data, the SDO Information description being
// fragmented) are reserved in a LazyBuffer and take RAM only once a transfer writes them; the
// ones a single request needs (a candidate value or image before it is committed) are on the
// serving thread's stack (issue 16: per-slave memory proportional to what the slave uses).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/mailbox_error.hpp"
#include "coe/abort_code.hpp"
#include "coe/access.hpp"
#include "coe/emergency_queue.hpp"
#include "coe/lazy_buffer.hpp"
#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

class SdoServer {
 public:
  static constexpr size_t kEmergencySlots = 16;

  // `od` must outlive the server. Sizes the transfer buffers from the dictionary's largest
  // object; call prepare() again if objects are added later.
  explicit SdoServer(ObjectDictionary& od);

  // One CoE request (the mailbox data: CoE header and body) -> the reply's data. `reply` is
  // SM1 after the mailbox header; its size bounds every reply and sets the segment / fragment
  // size. Returns the reply's length (0 when no reply is due: an abort request from the
  // master) or the mailbox error to answer with.
  mailbox::Answer handle(std::span<const uint8_t> request, std::span<uint8_t> reply,
                         EsmState state);
  // The data of the next unsolicited message (Emergency first, then further SDO Information
  // fragments), or 0. Call when SM1 is free.
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

  // Drops transfer and fragment state (e.g. the ESM went back to INIT: the mailbox restarts).
  // Queued emergencies stay. handle(), poll() and
  // reset() belong to one thread (the mailbox side).
  void reset();
  // Re-sizes the transfer buffers after objects were added (start-up only: allocates).
  void prepare();
  // Bytes a single request may hold on the serving thread's stack (a candidate value or
  // image); dictionaries with larger objects get reserved buffers for them instead.
  static constexpr size_t kStackScratch = 4096;

  const ObjectDictionary& dictionary() const { return od_; }

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
  size_t finish_coe(std::span<uint8_t> reply, size_t body_length, uint8_t service);
  // Records the mailbox error handle() answers with; returns 0 (no CoE reply).
  size_t mailbox_error(mailbox::Error error);
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
  // The largest value a transfer can move: the largest object image, at least 256 bytes.
  size_t capacity_ = 0;
  LazyBuffer buffers_;           // holds the spans below, reserved by prepare()
  std::span<uint8_t> data_;      // segmented transfer data (upload snapshot, download bytes)
  std::span<uint8_t> info_buf_;  // object / entry description being fragmented
  // Only when capacity_ > kStackScratch (else the request's stack holds them, see scratch()):
  std::span<uint8_t> scratch_;  // candidate image / padded entry value before commit
  std::span<uint8_t> value_;    // one entry's value during a complete-access write check
  EmergencyQueue<kEmergencySlots> emergencies_;
  mailbox::Error error_ = mailbox::Error::None;  // the current request's mailbox error
};

}  // namespace rackcat::coe
