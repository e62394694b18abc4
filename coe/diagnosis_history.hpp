// The diagnosis history object 0x10F3 (ETG.1020 ch. 13 "Diagnosis Handling"): a ring of
// diagnosis messages in the subindices 6..5+N, its control entries, and the overwrite and
// acknowledge modes.
//
//   0x10F3:01 Maximum Messages             UNSIGNED8  ro  N
//   0x10F3:02 Newest Message               UNSIGNED8  ro  subindex of the newest message, 0 = none
//   0x10F3:03 Newest Acknowledged Message  UNSIGNED8  rw  subindex of the newest acknowledged
//   0x10F3:04 New Messages Available       BOOLEAN    ro  TxPDO-mappable
//   0x10F3:05 Flags                        UNSIGNED16 rw  bit 0 send new messages as Emergency,
//             bits 1/2/3 disable info/warning/error messages, bit 4 0 = overwrite mode /
//             1 = acknowledge mode, bit 5 (read only) messages were overwritten (overwrite
//             mode) or discarded (acknowledge mode); bits 6..15 reserved (0)
//   0x10F3:06.. Diagnosis Message          OCTET_STRING(kMessageBytes) ro
//
// Message layout (ETG.1020 ch. 13 "Diagnosis Message", little-endian):
//   bytes 0..3   Diag Code: bits 0..15 0xE800 = the CoE Emergency error code is in bits
//                16..31; 0xE000..0xE7FF manufacturer specific
//   bytes 4..5   Flags: bits 0..3 type (0 info, 1 warning, 2 error), bit 4 the time stamp is
//                local (0 = DC system time), bits 8..15 number of parameters
//   bytes 6..7   Text ID (the ESI DiagMessages text)
//   bytes 8..15  Time stamp in ns (DC system time: since 2000-01-01)
//   bytes 16..   parameters, each a UNSIGNED16 parameter flag (bits 12..15 = 0: bits 0..11
//                are the ETG.1000.6 data type index) followed by the value
// The remaining bytes of a slot are 0; an empty slot is all 0.
//
// Ring rules (ETG.1020 ch. 13, as described by implementers' manuals):
//   overwrite mode: a new message replaces the oldest when the ring is full; replacing a
//     message that was not acknowledged sets Flags bit 5 and 0x10F3:03 becomes 0. Writing 0
//     to 0x10F3:03 deletes every message; writing the subindex of a stored message
//     acknowledges it and every older one. New Messages Available = the newest message has
//     not been read yet (an SDO read of its own subindex clears it, or acknowledging it).
//   acknowledge mode: a new message replaces only acknowledged messages; with a ring full of
//     unacknowledged ones it is discarded and Flags bit 5 set. Writing 0 to 0x10F3:03 deletes
//     the acknowledged messages. New Messages Available = an unacknowledged message exists.
//   0x10F3:03 writes: 1..5 abort 0x06090032, above 5+N 0x06090031, a subindex without a
//   message 0x06090030.
//
// Threading: one thread (the device thread) adds messages and serves the SDO hooks. add()
// allocates nothing.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "coe/object_dictionary.hpp"

namespace rackcat::coe::diag {

inline constexpr uint16_t kIndex = 0x10F3;
inline constexpr uint8_t kFirstMessage = 6;
inline constexpr size_t kMessageBytes = 32;  // header 16 + up to 16 bytes of parameters
inline constexpr size_t kMaxParameterBytes = kMessageBytes - 16;

// Flags (0x10F3:05).
inline constexpr uint16_t kFlagEmergency = 1u << 0;
inline constexpr uint16_t kFlagDisableInfo = 1u << 1;
inline constexpr uint16_t kFlagDisableWarning = 1u << 2;
inline constexpr uint16_t kFlagDisableError = 1u << 3;
inline constexpr uint16_t kFlagAcknowledgeMode = 1u << 4;
inline constexpr uint16_t kFlagOverflow = 1u << 5;
inline constexpr uint16_t kFlagsWritable = 0x001F;

// Message flags (bytes 4..5).
enum class Type : uint8_t { Info = 0, Warning = 1, Error = 2 };
inline constexpr uint16_t kMessageLocalTime = 1u << 4;

// Diag code with the CoE Emergency error code in bits 16..31 (ETG.1020 ch. 13 Diag Code).
constexpr uint32_t emergency_diag_code(uint16_t emergency_code) {
  return (static_cast<uint32_t>(emergency_code) << 16) | 0xE800u;
}

struct Message {
  uint32_t diag_code = 0;
  Type type = Type::Info;
  uint16_t text_id = 0;
  uint64_t time_ns = 0;
  bool local_time = false;  // time stamp from the local clock (DC not running)
  uint8_t parameter_count = 0;
  uint8_t parameter_bytes = 0;
  std::array<uint8_t, kMaxParameterBytes> parameters{};

