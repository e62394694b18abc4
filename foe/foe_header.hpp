// The 6-byte FoE header after the mailbox header (ETG.1000.5 §6.4, ETG.1000.6 §5.8 Tables
// "Read request" .. "Busy request"): OpCode (UINT8), Reserved (UINT8, 0), then one 32-bit
// field whose meaning depends on the OpCode: the password of a read or write request, the
// packet number of a data or acknowledge request, the error code of an error request, and
// Done / Entire (two UINT16) of a busy request. What follows is the file name (read / write
// request), the file data (data request) or the error / busy text.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace rackcat::foe {

enum class OpCode : uint8_t {
  ReadRequest = 1,
  WriteRequest = 2,
  Data = 3,
  Ack = 4,
  Error = 5,
  Busy = 6,
};

struct FoeHeader {
  static constexpr size_t kSize = 6;

  uint8_t opcode = 0;
  uint32_t value = 0;  // password, packet number, error code, or Done | Entire << 16

  // Writes the 6 header bytes; false (nothing written) if `out` is shorter.
  bool encode(std::span<uint8_t> out) const;
  // Reads the first 6 bytes; nullopt if `in` is shorter.
  static std::optional<FoeHeader> decode(std::span<const uint8_t> in);
};

}  // namespace rackcat::foe
