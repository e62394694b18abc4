// 0x10F3 diagnosis history (ETG.1020 ch. 13): message bytes against hand-built vectors, the
// overwrite and acknowledge modes, the type filters, wrap-around, and the SDO answers.
#include <gtest/gtest.h>

#include "coe/diagnosis_history.hpp"
#include "coe/sdo_server.hpp"
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

using diag::AddResult;
using diag::History;
using diag::Message;
using diag::Type;

// ETG.1020 ch. 13 "Diagnosis Message": Diag Code (UDINT), Flags (UINT: bits 0..3 type, bit 4
// local time stamp, bits 8..15 parameter count), Text ID (UINT), Time Stamp (ULINT, ns), then
// per parameter a UINT flag (bits 12..15 = 0: bits 0..11 = ETG.1000.6 data type index) and
// the value. All little-endian. Built here byte by byte from that table.
TEST(DiagnosisMessage, GoldenErrorWithEmergencyCodeAndTwoParameters) {
  Message m;
  m.diag_code = diag::emergency_diag_code(0x4210);  // 0xE800: Emergency code in bits 16..31
  m.type = Type::Error;
  m.text_id = 0x8101;
  m.time_ns = 0x0001020304050607ull;
  ASSERT_TRUE(m.add_u8(0x01));     // UNSIGNED8 (0x0005)
  ASSERT_TRUE(m.add_u16(0x0003));  // UNSIGNED16 (0x0006)
  const std::array<uint8_t, 32> expected = {
      0x00, 0xE8, 0x10, 0x42,                          // diag code 0x4210E800
      0x02, 0x02,                                      // flags: error, 2 parameters, DC time
      0x01, 0x81,                                      // text ID 0x8101
      0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01, 0x00,  // time stamp
      0x05, 0x00, 0x01,                                // UNSIGNED8 1
      0x06, 0x00, 0x03, 0x00,                          // UNSIGNED16 3
      0,    0,    0,    0,    0,    0,    0,    0,    0};
  EXPECT_EQ(diag::encode(m), expected);
}

TEST(DiagnosisMessage, GoldenInfoWithLocalTimeAndSignedParameter) {
  Message m;
  m.diag_code = 0x0000E800;  // Emergency code 0x0000: error reset / cause removed
  m.type = Type::Info;
  m.text_id = 0x1101;
  m.time_ns = 1000;
  m.local_time = true;
  ASSERT_TRUE(m.add_i16(-2));                                        // INTEGER16 (0x0003)
  ASSERT_TRUE(m.add_u32(0xA1B2C3D4u));                               // UNSIGNED32 (0x0007)
  const std::array<uint8_t, 32> expected = {0x00, 0xE8, 0x00, 0x00,  // diag code
                                            0x10, 0x02,  // info, bit 4 local time, 2 parameters
                                            0x01, 0x11,  // text ID 0x1101
                                            0xE8, 0x03, 0,    0,    0,    0,    0, 0,  // 1000 ns
                                            0x03, 0x00, 0xFE, 0xFF,              // INTEGER16 -2
                                            0x07, 0x00, 0xD4, 0xC3, 0xB2, 0xA1,  // UNSIGNED32
                                            0,    0,    0,    0,    0,    0};
  EXPECT_EQ(diag::encode(m), expected);
}

TEST(DiagnosisMessage, ParametersBeyondTheSlotAreRefused) {
  Message m;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(m.add_u16(1));  // 4 x 4 = 16 bytes
  EXPECT_FALSE(m.add_u8(1));
  EXPECT_EQ(m.parameter_count, 4);
  EXPECT_EQ(m.parameter_bytes, 16);
}

Message msg(uint16_t text, Type type = Type::Error) {
  Message m;
  m.diag_code = diag::emergency_diag_code(0x5000);
  m.type = type;
  m.text_id = text;
  m.time_ns = text;
  return m;
}

uint16_t text_of(std::span<const uint8_t> slot) {
  return static_cast<uint16_t>(slot[6] | (slot[7] << 8));
}

class HistoryTest : public ::testing::Test {
 protected:
  explicit HistoryTest(uint8_t capacity = 4) : h(capacity) {
    od.add(h.make_object());
    obj = od.find(diag::kIndex);
    h.bind(*obj);
  }
  void set_ack_mode() { ASSERT_EQ(h.write_flags(diag::kFlagAcknowledgeMode), AbortCode::None); }
  ObjectDictionary od;
  History h;
  Object* obj = nullptr;
};

