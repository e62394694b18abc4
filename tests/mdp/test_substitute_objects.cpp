// The substitute value objects over SDO (mdp/substitute_values.hpp): reaction codes outside the
// INTERBUS Basic profile's PDTimeoutCode / PF_Code table answer 0x06090030 (ETG.1000.6 Table 41
// "value range of parameter exceeded") by single and by complete access and change nothing; a
// digital channel's substitute value above 1 is 0x06090031; 0xFBF2 stores them over a restart.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "mdp/device.hpp"
#include "mdp/substitute_values.hpp"
#include "sdo_client.hpp"

namespace rackcat::mdp {
namespace {

using rackcat::EsmState;
using testing::SdoClient;
namespace sv = substitute;

constexpr uint32_t kValueRange = 0x06090030, kValueTooHigh = 0x06090031;

class SubstituteObjects : public testing::RestartingDeviceTest {
 protected:
  SubstituteObjects() : RestartingDeviceTest("mdp_substitute_") {}
  // Module n's object 0x4nnX.
  uint16_t index(uint16_t module, uint8_t nibble) {
    return device->modules()[module - 1].index(0x4000, nibble);
  }
};

// Default rack: module 1 = RIM 1 slot 1 CDO-10 (16 outputs), module 2 = slot 2 CDI-10.
TEST_F(SubstituteObjects, ReactionCodesOutsideTheProfileTableAreRefused) {
  const uint16_t out = index(1, sv::kOutputReaction);
  const uint16_t in = index(2, sv::kInputReaction);
  EXPECT_EQ(sdo->write_u(out, 1, sv::kMaximum, 2), 0u);
  EXPECT_EQ(sdo->read_u(out, 1), sv::kMaximum);
  EXPECT_EQ(sdo->write_u(out, 2, 0x0006, 2), kValueRange);
  EXPECT_EQ(sdo->write_u(out, 2, 0x0010, 2), kValueRange);
  EXPECT_EQ(sdo->read_u(out, 2), sv::kGuide);
  EXPECT_EQ(sdo->write_u(in, 1, sv::kOnes, 2), kValueRange);  // inputs: 0, 2, 3, 0x8000 only
  EXPECT_EQ(sdo->write_u(in, 1, sv::kHoldLast, 2), 0u);
  // Complete access: sub 0 (16 bits) then 16 x UINT16; one bad entry refuses all of it.
  std::vector<uint8_t> image;
  ASSERT_EQ(sdo->upload(out, 0, image, true), 0u);
  ASSERT_EQ(image.size(), 2u + 2 * 16);
  image[2 + 2 * 5] = 0x07;
  image[2 + 2 * 5 + 1] = 0x00;
  image[2 + 2 * 4] = 0x03;
  image[2 + 2 * 4 + 1] = 0x00;
  EXPECT_EQ(sdo->download(out, 0, image, true), kValueRange);
  EXPECT_EQ(sdo->read_u(out, 5), sv::kGuide);
  image[2 + 2 * 5] = 0x02;
  EXPECT_EQ(sdo->download(out, 0, image, true), 0u);
  EXPECT_EQ(sdo->read_u(out, 5), sv::kSubstitute);
  EXPECT_EQ(sdo->read_u(out, 6), sv::kHoldLast);
  // A digital channel's substitute value is 0 or 1.
  EXPECT_EQ(sdo->write_u(index(2, sv::kInputValue), 1, 2, 2), kValueTooHigh);
  EXPECT_EQ(sdo->write_u(index(2, sv::kInputValue), 1, 1, 2), 0u);
  // The status is the device's.
  EXPECT_NE(sdo->write_u(index(2, sv::kInputStatus), 0, 1, 2), 0u);
}

TEST_F(SubstituteObjects, StoredWithTheParametersOverARestart) {
  ASSERT_EQ(sdo->write_u(index(1, sv::kOutputReaction), 3, sv::kMinimum, 2), 0u);
  ASSERT_EQ(sdo->write_u(index(2, sv::kInputReaction), 4, sv::kSubstitute, 2), 0u);
  ASSERT_EQ(sdo->write_u(index(2, sv::kInputValue), 4, 1, 2), 0u);
  const std::vector<uint8_t> save{0x73, 0x61, 0x76, 0x65};
  ASSERT_EQ(sdo->download(0xFBF2, 1, save), 0u);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (sdo->read_u(0xFBF2, 2) == 255 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_EQ(sdo->read_u(0xFBF2, 2), 0u);
  restart();
  EXPECT_EQ(sdo->read_u(index(1, sv::kOutputReaction), 3), sv::kMinimum);
  EXPECT_EQ(sdo->read_u(index(2, sv::kInputReaction), 4), sv::kSubstitute);
  EXPECT_EQ(sdo->read_u(index(2, sv::kInputValue), 4), 1u);
}

}  // namespace
}  // namespace rackcat::mdp
