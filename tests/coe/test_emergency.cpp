// Emergency messages (ETG.1000.6 §5.6.4) and the SDO server's reset. The mailbox counter and
// double-write rules (ETG.1000.4 §5.6) are the firmware's (tests/ecat/test_firmware.cpp).
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

TEST_F(SdoTest, ResetForgetsTransfers) {
  sdo(upload_req(0x2002, 0));
  server.reset();
  EXPECT_EQ(payload(sdo({0x60, 0, 0, 0, 0, 0, 0, 0})), abort_payload(0, 0, 0x05040001));
}

}  // namespace
}  // namespace rackcat::coe::test