TEST_F(HistoryTest, ObjectLayoutAsEtg1020) {
  EXPECT_EQ(obj->code(), ObjectCode::Record);
  EXPECT_EQ(obj->sub0(), 9);  // 5 control entries + 4 messages
  EXPECT_EQ(obj->get_u(1), 4u);
  EXPECT_EQ(obj->entry(4)->type(), DataType::Boolean);
  EXPECT_TRUE(obj->entry(4)->access & access::kTxPdoMappable);
  EXPECT_EQ(obj->entry(5)->type(), DataType::Unsigned16);
  EXPECT_EQ(obj->get_u(5), diag::kFlagEmergency);  // new messages go out as Emergency
  EXPECT_EQ(obj->entry(6)->type(), DataType::OctetString);
  EXPECT_EQ(obj->entry(6)->byte_length(), 32);
  EXPECT_EQ(obj->get_u(2), 0u);
  EXPECT_EQ(obj->get_u(4), 0u);
}

TEST_F(HistoryTest, OverwriteModeWrapsAndFlagsUnacknowledgedLoss) {
  for (uint16_t t = 1; t <= 4; ++t) EXPECT_EQ(h.add(msg(t)), AddResult::Stored);
  EXPECT_EQ(obj->get_u(2), 9u);  // newest in subindex 9
  EXPECT_EQ(obj->get_u(4), 1u);
  EXPECT_EQ(obj->get_u(5) & diag::kFlagOverflow, 0u);
  // Acknowledge up to the second message, then wrap: the first (acknowledged) goes quietly.
  EXPECT_EQ(h.write_newest_acknowledged(7), AbortCode::None);
  EXPECT_EQ(obj->get_u(3), 7u);
  EXPECT_EQ(h.add(msg(5)), AddResult::Stored);
  EXPECT_EQ(obj->get_u(2), 6u);  // wrapped to the first message subindex
  EXPECT_EQ(text_of(obj->bytes(6)), 5);
  EXPECT_EQ(obj->get_u(3), 7u);
  EXPECT_EQ(obj->get_u(5) & diag::kFlagOverflow, 0u);
  // The second (acknowledged, the newest acknowledged) goes: nothing acknowledged remains.
  EXPECT_EQ(h.add(msg(6)), AddResult::Stored);
  EXPECT_EQ(obj->get_u(3), 0u);
  EXPECT_EQ(obj->get_u(5) & diag::kFlagOverflow, 0u);
  // Now an unacknowledged message is overwritten: bit 5.
  EXPECT_EQ(h.add(msg(7)), AddResult::Stored);
  EXPECT_EQ(obj->get_u(5) & diag::kFlagOverflow, diag::kFlagOverflow);
  EXPECT_EQ(obj->get_u(2), 8u);
  // Oldest .. newest: subindices 9, 6, 7, 8 holding 4, 5, 6, 7.
  EXPECT_EQ(h.subindex_of(0), 9);
  EXPECT_EQ(text_of(obj->bytes(9)), 4);
  EXPECT_EQ(text_of(obj->bytes(8)), 7);
}

TEST_F(HistoryTest, OverwriteModeNewMessagesClearedByReadingTheNewest) {
  h.add(msg(1));
  h.add(msg(2));
  h.on_read(6);  // an older one: still new
  EXPECT_EQ(obj->get_u(4), 1u);
  h.on_read(7);
  EXPECT_EQ(obj->get_u(4), 0u);
  h.add(msg(3));
  EXPECT_EQ(obj->get_u(4), 1u);
  h.on_read(-1);  // complete access / PDO packing: not a read of the newest message
  EXPECT_EQ(obj->get_u(4), 1u);
  h.on_read(8);
  EXPECT_EQ(obj->get_u(4), 0u);
}

TEST_F(HistoryTest, OverwriteModeWritingZeroDeletesEverything) {
  for (uint16_t t = 1; t <= 6; ++t) h.add(msg(t));
  ASSERT_EQ(obj->get_u(5) & diag::kFlagOverflow, diag::kFlagOverflow);
  EXPECT_EQ(h.write_newest_acknowledged(0), AbortCode::None);
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(obj->get_u(2), 0u);
  EXPECT_EQ(obj->get_u(3), 0u);
  EXPECT_EQ(obj->get_u(4), 0u);
  EXPECT_EQ(obj->get_u(5), diag::kFlagEmergency);
  for (uint8_t s = 6; s <= 9; ++s) {
    for (uint8_t b : obj->bytes(s)) EXPECT_EQ(b, 0);
  }
  h.add(msg(9));
  EXPECT_EQ(obj->get_u(2), 6u);
}

