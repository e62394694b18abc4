// SDO download golden vectors and every write check (ETG.1000.6 §5.6.2.1 - §5.6.2.3,
// abort codes of Table 41 / the guide's Appendix C).
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, ExpeditedDownloadGoldenBytes) {
  // Master: download 0x2000:00 = 0x05 (1 byte: 0x2F), counter 1.
  const Bytes request{0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20,
                      0x2F, 0x00, 0x20, 0x00, 0x05, 0x00, 0x00, 0x00};
  const Bytes expected{0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x30,
                       0x60, 0x00, 0x20, 0x00, 0x00, 0x00, 0x00, 0x00};
  EXPECT_EQ(send(request), expected);
  EXPECT_EQ(od.find(0x2000)->get_u(0), 5u);
}

TEST_F(SdoTest, ExpeditedDownloadWithoutSizeUsesTheEntryLength) {
  // 0x22: expedited, size not indicated: 4 data bytes, the entry takes its own 1 byte.
  EXPECT_EQ(payload(sdo({0x22, 0x00, 0x20, 0x00, 0x07, 0x00, 0x00, 0x00})), download_ok(0x2000, 0));
  EXPECT_EQ(od.find(0x2000)->get_u(0), 7u);
}

TEST_F(SdoTest, NormalDownloadAndShorterVisibleString) {
  // Normal download of 3 bytes into the 255-byte VISIBLE_STRING: allowed, padded with 0.
  EXPECT_EQ(payload(sdo(download_normal(0x2002, 0, {'a', 'b', 'c'}))), download_ok(0x2002, 0));
  EXPECT_EQ(od.find(0x2002)->get_string(0), "abc");
  EXPECT_EQ(od.find(0x2002)->image()[200], 0);
  // A normal download of a UDINT.
  EXPECT_EQ(payload(sdo(download_normal(0x200A, 0, {1, 2, 3, 4}))), download_ok(0x200A, 0));
  EXPECT_EQ(od.find(0x200A)->get_u(0), 0x04030201u);
}

