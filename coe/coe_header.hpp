// The 2-byte CoE header after the mailbox header (ETG.1000.6 §5.6.1 Table 32): Number
// (bits 0-8, used by PDO services; 0 for SDO, SDO Information and Emergency), reserved bits
// 9-11, Service (bits 12-15).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "coe/bits.hpp"

namespace rackcat::coe {

// CoE services (ETG.1000.6 §5.6.1 Table 32 "Service").
enum class CoeService : uint8_t {
  Emergency = 1,
  SdoRequest = 2,
  SdoResponse = 3,
  TxPdo = 4,
  RxPdo = 5,
  TxPdoRemoteRequest = 6,
  RxPdoRemoteRequest = 7,
  SdoInformation = 8,
};

struct CoeHeader {
  static constexpr size_t kSize = 2;

  uint16_t number = 0;  // 9 bits
  uint8_t service = 0;  // 4 bits, a CoeService value

  bool encode(std::span<uint8_t> out) const {
    if (out.size() < kSize) {
      return false;
    }
    le::put16(out.data(), static_cast<uint16_t>((number & 0x01FF) | ((service & 0x0F) << 12)));
    return true;
  }
  static std::optional<CoeHeader> decode(std::span<const uint8_t> in) {
    if (in.size() < kSize) {
      return std::nullopt;
    }
    const uint16_t w = le::get16(in.data());
    return CoeHeader{static_cast<uint16_t>(w & 0x01FF), static_cast<uint8_t>(w >> 12)};
  }
};

}  // namespace rackcat::coe
