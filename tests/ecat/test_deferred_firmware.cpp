// Deferred firmware (Segment::set_deferred_firmware, run_firmware_slice): the event loop runs
// the slaves' firmware in slices between frames. What the master sees when a frame comes
// before every slave's firmware has run: each ESC as its own firmware left it (SM3: the last
// input buffer that slave completed, ETG.1000.4 §6.7.2), and every slave runs once per round,
// in round-robin order from where the last slice stopped.
#include <gtest/gtest.h>

#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

constexpr size_t kSlaves = 4;

std::vector<uint8_t> cyclic_frame(uint8_t output_value) {
  std::vector<uint8_t> image(kSlaves * (kOutputBytes + kInputBytes), 0);
  for (size_t i = 0; i < kSlaves * kOutputBytes; ++i) image[i] = output_value;
  FrameBuilder b;
  b.add_logical(Command::Lrw, 0, image);
  return b.build();
}

// The input bytes slave k returned in an LRW reply (outputs of every slave first, then inputs).
uint8_t input_of(const std::vector<uint8_t>& reply, size_t k) {
  return decode(reply).at(0).data.at(kSlaves * kOutputBytes + k * kInputBytes);
}

struct Deferred : ::testing::Test {
  Deferred() {
    line.to_op();
    for (size_t k = 0; k < kSlaves; ++k) {
      line.app(k).inputs_value = {static_cast<uint8_t>(0xA0 + k), 0, 0, 0, 0, 0};
    }
    line.segment->set_deferred_firmware(true);
  }
  std::vector<int> outputs_counts() {
    std::vector<int> c;
    for (size_t k = 0; k < kSlaves; ++k) c.push_back(line.app(k).outputs_count);
    return c;
  }
  Line line{kSlaves};
};

TEST_F(Deferred, AFrameLeavesTheFirmwareToTheSlicesAndSeesWhatEachSlaveCompleted) {
  const std::vector<int> before = outputs_counts();
  std::vector<uint8_t> f1 = cyclic_frame(0x11);
  ASSERT_EQ(line.segment->process(f1), f1.size());
  EXPECT_EQ(decode(f1).at(0).wkc, 3 * kSlaves);
  // process() ran no firmware: nobody has the new outputs yet.
  EXPECT_EQ(outputs_counts(), before);
  EXPECT_TRUE(line.segment->firmware_pending());
  // A zero budget runs exactly one slave (the manual clock does not move): slave 0.
  EXPECT_TRUE(line.segment->run_firmware_slice(0));
  EXPECT_EQ(line.app(0).outputs_count, before[0] + 1);
  EXPECT_EQ(line.app(0).last_outputs, std::vector<uint8_t>(kOutputBytes, 0x11));
  EXPECT_EQ(line.app(1).outputs_count, before[1]);

  // The next frame comes before slaves 1-3 ran: slave 0 answers with the inputs its firmware
  // produced after frame 1; slaves 1-3 with the last buffer they completed (before the new
  // input values were set).
  std::vector<uint8_t> f2 = cyclic_frame(0x22);
  line.segment->process(f2);
  EXPECT_EQ(decode(f2).at(0).wkc, 3 * kSlaves);
  EXPECT_EQ(input_of(f2, 0), 0xA0);
  for (size_t k = 1; k < kSlaves; ++k) EXPECT_NE(input_of(f2, k), 0xA0 + k) << k;

  // Frame 2 starts a new round at the cursor: slaves 1, 2, 3, then 0, one per slice, each
  // taking the newest output buffer (frame 2's).
  for (size_t k : {1u, 2u, 3u, 0u}) {
    const std::vector<int> c = outputs_counts();
    line.segment->run_firmware_slice(0);
    for (size_t j = 0; j < kSlaves; ++j) {
      EXPECT_EQ(line.app(j).outputs_count, c[j] + (j == k ? 1 : 0)) << "slice for " << k;
    }
    EXPECT_EQ(line.app(k).last_outputs, std::vector<uint8_t>(kOutputBytes, 0x22)) << k;
  }
  EXPECT_FALSE(line.segment->firmware_pending());
  EXPECT_FALSE(line.segment->run_firmware_slice(0));

  // Every slave has run: the next frame sees every new input.
  std::vector<uint8_t> f3 = cyclic_frame(0x33);
  line.segment->process(f3);
  for (size_t k = 0; k < kSlaves; ++k) EXPECT_EQ(input_of(f3, k), 0xA0 + k) << k;
}

TEST_F(Deferred, ABudgetTheClockDoesNotUseUpRunsTheWholeRound) {
  std::vector<uint8_t> f = cyclic_frame(0x44);
  line.segment->process(f);
  EXPECT_FALSE(line.segment->run_firmware_slice(1'000));
  for (size_t k = 0; k < kSlaves; ++k) {
    EXPECT_EQ(line.app(k).last_outputs, std::vector<uint8_t>(kOutputBytes, 0x44)) << k;
  }
}

TEST_F(Deferred, AfterFrameStillRunsEverythingPending) {
  std::vector<uint8_t> f = cyclic_frame(0x55);
  line.segment->process(f);
  line.segment->after_frame();
  EXPECT_FALSE(line.segment->firmware_pending());
  for (size_t k = 0; k < kSlaves; ++k) {
    EXPECT_EQ(line.app(k).last_outputs, std::vector<uint8_t>(kOutputBytes, 0x55)) << k;
  }
}

TEST_F(Deferred, FramesFasterThanTheFirmwareStarveNoSlave) {
  // One slave per frame (the least the event loop runs after each frame): every slave still
  // gets its turn, each within one round of slaves.
  const std::vector<int> before = outputs_counts();
  for (int i = 0; i < static_cast<int>(kSlaves) * 3; ++i) {
    std::vector<uint8_t> f = cyclic_frame(static_cast<uint8_t>(i));
    line.segment->process(f);
    line.segment->run_firmware_slice(0);
  }
  for (size_t k = 0; k < kSlaves; ++k) EXPECT_EQ(line.app(k).outputs_count, before[k] + 3) << k;
}

}  // namespace
}  // namespace rackcat::ecat::test