TEST_F(HistoryTest, AcknowledgeModeDiscardsWhenFullOfUnacknowledged) {
  set_ack_mode();
  for (uint16_t t = 1; t <= 4; ++t) EXPECT_EQ(h.add(msg(t)), AddResult::Stored);
  EXPECT_EQ(obj->get_u(4), 1u);
  EXPECT_EQ(h.add(msg(5)), AddResult::Discarded);
  EXPECT_EQ(obj->get_u(5), diag::kFlagAcknowledgeMode | diag::kFlagOverflow | 0u);
  EXPECT_EQ(obj->get_u(2), 9u);  // unchanged
  EXPECT_EQ(text_of(obj->bytes(6)), 1);
  // Reading does not clear New Messages Available in acknowledge mode.
  h.on_read(9);
  EXPECT_EQ(obj->get_u(4), 1u);
  // Acknowledge two: the next message replaces the oldest acknowledged one.
  EXPECT_EQ(h.write_newest_acknowledged(7), AbortCode::None);
  EXPECT_EQ(h.add(msg(6)), AddResult::Stored);
  EXPECT_EQ(text_of(obj->bytes(6)), 6);
  EXPECT_EQ(obj->get_u(3), 7u);
  EXPECT_EQ(h.acknowledged(), 1u);
  // Acknowledge all: nothing new.
  EXPECT_EQ(h.write_newest_acknowledged(6), AbortCode::None);
  EXPECT_EQ(obj->get_u(4), 0u);
  EXPECT_EQ(obj->get_u(3), 6u);
}

TEST_F(HistoryTest, AcknowledgeModeWritingZeroDeletesOnlyAcknowledged) {
  set_ack_mode();
  for (uint16_t t = 1; t <= 4; ++t) h.add(msg(t));
  ASSERT_EQ(h.write_newest_acknowledged(7), AbortCode::None);  // messages 1, 2
  EXPECT_EQ(h.write_newest_acknowledged(0), AbortCode::None);
  EXPECT_EQ(h.count(), 2u);
  EXPECT_EQ(obj->get_u(3), 0u);
  EXPECT_EQ(obj->get_u(2), 9u);
  EXPECT_EQ(h.subindex_of(0), 8);
  for (uint8_t b : obj->bytes(6)) EXPECT_EQ(b, 0);
  EXPECT_EQ(text_of(obj->bytes(8)), 3);
  EXPECT_EQ(obj->get_u(4), 1u);
  // Two free slots again: 5 and 6 fit, then 7 is discarded.
  EXPECT_EQ(h.add(msg(5)), AddResult::Stored);
  EXPECT_EQ(h.add(msg(6)), AddResult::Stored);
  EXPECT_EQ(obj->get_u(2), 7u);
  EXPECT_EQ(h.add(msg(7)), AddResult::Discarded);
}

TEST_F(HistoryTest, TypeFiltersDropMessagesOfDisabledTypes) {
  ASSERT_EQ(h.write_flags(diag::kFlagDisableInfo | diag::kFlagDisableWarning), AbortCode::None);
  EXPECT_EQ(h.add(msg(1, Type::Info)), AddResult::Filtered);
  EXPECT_EQ(h.add(msg(2, Type::Warning)), AddResult::Filtered);
  EXPECT_EQ(h.add(msg(3, Type::Error)), AddResult::Stored);
  ASSERT_EQ(h.write_flags(diag::kFlagDisableError), AbortCode::None);
  EXPECT_EQ(h.add(msg(4, Type::Error)), AddResult::Filtered);
  EXPECT_EQ(h.add(msg(5, Type::Info)), AddResult::Stored);
  EXPECT_EQ(h.count(), 2u);
  EXPECT_FALSE(h.emergency_enabled());
  EXPECT_EQ(h.write_flags(0x0040), AbortCode::ValueRange);  // reserved bit
}

