// The mailbox message frame (ETG.1000.4 §5.6 Table 29, ETG.1000.6 §5.2): the 6-byte header in
// front of every mailbox message - Length (data bytes after the header), Address, Channel
// (bits 0-5) and Priority (bits 6-7), Type (bits 0-3) and Cnt (bits 4-6, the mailbox counter
// 1..7; 0 = the sender does not count) - and the mailbox types. The slave's MailboxServer
// (ecat/slave) is the one that reads and writes it; protocols see only the data after it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "base/little_endian.hpp"

namespace rackcat::mailbox {

// Mailbox types (ETG.1000.4 §5.6 Table 29 "Type").
enum class Type : uint8_t {
  Error = 0x0,
  AoE = 0x1,
  EoE = 0x2,
  CoE = 0x3,
  FoE = 0x4,
  SoE = 0x5,
  VoE = 0xF,
};

struct Header {
  static constexpr size_t kSize = 6;

  uint16_t length = 0;   // bytes of mailbox data following the header
  uint16_t address = 0;  // station address of the source (master -> slave) or destination
  uint8_t channel = 0;   // 6 bits, 0 = default channel
  uint8_t priority = 0;  // 2 bits
  uint8_t type = 0;      // 4 bits, a Type value
  uint8_t counter = 0;   // 3 bits, 1..7 (0 = not counted)

  // Writes the 6 header bytes; false (nothing written) if `out` is shorter.
  bool encode(std::span<uint8_t> out) const {
    if (out.size() < kSize) return false;
    le::put16(&out[0], length);
    le::put16(&out[2], address);
    out[4] = static_cast<uint8_t>((channel & 0x3F) | ((priority & 0x03) << 6));
    out[5] = static_cast<uint8_t>((type & 0x0F) | ((counter & 0x07) << 4));
    return true;
  }
  // Reads the first 6 bytes (bit 7 of byte 5 is reserved and ignored); nullopt if shorter.
  static std::optional<Header> decode(std::span<const uint8_t> in) {
    if (in.size() < kSize) return std::nullopt;
    Header h;
    h.length = le::get16(&in[0]);
    h.address = le::get16(&in[2]);
    h.channel = in[4] & 0x3F;
    h.priority = static_cast<uint8_t>(in[4] >> 6);
    h.type = in[5] & 0x0F;
    h.counter = static_cast<uint8_t>((in[5] >> 4) & 0x07);
    return h;
  }

  Type mailbox_type() const { return static_cast<Type>(type); }
};

// The next counter a sender uses after `counter` (1..7, wrapping 7 -> 1; ETG.1000.4 §5.6).
constexpr uint8_t next_counter(uint8_t counter) {
  return static_cast<uint8_t>(counter >= 7 ? 1 : counter + 1);
}

}  // namespace rackcat::mailbox
