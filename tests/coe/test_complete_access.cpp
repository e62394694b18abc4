// Complete access (ETG.1000.6 §5.6.2.1.4 / §5.6.2.4): subindex 0 in 16 bits, gaps, segmented
// transfers both ways.
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, CompleteAccessReadOfPdoAssignGoldenBytes) {
  // 0x1C12 with one entry 0x1600 reads 01 00 00 16 (sub0 = 1 plus 8 bits padding, 0x1600).
  const Bytes request{0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20,
                      0x50, 0x12, 0x1C, 0x00, 0x00, 0x00, 0x00, 0x00};
  const Bytes expected{0x0E, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x30, 0x51, 0x12,
                       0x1C, 0x00, 0x04, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x16};
  EXPECT_EQ(send(request), expected);
}

TEST_F(SdoTest, CompleteAccessFromSubindexOneSkipsSubindexZero) {
  EXPECT_EQ(payload(sdo(upload_req(0x1C12, 1, true))),
            (Bytes{0x00, 0x30, 0x51, 0x12, 0x1C, 0x01, 0x02, 0x00, 0x00, 0x00, 0x00, 0x16}));
  // Mapping 0x1600 with two entries in use of four.
  EXPECT_EQ(payload(sdo(upload_req(0x1600, 0, true))),
            (Bytes{0x00, 0x30, 0x51, 0x00, 0x16, 0x00, 0x0A, 0x00, 0x00, 0x00,
                   0x02, 0x00, 0x10, 0x01, 0x00, 0x70, 0x08, 0x02, 0x00, 0x70}));
}

TEST_F(SdoTest, CompleteAccessReadOfARecordWithGaps) {
  Object& in = *od.find(0x6000);
  in.set_u(1, 1);
  in.set_u(4, 0x1234);
  // Stray bits in the gap and the padding entry never reach the wire.
  in.image()[2] |= 0x20;
  in.image()[3] = 0xFF;
  // sub0 = 4 + pad | bit 0 = Input 1, bit 1 = Input 2, bits 2-7 padding | gap byte | 0x1234
  EXPECT_EQ(payload(sdo(upload_req(0x6000, 0, true))),
            (Bytes{0x00, 0x30, 0x51, 0x00, 0x60, 0x00, 0x06, 0x00, 0x00, 0x00, 0x04, 0x00, 0x01,
                   0x00, 0x34, 0x12}));
}

TEST_F(SdoTest, CompleteAccessWriteOfPdoAssign) {
  // sub0 = 2, 0x1600, 0x1601 (the last entry need not exist for the assign object itself).
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, {0x02, 0x00, 0x00, 0x16, 0x01, 0x16}, true))),
            download_ok(0x1C12, 0, true));
  const Object& a = *od.find(0x1C12);
  EXPECT_EQ(a.sub0(), 2);
  EXPECT_EQ(a.get_u(2), 0x1601u);
  // Clearing with sub0 = 0 (expedited, 2 bytes) leaves the entries as they are.
  EXPECT_EQ(payload(sdo(download_expedited(0x1C12, 0, 0x0000, 2, true))),
            download_ok(0x1C12, 0, true));
  EXPECT_EQ(a.sub0(), 0);
  EXPECT_EQ(a.get_u(1), 0x1600u);
}

TEST_F(SdoTest, CompleteAccessWriteFromSubindexOneUsesCurrentCount) {
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 1, {0x02, 0x16}, true))),
            download_ok(0x1C12, 1, true));
  EXPECT_EQ(od.find(0x1C12)->get_u(1), 0x1602u);
  EXPECT_EQ(od.find(0x1C12)->sub0(), 1);
}

TEST_F(SdoTest, CompleteAccessWriteChecks) {
  // Too short for two entries, longer than the whole object, more entries than exist.
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, {0x02, 0x00, 0x00, 0x16}, true))),
            abort_payload(0x1C12, 0, 0x06070013));
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, Bytes(11, 0x00), true))),
            abort_payload(0x1C12, 0, 0x06070012));
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, {0x05, 0x00, 0x00, 0x16}, true))),
            abort_payload(0x1C12, 0, 0x06090031));
  // Changing entries outside PREOP: wrong state; writing back what is there: accepted.
  EXPECT_EQ(
      payload(sdo(download_normal(0x1C12, 0, {0x01, 0x00, 0x01, 0x16}, true), EsmState::SafeOp)),
      abort_payload(0x1C12, 0, 0x08000022));
  EXPECT_EQ(
      payload(sdo(download_normal(0x1C12, 0, {0x01, 0x00, 0x00, 0x16}, true), EsmState::SafeOp)),
      download_ok(0x1C12, 0, true));
  // Read-only record.
  Bytes identity{0x04, 0x00, 0x0C, 0x0A, 0, 0,    0x78, 0x56, 0x34,
                 0x12, 2,    0,    1,    0, 0xBE, 0xBA, 0xFE, 0xCA};
  EXPECT_EQ(payload(sdo(download_normal(0x1018, 0, identity, true))),
            abort_payload(0x1018, 0, 0x06010002));
  EXPECT_EQ(od.find(0x1018)->get_u(1), 0x0A0Bu);
  // Not on a VAR, only from subindex 0 or 1.
  EXPECT_EQ(payload(sdo(upload_req(0x1000, 0, true))), abort_payload(0x1000, 0, 0x06010004));
  EXPECT_EQ(payload(sdo(download_expedited(0x2000, 0, 1, 1, true))),
            abort_payload(0x2000, 0, 0x06010004));
  EXPECT_EQ(payload(sdo(upload_req(0x1C12, 2, true))), abort_payload(0x1C12, 2, 0x06010000));
}

