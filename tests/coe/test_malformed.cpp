// Malformed CoE requests get a precise mailbox error (ETG.1000.6 §5.2.3 Table 29) or SDO abort,
// change nothing, and never crash. The mailbox header's own checks (type, channel, length)
// are the firmware's MailboxServer's (tests/ecat/test_firmware.cpp).
#include <random>

#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

// Mailbox error payload: service 0x0001, detail code.
Bytes mbx_error(uint16_t detail) {
  return {0x01, 0x00, static_cast<uint8_t>(detail), static_cast<uint8_t>(detail >> 8)};
}

TEST_F(SdoTest, TruncatedCoeRequests) {
  // No CoE header.
  EXPECT_EQ(payload(send({0x01, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00})), mbx_error(0x06));
  // SDO request shorter than 8 bytes.
  EXPECT_EQ(payload(send(coe_message(1, 2, {0x40, 0x00, 0x10}))), mbx_error(0x06));
  // SDO information header or list type missing.
  EXPECT_EQ(payload(send(coe_message(2, 8, {0x01, 0x00}))), mbx_error(0x06));
  EXPECT_EQ(payload(send(coe_message(3, 8, {0x01, 0x00, 0x00, 0x00}))), mbx_error(0x06));
  EXPECT_EQ(payload(send(coe_message(4, 8, {0x05, 0x00, 0x00, 0x00, 0x00, 0x10}))),
            mbx_error(0x06));
  // A fragmented SDO information request does not exist.
  EXPECT_EQ(payload(send(coe_message(5, 8, {0x81, 0x00, 0x00, 0x00, 0x01, 0x00}))),
            mbx_error(0x05));
  EXPECT_EQ(payload(send(coe_message(6, 8, {0x01, 0x00, 0x02, 0x00, 0x01, 0x00}))),
            mbx_error(0x05));
}

TEST_F(SdoTest, WrongService) {
  // RxPDO (5), SDO response (3), emergency (1) and reserved services from the master.
  EXPECT_EQ(payload(send(coe_message(4, 5, upload_req(0x1000, 0)))), mbx_error(0x04));
  EXPECT_EQ(payload(send(coe_message(5, 3, upload_req(0x1000, 0)))), mbx_error(0x04));
  EXPECT_EQ(payload(send(coe_message(6, 1, upload_req(0x1000, 0)))), mbx_error(0x04));
  EXPECT_EQ(payload(send(coe_message(7, 15, upload_req(0x1000, 0)))), mbx_error(0x04));
}

TEST_F(SdoTest, ReplyMailboxTooSmall) {
  // 12 bytes cannot hold an SDO reply: a mailbox error "no more memory" still fits.
  EXPECT_EQ(payload(send(coe_message(1, 2, upload_req(0x1000, 0)), EsmState::PreOp, 12)),
            mbx_error(0x07));
  EXPECT_TRUE(send(coe_message(2, 2, upload_req(0x1000, 0)), EsmState::PreOp, 8).empty());
}

TEST_F(SdoTest, BytesAfterTheAnnouncedLengthAreIgnored) {
  Bytes req = coe_message(1, 2, upload_req(0x1000, 0));
  req.resize(128, 0xEE);  // the whole SM0 buffer
  EXPECT_EQ(payload(send(req))[2], 0x43);
}

TEST_F(SdoTest, RandomMailboxesNeverCrashOrOverflow) {
  // Deterministic garbage: every reply stays inside the mailbox and starts with a valid header.
  std::mt19937 rng(12345);
  const ObjectDictionary before = od;
  for (int i = 0; i < 20000; ++i) {
    Bytes req(rng() % 40);
    for (auto& b : req) b = static_cast<uint8_t>(rng());
    if (req.size() >= 6 && (rng() & 1)) {
      // Mostly well-formed CoE headers, to reach the SDO code.
      const size_t len = req.size() - 6;
      req[0] = static_cast<uint8_t>(len);
      req[1] = 0;
      req[4] = 0;
      req[5] = static_cast<uint8_t>(0x03 | (rng() & 0x70));
      if (req.size() >= 8) req[7] = static_cast<uint8_t>((rng() & 1 ? 0x20 : 0x80));
    }
    const size_t mailbox = 16 + rng() % 120;
    Bytes reply(mailbox + 8, 0xEE);
    const size_t n = frame.request(
        req, std::span(reply).first(mailbox),
        [&](auto data, size_t, auto out) { return server.handle(data, out, EsmState::PreOp); });
    ASSERT_LE(n, mailbox);
    for (size_t k = mailbox; k < reply.size(); ++k) ASSERT_EQ(reply[k], 0xEE);
    if (n) {
      ASSERT_EQ(n, 6u + (reply[0] | (reply[1] << 8)));
    }
    Bytes polled(mailbox - 6);
    ASSERT_LE(server.poll(polled), polled.size());
  }
}

}  // namespace
}  // namespace rackcat::coe::test
