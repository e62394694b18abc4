// The 6-byte mailbox header in front of every mailbox message (ETG.1000.4 §5.6 Table 29,
// ETG.1000.6 §5.2): Length (data bytes after the header), Address, Channel (bits 0-5) and
// Priority (bits 6-7), Type (bits 0-3) and Cnt (bits 4-6, the mailbox counter 1..7; 0 = the
// sender does not count).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace rackcat::coe {

// Mailbox types (ETG.1000.4 §5.6 Table 29 "Type").
enum class MailboxType : uint8_t {
  Error = 0x0,
  AoE = 0x1,
  EoE = 0x2,
  CoE = 0x3,
  FoE = 0x4,
  SoE = 0x5,
  VoE = 0xF,
};

struct MailboxHeader {
  static constexpr size_t kSize = 6;

  uint16_t length = 0;   // bytes of mailbox data following the header
  uint16_t address = 0;  // station address of the source (master -> slave) or destination
  uint8_t channel = 0;   // 6 bits, 0 = default channel
  uint8_t priority = 0;  // 2 bits
  uint8_t type = 0;      // 4 bits, a MailboxType value
  uint8_t counter = 0;   // 3 bits, 1..7 (0 = not counted)

  // Writes the 6 header bytes; false (nothing written) if `out` is shorter.
  bool encode(std::span<uint8_t> out) const;
  // Reads the first 6 bytes; nullopt if `in` is shorter.
  static std::optional<MailboxHeader> decode(std::span<const uint8_t> in);

  MailboxType mailbox_type() const { return static_cast<MailboxType>(type); }
};

// The next counter a sender uses after `counter` (1..7, wrapping 7 -> 1; ETG.1000.4 §5.6).
constexpr uint8_t next_mailbox_counter(uint8_t counter) {
  return static_cast<uint8_t>(counter >= 7 ? 1 : counter + 1);
}

}  // namespace rackcat::coe
