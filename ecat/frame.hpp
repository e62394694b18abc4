// EtherCAT frame and datagram layout (ETG.1000.4 §5.3, §5.4).
//
//   Ethernet header   dst(6) src(6) [VLAN 0x8100 tag(4)] EtherType 0x88A4 (2)
//   EtherCAT header   length:11 reserved:1 type:4          (type 1 = EtherCAT commands)
//   datagram          cmd(1) idx(1) address(4) len:11 r:3 circulating:1 more:1 (2) irq(2)
//                     data(len) wkc(2)                      repeated while "more" is set
//
// parse_frame() only locates datagrams; it never writes, so a malformed frame is found before
// any slave changes state.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace rackcat::ecat {

inline constexpr uint16_t kEtherTypeEtherCat = 0x88A4;
inline constexpr uint16_t kEtherTypeVlan = 0x8100;
inline constexpr size_t kEthernetHeaderSize = 14;
inline constexpr size_t kEtherCatHeaderSize = 2;
inline constexpr size_t kDatagramHeaderSize = 10;
inline constexpr size_t kWorkingCounterSize = 2;
inline constexpr uint8_t kEtherCatTypeCommands = 1;

// ETG.1000.4 Table 14 (command types).
enum class Command : uint8_t {
  Nop = 0,
  Aprd = 1,
  Apwr = 2,
  Aprw = 3,
  Fprd = 4,
  Fpwr = 5,
  Fprw = 6,
  Brd = 7,
  Bwr = 8,
  Brw = 9,
  Lrd = 10,
  Lwr = 11,
  Lrw = 12,
  Armw = 13,
  Frmw = 14,
};

// Where each datagram of one frame starts (offset of its 10-byte header) and how long its
// data is. Fixed capacity: a 1514-byte frame holds at most 125 datagrams; jumbo frames
// beyond kMaxDatagrams datagrams are treated as malformed past that point.
struct FrameLayout {
  static constexpr size_t kMaxDatagrams = 768;
  enum class Kind : uint8_t {
    NotEtherCat,  // other EtherType or too short: the ESC does not process it
    OtherType,    // EtherCAT header type != 1: forwarded unchanged
    Commands,     // datagrams found (possibly followed by a malformed tail)
  };
  Kind kind = Kind::NotEtherCat;
  bool malformed = false;      // header length or a datagram chain runs past the frame end
  size_t ethercat_header = 0;  // offset of the 2-byte EtherCAT header
  size_t count = 0;
  std::array<uint16_t, kMaxDatagrams> offset{};
  std::array<uint16_t, kMaxDatagrams> length{};
};

// Locates the datagrams of an Ethernet frame. Datagrams that fit completely are listed; the
// first one that does not (header, data or working counter past the end of the frame) and
// everything after it is left out and `malformed` is set.
void parse_frame(std::span<const uint8_t> frame, FrameLayout& layout);

}  // namespace rackcat::ecat
