// SDO Information golden vectors (ETG.1000.6 §5.6.3): OD lists (all six list types), object
// and entry descriptions, fragmentation, SDO Information errors.
#include "coe/sdo_info.hpp"
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

Bytes words(std::initializer_list<uint16_t> ws) {
  Bytes b;
  for (uint16_t w : ws) {
    b.push_back(static_cast<uint8_t>(w));
    b.push_back(static_cast<uint8_t>(w >> 8));
  }
  return b;
}

Bytes cat(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST_F(SdoTest, OdListOfAllObjectsSplitOverFragments) {
  // A 24-byte mailbox leaves 24 - 12 = 12 bytes (6 words) per fragment; the list is the word
  // stream [list type 1, 22 indices] = 46 bytes = 4 fragments.
  const Bytes request{0x08, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00,
                      0x80, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00};
  const Bytes reply = send(request, EsmState::PreOp, 24);
  // Opcode 0x82 = list response | incomplete, fragments left 3.
  EXPECT_EQ(reply, cat({0x12, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x80, 0x82, 0x00, 0x03, 0x00},
                       words({0x0001, 0x1000, 0x1001, 0x1008, 0x1018, 0x1600})));
  EXPECT_TRUE(server.has_pending());
  EXPECT_EQ(payload(poll(24)), cat({0x00, 0x80, 0x82, 0x00, 0x02, 0x00},
                                   words({0x1A00, 0x1C12, 0x1C13, 0x2000, 0x2001, 0x2002})));
  EXPECT_EQ(payload(poll(24)), cat({0x00, 0x80, 0x82, 0x00, 0x01, 0x00},
                                   words({0x2003, 0x2004, 0x2005, 0x2008, 0x2009, 0x200A})));
  const Bytes last = poll(24);
  EXPECT_EQ(mailbox_length(last), 2 + 4 + 10);
  EXPECT_EQ(payload(last), cat({0x00, 0x80, 0x02, 0x00, 0x00, 0x00},
                               words({0x200B, 0x2010, 0x6000, 0x7000, 0x8000})));
  EXPECT_TRUE(poll(24).empty());
  EXPECT_FALSE(server.has_pending());
}

TEST_F(SdoTest, OdListOfManyObjectsInA128ByteMailbox) {
  for (uint16_t i = 0; i < 200; ++i)
    od.add(var(static_cast<uint16_t>(0x3000 + i), "x", DataType::Unsigned8, 8, access::kRo));
  // 1 + 222 words = 446 bytes; 116 bytes per fragment -> 4 fragments.
  Bytes stream = payload(info({0x01, 0x00, 0x00, 0x00, 0x01, 0x00}));
  EXPECT_EQ(stream[2], 0x82);
  EXPECT_EQ(stream[4], 3);
  stream.erase(stream.begin(), stream.begin() + 6);
  for (int i = 2; i >= 0; --i) {
    Bytes f = payload(poll());
    ASSERT_GE(f.size(), 6u);
    EXPECT_EQ(f[4], i);
    EXPECT_EQ(f[2], i ? 0x82 : 0x02);
    stream.insert(stream.end(), f.begin() + 6, f.end());
  }
  ASSERT_EQ(stream.size(), 446u);
  std::vector<uint16_t> indices;
  for (size_t i = 2; i < stream.size(); i += 2)
    indices.push_back(static_cast<uint16_t>(stream[i] | (stream[i + 1] << 8)));
  EXPECT_EQ(indices.size(), od.size());
  EXPECT_TRUE(std::is_sorted(indices.begin(), indices.end()));
}

TEST_F(SdoTest, OdListLengthsAndFilteredLists) {
  // List type 0: number of objects in lists 1..5.
  EXPECT_EQ(payload(info({0x01, 0x00, 0x00, 0x00, 0x00, 0x00})),
            cat({0x00, 0x80, 0x02, 0x00, 0x00, 0x00}, words({0, 22, 1, 1, 1, 1})));
  EXPECT_EQ(payload(info({0x01, 0x00, 0x00, 0x00, 0x02, 0x00})),
            cat({0x00, 0x80, 0x02, 0x00, 0x00, 0x00}, words({2, 0x7000})));
  EXPECT_EQ(payload(info({0x01, 0x00, 0x00, 0x00, 0x03, 0x00})),
            cat({0x00, 0x80, 0x02, 0x00, 0x00, 0x00}, words({3, 0x6000})));
  EXPECT_EQ(payload(info({0x01, 0x00, 0x00, 0x00, 0x04, 0x00})),
            cat({0x00, 0x80, 0x02, 0x00, 0x00, 0x00}, words({4, 0x200B})));
  EXPECT_EQ(payload(info({0x01, 0x00, 0x00, 0x00, 0x05, 0x00})),
            cat({0x00, 0x80, 0x02, 0x00, 0x00, 0x00}, words({5, 0x200B})));
}

TEST_F(SdoTest, ObjectDescription) {
  // Index, data type, max subindex, object code (RECORD = 9), name.
  Bytes expected{0x00, 0x80, 0x04, 0x00, 0x00, 0x00, 0x18, 0x10, 0x23, 0x00, 0x04, 0x09};
  for (char c : std::string("Identity")) expected.push_back(static_cast<uint8_t>(c));
  EXPECT_EQ(payload(info({0x03, 0x00, 0x00, 0x00, 0x18, 0x10})), expected);
  // A VAR reports its value type; an ARRAY its element type.
  Bytes var_desc = payload(info({0x03, 0x00, 0x00, 0x00, 0x00, 0x10}));
  EXPECT_EQ(Bytes(var_desc.begin() + 6, var_desc.begin() + 12),
            (Bytes{0x00, 0x10, 0x07, 0x00, 0x00, 0x07}));
  Bytes arr = payload(info({0x03, 0x00, 0x00, 0x00, 0x12, 0x1C}));
  EXPECT_EQ(Bytes(arr.begin() + 6, arr.begin() + 12), (Bytes{0x12, 0x1C, 0x06, 0x00, 0x04, 0x08}));
}

TEST_F(SdoTest, EntryDescriptionWithAllValueInfo) {
  // 0x1018:01 UDINT ro, value info 0x78: unit type, default, minimum, maximum.
  Bytes expected{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x18, 0x10, 0x01, 0x78,
                 0x07, 0x00, 0x20, 0x00, 0x07, 0x00, 0x00, 0x00, 0x0B, 0x0A,
                 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF, 0xFF, 0xFF};
  for (char c : std::string("Vendor ID")) expected.push_back(static_cast<uint8_t>(c));
  EXPECT_EQ(payload(info({0x05, 0x00, 0x00, 0x00, 0x18, 0x10, 0x01, 0x78})), expected);
}

TEST_F(SdoTest, EntryDescriptionValueInfoSubsets) {
  // INT16 with its own range: min -100, max 100; access rw = 0x3F.
  Bytes d = payload(info({0x05, 0x00, 0x00, 0x00, 0x01, 0x20, 0x00, 0x60}));
  EXPECT_EQ(
      Bytes(d.begin() + 6, d.begin() + 20),
      (Bytes{0x01, 0x20, 0x00, 0x60, 0x03, 0x00, 0x10, 0x00, 0x3F, 0x00, 0x9C, 0xFF, 0x64, 0x00}));
  // No value info: straight to the name.
  d = payload(info({0x05, 0x00, 0x00, 0x00, 0x00, 0x20, 0x00, 0x00}));
  EXPECT_EQ(std::string(d.begin() + 16, d.end()), "Percent");
  // A string has no minimum/maximum: the bits come back cleared.
  d = payload(info({0x05, 0x00, 0x00, 0x00, 0x08, 0x10, 0x00, 0x60}));
  EXPECT_EQ(d[9], 0x00);
  // PDO mappable flags are part of the access word (0x0087 for ro + TxPDO).
  d = payload(info({0x05, 0x00, 0x00, 0x00, 0x00, 0x60, 0x04, 0x00}));
  EXPECT_EQ(d[14], 0x87);
  EXPECT_EQ(d[15], 0x00);
}

TEST_F(SdoTest, SdoInformationErrors) {
  EXPECT_EQ(payload(info({0x03, 0x00, 0x00, 0x00, 0x34, 0x12})),
            (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x06}));
  EXPECT_EQ(payload(info({0x05, 0x00, 0x00, 0x00, 0x18, 0x10, 0x09, 0x00})),
            (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x11, 0x00, 0x09, 0x06}));
  // Subindex 5 does not exist (MaxSub 4): 0x06090011.
  EXPECT_EQ(payload(info({0x05, 0x00, 0x00, 0x00, 0x00, 0x60, 0x05, 0x00})),
            (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x11, 0x00, 0x09, 0x06}));
  // The padding entry 0x6000:03 lies inside MaxSub and is described (ETG.1000.6 §5.6.3.6.2):
  // opcode 0x06, index, subindex 3, value info 0, BIT6 (0x0035), 6 bits, access 0, no name.
  EXPECT_EQ(payload(info({0x05, 0x00, 0x00, 0x00, 0x00, 0x60, 0x03, 0x00})),
            (Bytes{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x00, 0x60, 0x03, 0x00, 0x35, 0x00, 0x06,
                   0x00, 0x00, 0x00}));
  EXPECT_EQ(payload(info({0x09, 0x00, 0x00, 0x00})),
            (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x01, 0x00, 0x04, 0x05}));
  EXPECT_EQ(payload(info({0x01, 0x00, 0x00, 0x00, 0x06, 0x00})),
            (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x06}));
}