TEST_F(SdoTest, SegmentedDownloadOf255Bytes) {
  Bytes text(255);
  for (size_t i = 0; i < text.size(); ++i) text[i] = static_cast<uint8_t>('a' + i % 26);
  // Initiate with complete size 255 and the first 112 bytes (a 128-byte mailbox).
  Bytes first(text.begin(), text.begin() + 112);
  EXPECT_EQ(payload(sdo(download_normal(0x2002, 0, first, false, 255))), download_ok(0x2002, 0));
  EXPECT_NE(od.find(0x2002)->image()[0], 'a');  // nothing committed before the last segment
  // Segment 1: toggle 0, 119 bytes. Response 0x20.
  Bytes seg1{0x00};
  seg1.insert(seg1.end(), text.begin() + 112, text.begin() + 231);
  EXPECT_EQ(payload(sdo(seg1)), (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
  // Segment 2: toggle 1, last, 24 bytes. Response 0x30.
  Bytes seg2{0x11};
  seg2.insert(seg2.end(), text.begin() + 231, text.end());
  EXPECT_EQ(payload(sdo(seg2)), (Bytes{0x00, 0x30, 0x30, 0, 0, 0, 0, 0, 0, 0}));
  const auto img = od.find(0x2002)->image();
  EXPECT_EQ(Bytes(img.begin(), img.end()), text);
}

TEST_F(SdoTest, MinimumSegmentUsesTheUnusedByteCount) {
  // 10 bytes to the string: 3 in the initiate (mailbox length 13), then a minimum segment with
  // 7 bytes of which n = 0 unused, last.
  Bytes init = download_normal(0x2002, 0, {'0', '1', '2'}, false, 10);
  EXPECT_EQ(payload(sdo(init)), download_ok(0x2002, 0));
  // 0x01 | (0 << 1): 7 bytes, last, toggle 0.
  EXPECT_EQ(payload(sdo({0x01, '3', '4', '5', '6', '7', '8', '9'})),
            (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(od.find(0x2002)->get_string(0), "0123456789");
  // Now 5 bytes: 3 + a segment of 2 data bytes (n = 5: 0x0B).
  EXPECT_EQ(payload(sdo(download_normal(0x2002, 0, {'x', 'y', 'z'}, false, 5))),
            download_ok(0x2002, 0));
  EXPECT_EQ(payload(sdo({0x0B, 'u', 'v', 0, 0, 0, 0, 0})),
            (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(od.find(0x2002)->get_string(0), "xyzuv");
}

TEST_F(SdoTest, SegmentedDownloadErrors) {
  // Wrong toggle.
  sdo(download_normal(0x2002, 0, {'a'}, false, 20));
  EXPECT_EQ(payload(sdo({0x10, 1, 2, 3, 4, 5, 6, 7})), abort_payload(0x2002, 0, 0x05030000));
  // More data than announced.
  sdo(download_normal(0x2002, 0, {'a'}, false, 5));
  EXPECT_EQ(payload(sdo({0x00, 1, 2, 3, 4, 5, 6, 7})), abort_payload(0x2002, 0, 0x06070010));
  // Last segment before the announced size.
  sdo(download_normal(0x2002, 0, {'a'}, false, 20));
  EXPECT_EQ(payload(sdo({0x01, 1, 2, 3, 4, 5, 6, 7})), abort_payload(0x2002, 0, 0x06070010));
  // A segment with no transfer.
  EXPECT_EQ(payload(sdo({0x00, 1, 2, 3, 4, 5, 6, 7})), abort_payload(0, 0, 0x05040001));
  // Announced size beyond the entry: refused at the initiate.
  EXPECT_EQ(payload(sdo(download_normal(0x2002, 0, {'a'}, false, 300))),
            abort_payload(0x2002, 0, 0x06070012));
  EXPECT_EQ(od.find(0x2002)->image()[0], 'A');  // unchanged throughout
}

TEST_F(SdoTest, NewInitiateAbortsAStaleTransfer) {
  sdo(download_normal(0x2002, 0, {'a'}, false, 20));
  // The master gives up silently and starts over with an upload: served normally.
  EXPECT_EQ(payload(sdo(upload_req(0x2000, 0)))[2], 0x4F);
  // The old download is gone: its next segment is an unknown command.
  EXPECT_EQ(payload(sdo({0x00, 1, 2, 3, 4, 5, 6, 7})), abort_payload(0, 0, 0x05040001));
}

TEST_F(SdoTest, AbortRequestFromMasterEndsTransferWithoutReply) {
  sdo(upload_req(0x2002, 0));
  EXPECT_TRUE(sdo({0x80, 0x02, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05}).empty());
  EXPECT_EQ(payload(sdo({0x60, 0, 0, 0, 0, 0, 0, 0})), abort_payload(0, 0, 0x05040001));
}

TEST_F(SdoTest, WriteAccessPerState) {
  // Read-only in every state.
  EXPECT_EQ(payload(sdo(download_expedited(0x1018, 1, 1, 4))),
            abort_payload(0x1018, 1, 0x06010002));
  // ro,wr_op: written in OP only.
  EXPECT_EQ(payload(sdo(download_expedited(0x2003, 0, 1, 4), EsmState::PreOp)),
            abort_payload(0x2003, 0, 0x08000022));
  EXPECT_EQ(payload(sdo(download_expedited(0x2003, 0, 1, 4), EsmState::Op)),
            download_ok(0x2003, 0));
  // ro,wr_preop: refused in SAFEOP and OP.
  EXPECT_EQ(payload(sdo(download_expedited(0x200A, 0, 1, 4), EsmState::SafeOp)),
            abort_payload(0x200A, 0, 0x08000022));
  EXPECT_EQ(payload(sdo(download_expedited(0x200A, 0, 1, 4), EsmState::Op)),
            abort_payload(0x200A, 0, 0x08000022));
  // Write-only: written, never read.
  EXPECT_EQ(payload(sdo(download_expedited(0x2004, 0, 0xBEEF, 2))), download_ok(0x2004, 0));
  EXPECT_EQ(od.find(0x2004)->get_u(0), 0xBEEFu);
}

TEST_F(SdoTest, LengthAborts) {
  EXPECT_EQ(payload(sdo(download_expedited(0x2000, 0, 0x0101, 2))),
            abort_payload(0x2000, 0, 0x06070012));
  EXPECT_EQ(payload(sdo(download_expedited(0x200A, 0, 1, 1))),
            abort_payload(0x200A, 0, 0x06070013));
  EXPECT_EQ(payload(sdo(download_normal(0x200A, 0, {1, 2, 3, 4, 5}))),
            abort_payload(0x200A, 0, 0x06070012));
  EXPECT_EQ(od.find(0x200A)->get_u(0), 0u);
}

TEST_F(SdoTest, ValueAborts) {
  EXPECT_EQ(payload(sdo(download_expedited(0x2000, 0, 101, 1))),
            abort_payload(0x2000, 0, 0x06090031));
  EXPECT_EQ(payload(sdo(download_expedited(0x2000, 0, 0, 1))),
            abort_payload(0x2000, 0, 0x06090032));
  EXPECT_EQ(payload(sdo(download_expedited(0x2001, 0, static_cast<uint16_t>(-101), 2))),
            abort_payload(0x2001, 0, 0x06090032));
  EXPECT_EQ(payload(sdo(download_expedited(0x2001, 0, static_cast<uint16_t>(-100), 2))),
            download_ok(0x2001, 0));
  EXPECT_EQ(od.find(0x2001)->get_i(0), -100);
  // An enumeration accepts its values only (DT0800EN04 has 0..8).
  EXPECT_EQ(payload(sdo(download_expedited(0x2005, 0, 9, 1))),
            abort_payload(0x2005, 0, 0x06090030));
  EXPECT_EQ(payload(sdo(download_expedited(0x2005, 0, 8, 1))), download_ok(0x2005, 0));
  // A BOOLEAN is 0 or 1.
  EXPECT_EQ(payload(sdo(download_expedited(0x2010, 0, 2, 1))),
            abort_payload(0x2010, 0, 0x06090030));
  // Paired limits: the maximum may not go below the minimum, nor the minimum above it.
  EXPECT_EQ(payload(sdo(download_expedited(0x2008, 2, 5, 2))),
            abort_payload(0x2008, 2, 0x06090036));
  EXPECT_EQ(payload(sdo(download_expedited(0x2008, 1, 25, 2))),
            abort_payload(0x2008, 1, 0x06090036));
  EXPECT_EQ(payload(sdo(download_expedited(0x2008, 2, 10, 2))), download_ok(0x2008, 2));
  // Subindex 0 of an ARRAY: never more than the entries that exist.
  EXPECT_EQ(payload(sdo(download_expedited(0x1C12, 0, 5, 1))),
            abort_payload(0x1C12, 0, 0x06090031));
}

TEST_F(SdoTest, AddressingAborts) {
  EXPECT_EQ(payload(sdo(download_expedited(0x1234, 0, 1, 1))),
            abort_payload(0x1234, 0, 0x06020000));
  EXPECT_EQ(payload(sdo(download_expedited(0x2000, 1, 1, 1))),
            abort_payload(0x2000, 1, 0x06090011));
  // Block download (ccs 6) does not exist in CoE.
  EXPECT_EQ(payload(sdo({0xC0, 0x00, 0x20, 0x00, 0, 0, 0, 0})),
            abort_payload(0x2000, 0, 0x05040001));
}

TEST_F(SdoTest, HooksValidateAndObserveWrites) {
  int after = 0;
  Object& o = *od.find(0x2009);
  o.edit_hooks().validate_write = [](const Object&, int sub, std::span<const uint8_t> data,
                                     EsmState) {
    EXPECT_EQ(sub, 0);
    if (data[0] == 0x42) return AbortCode::HardwareError;
    if (data[0] == 0x43) return AbortCode::LocalControl;
    if (data[0] == 0x44) return AbortCode::CannotTransfer;
    if (data[0] == 0x45) return AbortCode::GeneralError;
    return AbortCode::None;
  };
  o.edit_hooks().after_write = [&](Object&, int) { ++after; };
  EXPECT_EQ(payload(sdo(download_expedited(0x2009, 0, 0x42, 1))),
            abort_payload(0x2009, 0, 0x06060000));
  EXPECT_EQ(payload(sdo(download_expedited(0x2009, 0, 0x43, 1))),
            abort_payload(0x2009, 0, 0x08000021));
  EXPECT_EQ(payload(sdo(download_expedited(0x2009, 0, 0x44, 1))),
            abort_payload(0x2009, 0, 0x08000020));
  EXPECT_EQ(payload(sdo(download_expedited(0x2009, 0, 0x45, 1))),
            abort_payload(0x2009, 0, 0x08000000));
  EXPECT_EQ(after, 0);
  EXPECT_EQ(o.get_u(0), 0u);
  EXPECT_EQ(payload(sdo(download_expedited(0x2009, 0, 0x01, 1))), download_ok(0x2009, 0));
  EXPECT_EQ(after, 1);
  EXPECT_EQ(o.get_u(0), 1u);
}

TEST_F(SdoTest, WriteOfABitEntryKeepsItsNeighbours) {
  Object& flags = *od.find(0x2010);
  EXPECT_EQ(payload(sdo(download_expedited(0x2010, 0, 1, 1))), download_ok(0x2010, 0));
  EXPECT_EQ(flags.get_u(0), 1u);
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, WritesToObjectsLargerThanThePreparedBuffersAbortCleanly) {
  // Added after the server was built and without prepare(): the staging buffers are too small.
  std::vector<uint64_t> values(1000, 0);
  od.add(
      array(0x5000, "Big", DataType::Unsigned32, 32, 250, access::kRw, access::kRw, values, 250));
  od.add(var(0x5001, "Big string", DataType::OctetString, 8 * 2000, access::kRw));
  EXPECT_EQ(payload(sdo(download_normal(0x5000, 0, {0x00, 0x00}, true))),
            abort_payload(0x5000, 0, 0x05040005));
  EXPECT_EQ(payload(sdo(download_normal(0x5001, 0, Bytes(100, 1), false, 2000))),
            abort_payload(0x5001, 0, 0x05040005));
  const Bytes d = payload(info({0x05, 0x00, 0x00, 0x00, 0x01, 0x50, 0x00, 0x10}));
  EXPECT_EQ(d[9], 0x00);  // no room for a 2000-byte default: value info cleared
  server.prepare();
  EXPECT_EQ(payload(sdo(download_normal(0x5000, 0, {0x00, 0x00}, true))),
            download_ok(0x5000, 0, true));
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, ValuesLargerThanTheStackScratchUseTheReservedBuffers) {
  // A request's candidate value and image sit on the stack up to SdoServer::kStackScratch
  // bytes; larger objects stage in buffers prepare() reserves. Same answers either way.
  static_assert(SdoServer::kStackScratch < 5000);
  od.add(var(0x5002, "Huge", DataType::OctetString, 8 * 5000, access::kRw));
  Object rec(0x5003, ObjectCode::Record, "Huge record");
  rec.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, access::kReadAll, {2}));
  rec.add(entry(1, "Blob", DataType::OctetString, 8 * 5000, access::kRw));
  rec.add(entry(2, "Word", DataType::Unsigned16, 16, access::kRw));
  rec.finalize();
  od.add(std::move(rec));
  server.prepare();

  Bytes blob(5000);
  for (size_t i = 0; i < blob.size(); ++i) blob[i] = static_cast<uint8_t>(i * 7 + 3);
  constexpr size_t kMailbox = 8192;  // the whole value in one normal transfer
  EXPECT_EQ(payload(sdo(download_normal(0x5002, 0, blob), EsmState::PreOp, kMailbox)),
            download_ok(0x5002, 0));
  const auto image = od.find(0x5002)->image();
  EXPECT_TRUE(std::equal(blob.begin(), blob.end(), image.begin(), image.end()));
  const Bytes up = payload(sdo(upload_req(0x5002, 0), EsmState::PreOp, kMailbox));
  ASSERT_EQ(up.size(), 10u + blob.size());
  EXPECT_EQ(up[2], 0x41);  // normal upload response, size indicated
  EXPECT_TRUE(std::equal(blob.begin(), blob.end(), up.begin() + 10));

  // Complete access from subindex 1: the 5002-byte candidate image and the 5000-byte entry.
  Bytes ca(blob.rbegin(), blob.rend());
  ca.push_back(0x34);
  ca.push_back(0x12);
  EXPECT_EQ(payload(sdo(download_normal(0x5003, 1, ca, true), EsmState::PreOp, kMailbox)),
            download_ok(0x5003, 1, true));
  const Object& r = *od.find(0x5003);
  EXPECT_EQ(r.get_u(2), 0x1234u);
  EXPECT_TRUE(std::equal(blob.rbegin(), blob.rend(), r.bytes(1).begin(), r.bytes(1).end()));
  // A refused value in the large candidate commits nothing.
  od.find(0x5003)->edit_hooks().validate_write = [](const Object&, int, std::span<const uint8_t>,
                                                    EsmState) { return AbortCode::ValueTooHigh; };
  EXPECT_EQ(
      payload(sdo(download_normal(0x5003, 1, Bytes(5002, 0), true), EsmState::PreOp, kMailbox)),
      abort_payload(0x5003, 1, static_cast<uint32_t>(AbortCode::ValueTooHigh)));
  EXPECT_EQ(r.get_u(2), 0x1234u);
}

}  // namespace
}  // namespace rackcat::coe::test
