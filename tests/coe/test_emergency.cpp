// Emergency messages (ETG.1000.6 §5.6.4) and the mailbox counter / repeat rules
// (ETG.1000.4 §5.6).
#include <thread>

#include "coe/emergency_queue.hpp"
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, EmergencyGoldenBytes) {
  server.queue_emergency(0x8130, 0x11, {0x01, 0x02, 0x03, 0x04, 0x05});
  EXPECT_TRUE(server.has_pending());
  // Mailbox length 10, CoE service 1 (0x1000), error code, error register, 5 data bytes.
  EXPECT_EQ(poll(), (Bytes{0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x10, 0x30, 0x81, 0x11, 0x01,
                           0x02, 0x03, 0x04, 0x05}));
  EXPECT_TRUE(poll().empty());
}

TEST_F(SdoTest, EmergencyQueueIsAFixedRingCountingOverruns) {
  for (uint16_t i = 0; i < SdoServer::kEmergencySlots; ++i)
    EXPECT_TRUE(server.queue_emergency(i, 0));
  EXPECT_FALSE(server.queue_emergency(0xFFFF, 0));
  EXPECT_EQ(server.pending_emergencies(), SdoServer::kEmergencySlots);
  EXPECT_EQ(server.emergency_overruns(), 1u);
  for (uint16_t i = 0; i < SdoServer::kEmergencySlots; ++i) {
    const Bytes p = payload(poll());
    EXPECT_EQ(p[2] | (p[3] << 8), i);  // in order, the overrun one never appears
  }
  EXPECT_TRUE(poll().empty());
  EXPECT_TRUE(server.queue_emergency(0x1234, 0));  // room again
}

TEST(EmergencyQueue, OneProducerThreadOneConsumer) {
  EmergencyQueue<4> q;
  constexpr uint16_t kCount = 2000;
  std::thread producer([&] {
    for (uint16_t i = 0; i < kCount;) {
      if (q.push(Emergency{i, 0, {}}))
        ++i;
      else
        std::this_thread::yield();
    }
  });
  uint16_t expected = 0;
  Emergency e;
  while (expected < kCount) {
    if (q.pop(e)) {
      ASSERT_EQ(e.error_code, expected);
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_TRUE(q.empty());
}

TEST_F(SdoTest, EmergencyGoesBeforeQueuedFragments) {
  info({0x01, 0x00, 0x00, 0x00, 0x01, 0x00}, 24);
  server.queue_emergency(0xFF00, 0x80);
  EXPECT_EQ(payload(poll(24))[1], 0x10);
  EXPECT_EQ(payload(poll(24))[1], 0x80);
}

TEST_F(SdoTest, OwnCounterCyclesOneToSevenOverAllMessages) {
  std::vector<uint8_t> counters;
  for (int i = 0; i < 8; ++i) counters.push_back(sdo(upload_req(0x1000, 0))[5] >> 4);
  server.queue_emergency(0x1000, 0);
  counters.push_back(poll()[5] >> 4);
  EXPECT_EQ(counters, (std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 1, 2}));
}

// ETG.1000.4 §5.6, mailbox header Cnt: the counter lets the slave detect a double write, i.e.
// the master retransmitting a mailbox write whose working counter it did not see (SOEM does so
// after 2 ms). The reply to the first write is already on its way, so the repeat is dropped:
// no second reply (which a master would take as the answer to its next request) and nothing
// executes twice. A master that lost a reply asks for it with the SM1 repeat request (ecat).
TEST_F(SdoTest, RepeatedCounterIsADoubleWriteAndIsDropped) {
  int writes = 0;
  od.find(0x2009)->hooks.after_write = [&](Object&, int) { ++writes; };
  const Bytes request = coe_message(3, 2, download_expedited(0x2009, 0, 7, 1));
  const Bytes first = send(request);
  EXPECT_FALSE(first.empty());
  EXPECT_TRUE(send(request).empty());  // same bytes, same counter: no reply
  EXPECT_EQ(writes, 1);
  // The next counter is a new request.
  EXPECT_FALSE(send(coe_message(4, 2, download_expedited(0x2009, 0, 7, 1))).empty());
  EXPECT_EQ(writes, 2);
  // Counter 0 means "not counted": every request executes and is answered.
  EXPECT_FALSE(send(coe_message(0, 2, download_expedited(0x2009, 0, 7, 1))).empty());
  EXPECT_FALSE(send(coe_message(0, 2, download_expedited(0x2009, 0, 7, 1))).empty());
  EXPECT_EQ(writes, 4);
  // The same counter with other bytes is not a retransmission: it executes.
  EXPECT_FALSE(send(coe_message(4, 2, download_expedited(0x2009, 0, 9, 1))).empty());
  EXPECT_EQ(writes, 5);
}

TEST_F(SdoTest, RepeatOfASegmentRequestDoesNotAdvanceTheTransfer) {
  sdo(upload_req(0x2002, 0));
  const Bytes seg = coe_message(next_counter(), 2, {0x60, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_FALSE(send(seg).empty());
  EXPECT_TRUE(send(seg).empty());
  // The transfer advanced once: the next segment (toggle 1) is the last one.
  EXPECT_EQ(sdo({0x70, 0, 0, 0, 0, 0, 0, 0})[8], 0x11);
}

TEST_F(SdoTest, ResetForgetsTransfersAndRepeats) {
  sdo(upload_req(0x2002, 0));
  server.reset();
  EXPECT_EQ(payload(sdo({0x60, 0, 0, 0, 0, 0, 0, 0})), abort_payload(0, 0, 0x05040001));
}

}  // namespace
}  // namespace rackcat::coe::test
