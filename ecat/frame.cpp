#include "ecat/frame.hpp"

#include "base/little_endian.hpp"

namespace rackcat::ecat {

void parse_frame(std::span<const uint8_t> frame, FrameLayout& layout) {
  layout.kind = FrameLayout::Kind::NotEtherCat;
  layout.malformed = false;
  layout.count = 0;
  // Offsets are 16-bit: anything longer than 64 KiB is no Ethernet frame.
  if (frame.size() < kEthernetHeaderSize + kEtherCatHeaderSize || frame.size() > 0xFFFF) return;
  size_t pos = 12;
  uint16_t ether_type = static_cast<uint16_t>(frame[pos] << 8 | frame[pos + 1]);
  if (ether_type == kEtherTypeVlan) {  // IEEE 802.1Q tag: the ESC skips it (ETG.1000.4 §5.3)
    pos += 4;
    if (frame.size() < pos + 2 + kEtherCatHeaderSize) return;
    ether_type = static_cast<uint16_t>(frame[pos] << 8 | frame[pos + 1]);
  }
  if (ether_type != kEtherTypeEtherCat) return;
  pos += 2;
  layout.ethercat_header = pos;
  const uint16_t header = le::get16(&frame[pos]);
  pos += kEtherCatHeaderSize;
  if ((header >> 12) != kEtherCatTypeCommands) {
    layout.kind = FrameLayout::Kind::OtherType;
    return;
  }
  layout.kind = FrameLayout::Kind::Commands;
  const size_t declared = header & 0x07FF;
  if (pos + declared > frame.size()) layout.malformed = true;

  while (true) {
    if (pos + kDatagramHeaderSize + kWorkingCounterSize > frame.size() ||
        layout.count == FrameLayout::kMaxDatagrams) {
      layout.malformed = true;
      return;
    }
    const uint16_t len_field = le::get16(&frame[pos + 6]);
    const size_t data_len = len_field & 0x07FF;
    if (pos + kDatagramHeaderSize + data_len + kWorkingCounterSize > frame.size()) {
      layout.malformed = true;
      return;
    }
    layout.offset[layout.count] = static_cast<uint16_t>(pos);
    layout.length[layout.count] = static_cast<uint16_t>(data_len);
    ++layout.count;
    pos += kDatagramHeaderSize + data_len + kWorkingCounterSize;
    if ((len_field & 0x8000) == 0) return;  // "more follows" clear: last datagram
  }
}

}  // namespace rackcat::ecat