TEST_F(SdoTest, CompleteAccessHookSeesTheWholeCandidateImage) {
  Object& a = *od.find(0x1C12);
  a.edit_hooks().validate_write = [](const Object&, int sub, std::span<const uint8_t> data,
                                     EsmState) {
    EXPECT_EQ(sub, -1);
    EXPECT_EQ(data.size(), 10u);  // the image from subindex 0, also for a write from 1
    return data[2] == 0x99 ? AbortCode::ParameterIncompatible : AbortCode::None;
  };
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 1, {0x99, 0x16}, true))),
            abort_payload(0x1C12, 1, 0x06040043));
  EXPECT_EQ(a.get_u(1), 0x1600u);
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 1, {0x01, 0x16}, true))),
            download_ok(0x1C12, 1, true));
}

TEST_F(SdoTest, SegmentedCompleteAccessBothWays) {
  // 0x8000: sub0 (16 bits) + 100 UDINTs = 402 bytes through a 128-byte mailbox.
  Bytes r = sdo(upload_req(0x8000, 0, true));
  ASSERT_EQ(r.size(), 128u);
  EXPECT_EQ(Bytes(r.begin() + 6, r.begin() + 16),
            (Bytes{0x00, 0x30, 0x51, 0x00, 0x80, 0x00, 0x92, 0x01, 0x00, 0x00}));
  Bytes got(r.begin() + 16, r.end());
  uint8_t toggle = 0;
  for (;;) {
    r = sdo({static_cast<uint8_t>(0x60 | toggle), 0, 0, 0, 0, 0, 0, 0});
    ASSERT_GE(r.size(), 16u);
    ASSERT_EQ(r[8] & 0x10, toggle);
    got.insert(got.end(), r.begin() + 9, r.end());
    toggle ^= 0x10;
    if (r[8] & 0x01) break;
  }
  ASSERT_EQ(got.size(), 402u);
  Bytes expected{100, 0};
  for (uint32_t i = 0; i < 100; ++i) {
    const uint32_t v = 0x01000000u + i;
    for (int k = 0; k < 4; ++k) expected.push_back(static_cast<uint8_t>(v >> (8 * k)));
  }
  EXPECT_EQ(got, expected);

  // Write it back changed, segmented: 112 bytes in the initiate, then 119-byte segments.
  for (size_t i = 2; i < expected.size(); i += 4) expected[i] = 0x55;
  Bytes init = download_normal(0x8000, 0, Bytes(expected.begin(), expected.begin() + 112), true,
                               expected.size());
  EXPECT_EQ(payload(sdo(init)), download_ok(0x8000, 0, true));
  size_t pos = 112;
  toggle = 0;
  while (pos < expected.size()) {
    const size_t n = std::min<size_t>(119, expected.size() - pos);
    const bool last = pos + n == expected.size();
    Bytes seg{static_cast<uint8_t>(toggle | (last ? 1 : 0))};
    seg.insert(seg.end(), expected.begin() + pos, expected.begin() + pos + n);
    EXPECT_EQ(payload(sdo(seg)),
              (Bytes{0x00, 0x30, static_cast<uint8_t>(0x20 | toggle), 0, 0, 0, 0, 0, 0, 0}));
    pos += n;
    toggle ^= 0x10;
  }
  EXPECT_EQ(od.find(0x8000)->get_u(1), 0x01000055u);
  EXPECT_EQ(od.find(0x8000)->get_u(100), 0x01000055u);
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, CompleteAccessReadChecksEveryEntryInUse) {
  // A RECORD with a write-only entry cannot be read as a whole.
  Object o(0x3000, ObjectCode::Record, "Mixed");
  o.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, access::kRo, {2}));
  o.add(entry(1, "Readable", DataType::Unsigned8, 8, access::kRw));
  o.add(entry(2, "Secret", DataType::Unsigned8, 8, access::kWo));
  od.add(std::move(o));
  EXPECT_EQ(payload(sdo(upload_req(0x3000, 0, true))), abort_payload(0x3000, 0, 0x06010001));
  // With only subindex 1 in use, it can.
  od.find(0x3000)->set_u(0, 1);
  EXPECT_EQ(payload(sdo(upload_req(0x3000, 0, true))),
            (Bytes{0x00, 0x30, 0x51, 0x00, 0x30, 0x00, 0x03, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00}));
  // A readable-in-PREOP-only entry: wrong state in OP.
  Object p(0x3001, ObjectCode::Record, "Preop read");
  p.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, access::kRo, {1}));
  p.add(entry(1, "Value", DataType::Unsigned8, 8, access::kReadPreOp));
  od.add(std::move(p));
  EXPECT_EQ(payload(sdo(upload_req(0x3001, 0, true), EsmState::Op)),
            abort_payload(0x3001, 0, 0x08000022));
}

TEST_F(SdoTest, CompleteAccessOfAnEmptyArrayFromSubindexOne) {
  od.find(0x1C12)->set_u(0, 0);
  // Nothing in use: a normal response with complete size 0.
  EXPECT_EQ(payload(sdo(upload_req(0x1C12, 1, true))),
            (Bytes{0x00, 0x30, 0x51, 0x12, 0x1C, 0x01, 0x00, 0x00, 0x00, 0x00}));
  EXPECT_EQ(payload(sdo(upload_req(0x1C12, 0, true))),
            (Bytes{0x00, 0x30, 0x51, 0x12, 0x1C, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00}));
}

}  // namespace
}  // namespace rackcat::coe::test
