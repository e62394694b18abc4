#include "coe/mailbox_header.hpp"

#include "coe/bits.hpp"

namespace rackcat::coe {

bool MailboxHeader::encode(std::span<uint8_t> out) const {
  if (out.size() < kSize) {
    return false;
  }
  le::put16(&out[0], length);
  le::put16(&out[2], address);
  out[4] = static_cast<uint8_t>((channel & 0x3F) | ((priority & 0x03) << 6));
  out[5] = static_cast<uint8_t>((type & 0x0F) | ((counter & 0x07) << 4));
  return true;
}

std::optional<MailboxHeader> MailboxHeader::decode(std::span<const uint8_t> in) {
  if (in.size() < kSize) {
    return std::nullopt;
  }
  MailboxHeader h;
  h.length = le::get16(&in[0]);
  h.address = le::get16(&in[2]);
  h.channel = in[4] & 0x3F;
  h.priority = static_cast<uint8_t>(in[4] >> 6);
  h.type = in[5] & 0x0F;
  h.counter = static_cast<uint8_t>((in[5] >> 4) & 0x07);
  return h;
}

}  // namespace rackcat::coe