TEST_F(SdoTest, LongDescriptionIsFragmented) {
  const std::string name(200, 'n');
  od.add(var(0x3000, name, DataType::Unsigned8, 8, access::kRo));
  // 64-byte mailbox: 52 bytes per fragment; 6 + 200 = 206 bytes -> 4 fragments.
  Bytes f = payload(info({0x03, 0x00, 0x00, 0x00, 0x00, 0x30}, 64));
  EXPECT_EQ(f[2], 0x84);
  EXPECT_EQ(f[4], 3);
  Bytes all(f.begin() + 6, f.end());
  while (server.has_pending()) {
    f = payload(poll(64));
    all.insert(all.end(), f.begin() + 6, f.end());
  }
  EXPECT_EQ(f[2], 0x04);
  ASSERT_EQ(all.size(), 206u);
  EXPECT_EQ(std::string(all.begin() + 6, all.end()), name);
}

TEST_F(SdoTest, MasterErrorRequestOrNewRequestStopsFragments) {
  info({0x01, 0x00, 0x00, 0x00, 0x01, 0x00}, 24);
  EXPECT_TRUE(server.has_pending());
  // SDO Information error request from the master: no reply, no more fragments.
  EXPECT_TRUE(info({0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x08}, 24).empty());
  EXPECT_FALSE(server.has_pending());
  info({0x01, 0x00, 0x00, 0x00, 0x01, 0x00}, 24);
  sdo(upload_req(0x1000, 0), EsmState::PreOp, 24);
  EXPECT_FALSE(server.has_pending());
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, OdListLengthsFragmentInTheSmallestMailbox) {
  // A 16-byte mailbox leaves 4 bytes per fragment: list type 0 + 5 counts = 12 bytes = 3.
  Bytes f = payload(info({0x01, 0x00, 0x00, 0x00, 0x00, 0x00}, 16));
  EXPECT_EQ(f, (Bytes{0x00, 0x80, 0x82, 0x00, 0x02, 0x00, 0x00, 0x00, 22, 0x00}));
  EXPECT_EQ(payload(poll(16)), (Bytes{0x00, 0x80, 0x82, 0x00, 0x01, 0x00, 1, 0, 1, 0}));
  EXPECT_EQ(payload(poll(16)), (Bytes{0x00, 0x80, 0x02, 0x00, 0x00, 0x00, 1, 0, 1, 0}));
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, EntryDescriptionDefaultOfAnEntryWithoutDefaultIsZero) {
  // 0x2009 has no default value: the default field is the entry's size in zeros.
  const Bytes d = payload(info({0x05, 0x00, 0x00, 0x00, 0x09, 0x20, 0x00, 0x10}));
  EXPECT_EQ(Bytes(d.begin() + 6, d.begin() + 17),
            (Bytes{0x09, 0x20, 0x00, 0x10, 0x05, 0x00, 0x08, 0x00, 0x3F, 0x00, 0x00}));
  EXPECT_EQ(std::string(d.begin() + 17, d.end()), "Hooked");
}

}  // namespace
}  // namespace rackcat::coe::test
