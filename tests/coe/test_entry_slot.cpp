// coe::EntrySlot: a byte-aligned 8/16/32/64-bit entry read and written through its cached
// address stores the same little-endian bytes as Object::set_u (ETG.1000.6 §5.6.2), wherever
// the entry lies in the image (odd addresses included), and reads what set_u stored.
#include <gtest/gtest.h>

#include "coe/access.hpp"
#include "coe/entry_slot.hpp"
#include "coe/object_dictionary.hpp"

namespace rackcat::coe::test {
namespace {

// Subindex 0 takes 16 bits, so entries 2-4 start at the odd byte addresses 3, 5 and 9.
Object record() {
  Object o(0x2000, ObjectCode::Record, "slots");
  o.add(make_entry(0, "n", DataType::Unsigned8, 8, access::kRo, {4}));
  o.add(make_entry(1, "b", DataType::Unsigned8, 8, access::kRw));
  o.add(make_entry(2, "w", DataType::Unsigned16, 16, access::kRw));
  o.add(make_entry(3, "d", DataType::Unsigned32, 32, access::kRw));
  o.add(make_entry(4, "q", DataType::Unsigned64, 64, access::kRw));
  o.finalize();
  return o;
}

TEST(EntrySlot, StoresLittleEndianBytesAtOddAddresses) {
  Object o = record();
  ASSERT_EQ(o.entry(2)->bit_offset, 24);
  ASSERT_EQ(o.entry(4)->bit_offset, 72);
  EntrySlot(o, 1).set(0xA1);
  EntrySlot(o, 2).set(0xB2B1);
  EntrySlot(o, 3).set(0xC4C3C2C1);
  EntrySlot(o, 4).set(0xD8D7D6D5D4D3D2D1);
  const std::vector<uint8_t> want = {0x04, 0x00, 0xA1, 0xB1, 0xB2, 0xC1, 0xC2, 0xC3, 0xC4,
                                     0xD1, 0xD2, 0xD3, 0xD4, 0xD5, 0xD6, 0xD7, 0xD8};
  EXPECT_EQ(std::vector<uint8_t>(o.image().begin(), o.image().end()), want);
}

TEST(EntrySlot, ReadsWhatSetUStored) {
  Object o = record();
  o.set_u(2, 0x1234);
  o.set_u(3, 0x89ABCDEF);
  o.set_u(4, 0x0123456789ABCDEF);
  EXPECT_EQ(EntrySlot(o, 2).get(), 0x1234u);
  EXPECT_EQ(EntrySlot(o, 3).get(), 0x89ABCDEFu);
  EXPECT_EQ(EntrySlot(o, 4).get(), 0x0123456789ABCDEFu);
  // A value wider than the entry keeps only the entry's bits, as set_u does.
  EntrySlot(o, 2).set(0xFFFF5678);
  EXPECT_EQ(o.get_u(2), 0x5678u);
  EXPECT_EQ(o.get_u(3), 0x89ABCDEFu);
}

}  // namespace
}  // namespace rackcat::coe::test