TEST_F(HistoryTest, LongRunWrapsManyTimes) {
  for (uint16_t t = 1; t <= 1000; ++t) h.add(msg(t));
  EXPECT_EQ(h.count(), 4u);
  for (size_t age = 0; age < 4; ++age) {
    EXPECT_EQ(text_of(obj->bytes(h.subindex_of(age))), 997 + age);
  }
  EXPECT_EQ(obj->get_u(2), static_cast<uint64_t>(6 + (999 % 4)));
}

// The SDO answers a master gets (ETG.1020 ch. 13, 0x10F3:03 write rules).
class HistorySdoTest : public HistoryTest {
 protected:
  HistorySdoTest() : server(od) {}
  Bytes sdo(const Bytes& body) {
    Bytes reply(256, 0xEE);
    counter = counter >= 7 ? 1 : counter + 1;
    reply.resize(frame.request(
        coe_message(counter, 2, body), reply,
        [&](auto data, size_t, auto out) { return server.handle(data, out, EsmState::Op); }));
    return payload(reply);
  }
  SdoServer server;
  rackcat::testing::SlaveMailbox frame;
  uint8_t counter = 0;
};

TEST_F(HistorySdoTest, NewestAcknowledgedWriteAborts) {
  h.add(msg(1));
  EXPECT_EQ(sdo(download_expedited(0x10F3, 3, 5, 1)), abort_payload(0x10F3, 3, 0x06090032));
  EXPECT_EQ(sdo(download_expedited(0x10F3, 3, 10, 1)), abort_payload(0x10F3, 3, 0x06090031));
  EXPECT_EQ(sdo(download_expedited(0x10F3, 3, 7, 1)), abort_payload(0x10F3, 3, 0x06090030));
  EXPECT_EQ(sdo(download_expedited(0x10F3, 2, 6, 1)), abort_payload(0x10F3, 2, 0x06010002));
  EXPECT_EQ(sdo(download_expedited(0x10F3, 3, 6, 1)), download_ok(0x10F3, 3));
  EXPECT_EQ(obj->get_u(3), 6u);
  EXPECT_EQ(sdo(download_expedited(0x10F3, 3, 0, 1)), download_ok(0x10F3, 3));
  EXPECT_EQ(h.count(), 0u);
}

TEST_F(HistorySdoTest, FlagsWriteSwitchesModeAndKeepsReadOnlyBit) {
  for (uint16_t t = 1; t <= 5; ++t) h.add(msg(t));
  ASSERT_TRUE(h.overflow());
  EXPECT_EQ(sdo(download_expedited(0x10F3, 5, 0x0011, 2)), download_ok(0x10F3, 5));
  EXPECT_TRUE(h.acknowledge_mode());
  EXPECT_EQ(obj->get_u(5), 0x0031u);  // bit 5 stays the device's
  EXPECT_EQ(sdo(download_expedited(0x10F3, 5, 0x0100, 2)), abort_payload(0x10F3, 5, 0x06090030));
  EXPECT_EQ(obj->get_u(5), 0x0031u);
}

TEST_F(HistorySdoTest, ReadingTheNewestBySdoClearsNewMessages) {
  h.add(msg(1));
  EXPECT_EQ(obj->get_u(4), 1u);
  const Bytes r = sdo(upload_req(0x10F3, 6));
  ASSERT_GE(r.size(), 10u);
  EXPECT_EQ(obj->get_u(4), 0u);
}

}  // namespace
}  // namespace rackcat::coe::test

namespace rackcat::coe::test {
namespace {

TEST(DiagnosisMessage, DecodeIsTheInverseOfEncode) {
  Message m;
  m.diag_code = diag::emergency_diag_code(0x2320);
  m.type = Type::Warning;
  m.text_id = 0x4601;
  m.time_ns = 123456789;
  m.add_u8(2);
  m.add_u16(17);
  m.add_u8(5);
  m.add_u16(0);
  const auto bytes = diag::encode(m);
  const auto back = diag::decode(bytes);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(diag::encode(*back), bytes);
  EXPECT_EQ(back->parameter(0), 2u);
  EXPECT_EQ(back->parameter(1), 17u);
  EXPECT_EQ(back->parameter(2), 5u);
  EXPECT_EQ(back->parameter(4), 0u);
  const std::array<uint8_t, 32> empty{};
  EXPECT_FALSE(diag::decode(empty).has_value());
}

}  // namespace
}  // namespace rackcat::coe::test
