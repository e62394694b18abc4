// One classic CAN frame (ISO 11898-1: 11-bit identifier, up to 8 data bytes) and the CANopen
// pre-defined connection set (CiA 301 §7.3.5, Table 72): COB-ID = function code + node-ID.
// The RIM link (docs/CAN.md) speaks standard CANopen, so candump and Wireshark decode it.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>

namespace rackcat::modules::canopen {

// Time on the link: microseconds of a monotonic clock. The virtual bus passes a test's
// clock, SocketCAN processes pass steady_clock; nothing below reads a clock itself.
using Micros = int64_t;

struct CanFrame {
  uint32_t id = 0;  // 11-bit identifier (COB-ID)
  uint8_t len = 0;  // DLC, 0..8
  std::array<uint8_t, 8> data{};

  static CanFrame make(uint32_t id, std::span<const uint8_t> bytes) {
    CanFrame f;
    f.id = id & 0x7FF;
    f.len = static_cast<uint8_t>(std::min<size_t>(bytes.size(), 8));
    std::copy_n(bytes.begin(), f.len, f.data.begin());
    return f;
  }
  std::span<const uint8_t> payload() const { return {data.data(), len}; }
};

// Function codes (bits 10..7 of the COB-ID), CiA 301 Table 72.
namespace cob {
inline constexpr uint32_t kNmt = 0x000;
inline constexpr uint32_t kEmcy = 0x080;       // + node-ID (node-ID 0 is SYNC)
inline constexpr uint32_t kSdoTx = 0x580;      // server -> client, + node-ID
inline constexpr uint32_t kSdoRx = 0x600;      // client -> server, + node-ID
inline constexpr uint32_t kHeartbeat = 0x700;  // NMT error control, + node-ID
// TPDO1..4 and RPDO1..4 of the pre-defined connection set.
inline constexpr std::array<uint32_t, 4> kTpdo{0x180, 0x280, 0x380, 0x480};
inline constexpr std::array<uint32_t, 4> kRpdo{0x200, 0x300, 0x400, 0x500};

constexpr uint32_t function(uint32_t id) {
  return id & 0x780;
}
constexpr uint8_t node(uint32_t id) {
  return static_cast<uint8_t>(id & 0x7F);
}
}  // namespace cob

}  // namespace rackcat::modules::canopen
