// SyncManager semantics (ETG.1000.4 §6.7): mailbox hand-over on the last byte, full flag,
// WKC 0 for a full write / empty read mailbox, repeat request, buffered process data and the
// PDI deactivate bit.
#include <gtest/gtest.h>

#include "ecat/registers.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

constexpr uint16_t kStation = 0x1001;

// A mailbox message: 6-byte header (length, address, channel/priority, type 3 = CoE with
// counter) and `payload`, padded to the SM0 size as SOEM writes it.
std::vector<uint8_t> mailbox_message(std::vector<uint8_t> payload, uint8_t counter = 1) {
  std::vector<uint8_t> m(kMbxSize, 0);
  m[0] = static_cast<uint8_t>(payload.size());
  m[5] = static_cast<uint8_t>(0x03 | counter << 4);
  for (size_t i = 0; i < payload.size(); ++i) m[6 + i] = payload[i];
  return m;
}

uint8_t sm_status(Line& line, int sm) {
  return line.master->fprd8(kStation, static_cast<uint16_t>(0x0805 + 8 * sm));
}

TEST(MailboxSm, WritingLastByteHandsRequestOverAndReplyFillsSm1) {
  Line line(1);
  line.to_preop();
  const auto request = mailbox_message({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart, request).wkc, 1);
  EXPECT_EQ(line.app(0).mailbox_requests, 1);
  // The device sees the mailbox data; the header is the firmware's.
  EXPECT_EQ(line.app(0).last_request,
            std::vector<uint8_t>(request.begin() + 6, request.begin() + 10));
  EXPECT_EQ(sm_status(line, 0) & 0x08, 0);     // the µC took the request: SM0 empty again
  EXPECT_EQ(sm_status(line, 1) & 0x08, 0x08);  // reply waiting in SM1
  const auto reply = line.master->fprd(kStation, kMbxInStart, kMbxSize);
  EXPECT_EQ(reply.wkc, 1);
  EXPECT_TRUE(std::equal(request.begin(), request.begin() + 10, reply.data.begin()));
  EXPECT_EQ(sm_status(line, 1) & 0x08, 0);  // reading the last byte freed SM1
}

TEST(MailboxSm, ReadingEmptyMailboxGetsNoWorkingCounter) {
  Line line(1);
  line.to_preop();
  const auto r = line.master->fprd(kStation, kMbxInStart, kMbxSize);
  EXPECT_EQ(r.wkc, 0);
  EXPECT_EQ(r.data, std::vector<uint8_t>(kMbxSize, 0));
}

TEST(MailboxSm, WriteToFullMailboxGetsNoWorkingCounter) {
  Line line(1);
  line.to_preop();
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart, mailbox_message({0xA1}, 1)).wkc,
            1);  // reply -> SM1
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart, mailbox_message({0xA2}, 2)).wkc,
            1);  // waits in SM0
  EXPECT_EQ(sm_status(line, 0) & 0x08, 0x08);
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart, mailbox_message({0xA3}, 3)).wkc,
            0);  // refused
  EXPECT_EQ(line.app(0).mailbox_requests, 1);
  // Reading the first reply frees SM1; the µC then takes the waiting request.
  EXPECT_EQ(line.master->fprd(kStation, kMbxInStart, kMbxSize).data[6], 0xA1);
  EXPECT_EQ(line.app(0).mailbox_requests, 2);
  EXPECT_EQ(line.master->fprd(kStation, kMbxInStart, kMbxSize).data[6], 0xA2);
}

TEST(MailboxSm, PartialWriteWithoutLastByteIsNotHandedOver) {
  Line line(1);
  line.to_preop();
  auto request = mailbox_message({0x01});
  request.resize(16);
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart, request).wkc, 1);
  EXPECT_EQ(line.app(0).mailbox_requests, 0);
  EXPECT_EQ(sm_status(line, 0) & 0x08, 0);
  // The last byte completes it.
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart + kMbxSize - 1, {0x00}).wkc, 1);
  EXPECT_EQ(line.app(0).mailbox_requests, 1);
}

TEST(MailboxSm, RepeatRequestResendsLastReplyAndTogglesAck) {
  Line line(1);
  line.to_preop();
  line.master->fpwr(kStation, kMbxOutStart, mailbox_message({0x5A, 0xA5}));
  const auto first = line.master->fprd(kStation, kMbxInStart, kMbxSize);
  ASSERT_EQ(first.wkc, 1);
  // The reply was "lost": toggle the repeat request bit (0x080E bit 1).
  EXPECT_EQ(line.master->fprd8(kStation, 0x080F) & 0x02, 0);
  EXPECT_EQ(line.master->fpwr8(kStation, 0x080E, 0x03), 1);
  EXPECT_EQ(line.master->fprd8(kStation, 0x080F) & 0x02, 0x02);  // repeat ack toggled
  const auto again = line.master->fprd(kStation, kMbxInStart, kMbxSize);
  EXPECT_EQ(again.wkc, 1);
  EXPECT_EQ(again.data, first.data);
  EXPECT_EQ(line.app(0).mailbox_requests, 1);  // the device was not asked twice
}

