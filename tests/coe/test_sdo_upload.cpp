// SDO upload golden vectors (ETG.1000.6 §5.6.2.4 - §5.6.2.6, Tables 37-42).
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, ExpeditedUploadGoldenBytes) {
  // Master: upload 0x1018:01 with mailbox counter 1.
  const Bytes request{0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20,
                      0x40, 0x18, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00};
  // Slave: SDO response (0x3000), 0x43 = expedited, size indicated, 4 bytes; our counter 1.
  const Bytes expected{0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x30,
                       0x43, 0x18, 0x10, 0x01, 0x0B, 0x0A, 0x00, 0x00};
  EXPECT_EQ(send(request), expected);
}

TEST_F(SdoTest, ExpeditedUploadSizeBitsForOneAndTwoBytes) {
  EXPECT_EQ(payload(sdo(upload_req(0x2000, 0))),
            (Bytes{0x00, 0x30, 0x4F, 0x00, 0x20, 0x00, 0x32, 0x00, 0x00, 0x00}));
  EXPECT_EQ(payload(sdo(upload_req(0x1C12, 1))),
            (Bytes{0x00, 0x30, 0x4B, 0x12, 0x1C, 0x01, 0x00, 0x16, 0x00, 0x00}));
  // Subindex 0 of an ARRAY is one byte on its own.
  EXPECT_EQ(payload(sdo(upload_req(0x1C12, 0))),
            (Bytes{0x00, 0x30, 0x4F, 0x12, 0x1C, 0x00, 0x01, 0x00, 0x00, 0x00}));
}

TEST_F(SdoTest, UploadOfABitEntryInsideARecord) {
  od.find(0x6000)->set_u(2, 1);
  EXPECT_EQ(payload(sdo(upload_req(0x6000, 2))),
            (Bytes{0x00, 0x30, 0x4F, 0x00, 0x60, 0x02, 0x01, 0x00, 0x00, 0x00}));
  EXPECT_EQ(payload(sdo(upload_req(0x6000, 1))),
            (Bytes{0x00, 0x30, 0x4F, 0x00, 0x60, 0x01, 0x00, 0x00, 0x00, 0x00}));
}

TEST_F(SdoTest, NormalUploadCarriesCompleteSizeAndData) {
  const Bytes r = sdo(upload_req(0x1008, 0));
  Bytes expected{0x00, 0x30, 0x41, 0x08, 0x10, 0x00, 0x10, 0x00, 0x00,
                 0x00, 'r',  'a',  'c',  'k',  'c',  'a',  't'};
  expected.resize(10 + 16, 0x00);
  EXPECT_EQ(mailbox_length(r), 26);
  EXPECT_EQ(payload(r), expected);
}