  // Appends one parameter (flag word = ETG.1000.6 data type index, then the value). False when
  // it does not fit the slot (the message is left unchanged).
  bool add_u8(uint8_t v) { return add(0x0005, v, 1); }
  bool add_u16(uint16_t v) { return add(0x0006, v, 2); }
  bool add_u32(uint32_t v) { return add(0x0007, v, 4); }
  bool add_i16(int16_t v) { return add(0x0003, static_cast<uint16_t>(v), 2); }
  // The value of parameter `n` (0-based) as unsigned, sign bits as stored; 0 if absent or
  // not an integer of 1..4 bytes.
  uint32_t parameter(size_t n) const;

 private:
  bool add(uint16_t type, uint32_t value, uint8_t size);
};

// The message's bytes as they appear in its subindex.
std::array<uint8_t, kMessageBytes> encode(const Message& m);
// The inverse for a slot of at least 16 bytes (parameters that do not fit the slot are
// dropped); nullopt for an empty (all 0) slot or a shorter one.
std::optional<Message> decode(std::span<const uint8_t> slot);

enum class AddResult : uint8_t { Stored, Filtered, Discarded };

class History {
 public:
  // capacity 1..250 (subindices 6..255).
  explicit History(uint8_t capacity);

  // The 0x10F3 object with its entries (defaults: empty ring, `flags`).
  Object make_object(uint16_t default_flags = kFlagEmergency) const;
  // Attach to the 0x10F3 object in the dictionary: installs its SDO hooks, adopts the flags
  // found there and clears the ring. The object must outlive the history's use.
  void bind(Object& object);

  // Device thread, no allocation. Stored: the message is in the ring; Filtered: its type is
  // disabled by Flags bits 1..3; Discarded: acknowledge mode with a ring full of
  // unacknowledged messages (Flags bit 5 set).
  AddResult add(const Message& m);
  // Delete every message (power-on state; the flags keep their value).
  void clear();

  uint16_t flags() const;
  bool emergency_enabled() const { return (flags() & kFlagEmergency) != 0; }
  bool acknowledge_mode() const { return (flags() & kFlagAcknowledgeMode) != 0; }
  uint8_t capacity() const { return capacity_; }
  size_t count() const { return count_; }
  size_t acknowledged() const { return acked_; }
  bool new_messages() const;
  bool overflow() const { return overflow_; }
  // Subindex of the message `age` positions after the oldest (0 = oldest), 0 if none.
  uint8_t subindex_of(size_t age) const;
  uint8_t newest_subindex() const { return count_ ? subindex_of(count_ - 1) : 0; }
  // The stored bytes of a message subindex (empty slots are all 0).
  std::span<const uint8_t> slot(uint8_t subindex) const;

  // What an SDO write of 0x10F3:03 / :05 does (also used by the hooks). AbortCode::None when
  // accepted and executed.
  AbortCode write_newest_acknowledged(uint8_t subindex);
  AbortCode write_flags(uint16_t value);
  // An SDO read of `subindex` (-1 = complete access or the process image packing a mapped
  // 0x10F3:04): clears New Messages Available in overwrite mode when it is the newest
  // message's subindex.
  void on_read(int subindex);

 private:
  size_t ring_of_subindex(uint8_t subindex) const { return subindex - kFirstMessage; }
  size_t oldest_ring() const { return (head_ + capacity_ - count_) % capacity_; }
  void drop_oldest();
  void clear_slot(size_t ring);
  void publish();
  AbortCode check_newest_acknowledged(uint8_t subindex) const;

  uint8_t capacity_;
  Object* object_ = nullptr;
  uint16_t flags_ = kFlagEmergency;  // writable bits; bit 5 is overflow_
  size_t head_ = 0;                  // ring position of the next message
  size_t count_ = 0;                 // stored messages
  size_t acked_ = 0;                 // the oldest `acked_` messages are acknowledged
  bool unread_ = false;              // overwrite mode: the newest message was not read
  bool overflow_ = false;
};

}  // namespace rackcat::coe::diag