TEST(MailboxSm, UnsolicitedMessageIsDeliveredWhenSm1IsFree) {
  Line line(1);
  line.to_preop();
  line.app(0).pending_emergency = {0x00, 0x10, 0x01, 0x02};
  line.master->fprd8(kStation, 0x080D);  // any frame lets the µC run
  const auto r = line.master->fprd(kStation, kMbxInStart, kMbxSize);
  EXPECT_EQ(r.wkc, 1);
  EXPECT_EQ(r.data[0], 4);     // Length: the data the device gave
  EXPECT_EQ(r.data[5], 0x13);  // its protocol's type (CoE), the firmware's counter 1
  EXPECT_EQ(r.data[6], 0x00);
}

TEST(MailboxSm, PdiDeactivatedSmBlocksAccessInInit) {
  Line line(1);
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  // Enable SM0 from the master side while INIT: the µC keeps it deactivated (0x0807 bit 0).
  line.master->fpwr(kStation, 0x0800, {0x00, 0x10, kMbxSize, 0x00, 0x26, 0x00, 0x01, 0x00});
  EXPECT_EQ(line.master->fprd8(kStation, 0x0807) & 0x01, 0x01);
  EXPECT_EQ(line.master->fpwr(kStation, kMbxOutStart, mailbox_message({1})).wkc, 0);
  EXPECT_EQ(line.app(0).mailbox_requests, 0);
}

TEST(MailboxSm, ConfigurationIsLockedWhileEnabled) {
  Line line(1);
  line.to_preop();
  // SM0 length stays as configured while the SM is enabled; status and PDI control are
  // read-only.
  line.master->fpwr(kStation, 0x0802, bytes16(0x0010));
  EXPECT_EQ(line.master->fprd16(kStation, 0x0802), kMbxSize);
  line.master->fpwr8(kStation, 0x0807, 0x00);
  line.master->fpwr8(kStation, 0x0805, 0xFF);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0805), 0x00);
  // Disable, change, enable: accepted.
  line.master->fpwr8(kStation, 0x0806, 0x00);
  line.master->fpwr(kStation, 0x0802, bytes16(0x0010));
  EXPECT_EQ(line.master->fprd16(kStation, 0x0802), 0x0010);
}

TEST(BufferedSm, OutputsReachTheDeviceOnlyInOp) {
  Line line(1);
  line.to_safeop();
  auto r = line.cycle({0xDE, 0xAD, 0xBE, 0xEF});
  EXPECT_EQ(r[0].wkc, 3);                   // outputs written (2) + inputs read (1)
  EXPECT_EQ(line.app(0).outputs_count, 0);  // SAFEOP: outputs stay in their safe state
  line.master->request_state(kStation, 0x08);
  ASSERT_EQ(line.fw(0).state(), EsmState::Op);
  r = line.cycle({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(r[0].wkc, 3);
  EXPECT_EQ(line.app(0).last_outputs, (std::vector<uint8_t>{0x01, 0x02, 0x03, 0x04}));
  // The inputs follow the outputs in the LRW image.
  EXPECT_EQ(std::vector<uint8_t>(r[0].data.begin() + 4, r[0].data.end()), line.app(0).inputs_value);
}

TEST(BufferedSm, InputsAreRefreshedForEveryCycle) {
  Line line(1);
  line.to_op();
  const int before = line.app(0).inputs_count;
  line.app(0).inputs_value = {9, 8, 7, 6, 5, 4};
  // The firmware writes SM3 after each frame that wrote SM2 / read SM3: the master's next
  // frame reads it (one frame of latency, as behind a real ESC).
  line.cycle({0, 0, 0, 0});
  const auto r = line.cycle({0, 0, 0, 0});
  EXPECT_EQ(line.app(0).inputs_count, before + 2);
  EXPECT_EQ(std::vector<uint8_t>(r[0].data.begin() + 4, r[0].data.end()), line.app(0).inputs_value);
}

TEST(BufferedSm, StatusReportsTheLastWrittenBuffer) {
  Line line(1);
  line.to_op();
  // Bits 5:4 of the SM2 status cycle through the three buffers.
  std::vector<uint8_t> seen;
  for (int i = 0; i < 3; ++i) {
    line.cycle({0, 0, 0, 0});
    seen.push_back(static_cast<uint8_t>((line.master->fprd8(kStation, 0x0815) >> 4) & 0x03));
  }
  EXPECT_NE(seen[0], seen[1]);
  EXPECT_NE(seen[1], seen[2]);
  EXPECT_NE(seen[0], seen[2]);
}

TEST(BufferedSm, ProcessDataIsBlockedInPreop) {
  Line line(1);
  line.to_preop();
  line.master->config_map();
  // SM2/SM3 enabled by the master but deactivated by the PDI until SAFEOP: no WKC.
  EXPECT_EQ(line.cycle({1, 2, 3, 4})[0].wkc, 0);
}

}  // namespace
}  // namespace rackcat::ecat::test