TEST_F(SdoTest, SegmentedUploadOf255BytesThrough128ByteMailbox) {
  const Object& text = *od.find(0x2002);
  const Bytes value(text.image().begin(), text.image().end());
  ASSERT_EQ(value.size(), 255u);

  // Initiate response: normal, complete size 255, the first 128 - 16 = 112 bytes.
  Bytes r = sdo(upload_req(0x2002, 0));
  ASSERT_EQ(r.size(), 128u);
  EXPECT_EQ(mailbox_length(r), 122);
  Bytes head{0x00, 0x30, 0x41, 0x02, 0x20, 0x00, 0xFF, 0x00, 0x00, 0x00};
  EXPECT_EQ(Bytes(r.begin() + 6, r.begin() + 16), head);
  Bytes got(r.begin() + 16, r.end());

  // Segment 1 (toggle 0): 119 bytes fill the mailbox, not last.
  r = sdo({0x60, 0, 0, 0, 0, 0, 0, 0});
  ASSERT_EQ(r.size(), 128u);
  EXPECT_EQ(r[6], 0x00);
  EXPECT_EQ(r[7], 0x30);
  EXPECT_EQ(r[8], 0x00);  // scs 0, toggle 0, more follows
  got.insert(got.end(), r.begin() + 9, r.end());

  // Segment 2 (toggle 1): the last 24 bytes, last-segment flag.
  r = sdo({0x70, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(mailbox_length(r), 3 + 24);
  EXPECT_EQ(r[8], 0x11);
  got.insert(got.end(), r.begin() + 9, r.end());
  EXPECT_EQ(got, value);

  // The transfer is over: another segment request is an unknown command now.
  EXPECT_EQ(payload(sdo({0x60, 0, 0, 0, 0, 0, 0, 0})), abort_payload(0, 0, 0x05040001));
}

TEST_F(SdoTest, ShortLastSegmentPadsToSevenBytesWithCount) {
  // 0x2002 (255 bytes) through a 22-byte mailbox: 6 bytes in the initiate response, then
  // 13-byte segments: 6 + 19 * 13 = 253, the last segment carries 2 bytes, padded to 7 with
  // n = 5 in bits 1-3.
  Bytes r = sdo(upload_req(0x2002, 0), EsmState::PreOp, 22);
  ASSERT_EQ(r.size(), 22u);
  uint8_t toggle = 0;
  for (int i = 0; i < 19; ++i) {
    r = sdo({static_cast<uint8_t>(0x60 | toggle), 0, 0, 0, 0, 0, 0, 0}, EsmState::PreOp, 22);
    ASSERT_EQ(r.size(), 22u);
    EXPECT_EQ(r[8], toggle);
    toggle ^= 0x10;
  }
  r = sdo({static_cast<uint8_t>(0x60 | toggle), 0, 0, 0, 0, 0, 0, 0}, EsmState::PreOp, 22);
  EXPECT_EQ(mailbox_length(r), 10);
  EXPECT_EQ(r[8], static_cast<uint8_t>(toggle | (5 << 1) | 0x01));
  EXPECT_EQ(Bytes(r.begin() + 11, r.end()), Bytes(5, 0x00));
}

TEST_F(SdoTest, WrongToggleAbortsTheUpload) {
  sdo(upload_req(0x2002, 0));
  EXPECT_EQ(payload(sdo({0x70, 0, 0, 0, 0, 0, 0, 0})), abort_payload(0x2002, 0, 0x05030000));
  // The transfer is gone after the abort.
  EXPECT_EQ(payload(sdo({0x60, 0, 0, 0, 0, 0, 0, 0})), abort_payload(0, 0, 0x05040001));
}

TEST_F(SdoTest, UploadAborts) {
  EXPECT_EQ(payload(sdo(upload_req(0x1234, 0))), abort_payload(0x1234, 0, 0x06020000));
  EXPECT_EQ(payload(sdo(upload_req(0x1018, 9))), abort_payload(0x1018, 9, 0x06090011));
  // A padding entry is never addressed by SDO.
  EXPECT_EQ(payload(sdo(upload_req(0x6000, 3))), abort_payload(0x6000, 3, 0x06090011));
  EXPECT_EQ(payload(sdo(upload_req(0x2004, 0))), abort_payload(0x2004, 0, 0x06010001));
  // INIT and BOOT have no SDO access: wrong state.
  EXPECT_EQ(payload(sdo(upload_req(0x1000, 0), EsmState::Boot)),
            abort_payload(0x1000, 0, 0x08000022));
}

TEST_F(SdoTest, ObjectsAddedWithoutPrepareAbortWithOutOfMemory) {
  // The transfer buffers are sized at start-up; a larger object added later (without
  // prepare()) cannot be snapshotted for a segmented upload.
  od.add(var(0x5000, "Huge", DataType::OctetString, 8 * 4000, access::kRo));
  EXPECT_EQ(payload(sdo(upload_req(0x5000, 0))), abort_payload(0x5000, 0, 0x05040005));
  server.prepare();
  const Bytes r = sdo(upload_req(0x5000, 0));
  EXPECT_EQ(r[8], 0x41);
}

TEST_F(SdoTest, BeforeReadHookRefreshesLiveValue) {
  int calls = 0;
  od.find(0x1001)->edit_hooks().before_read = [&](Object& o, int sub) {
    ++calls;
    EXPECT_EQ(sub, 0);
    o.set_u(0, 0x81);
  };
  EXPECT_EQ(payload(sdo(upload_req(0x1001, 0)))[6], 0x81);
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST(SdoServerEmpty, NoDictionaryAbort) {
  ObjectDictionary empty;
  SdoServer server(empty);
  const Bytes request = coe_message(1, 2, upload_req(0x1000, 0));
  Bytes reply(128);
  rackcat::testing::SlaveMailbox frame;
  reply.resize(frame.request(request, reply, [&](auto data, size_t, auto out) {
    return server.handle(data, out, EsmState::PreOp);
  }));
  EXPECT_EQ(payload(reply), abort_payload(0x1000, 0, 0x08000023));
}

}  // namespace
}  // namespace rackcat::coe::test
