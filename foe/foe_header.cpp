// FoE header encoding (ETG.1000.6 §5.8): little-endian, reserved byte written as 0.
#include "foe/foe_header.hpp"

namespace rackcat::foe {

bool FoeHeader::encode(std::span<uint8_t> out) const {
  if (out.size() < kSize) return false;
  out[0] = opcode;
  out[1] = 0;
  for (int i = 0; i < 4; ++i) out[2 + i] = static_cast<uint8_t>(value >> (8 * i));
  return true;
}

std::optional<FoeHeader> FoeHeader::decode(std::span<const uint8_t> in) {
  if (in.size() < kSize) return std::nullopt;
  FoeHeader h;
  h.opcode = in[0];
  for (int i = 0; i < 4; ++i) h.value |= static_cast<uint32_t>(in[2 + i]) << (8 * i);
  return h;
}

}  // namespace rackcat::foe
