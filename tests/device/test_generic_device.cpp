// GenericDevice: process-data sizes per the ESI, outputs readable back, inputs set from outside
// (and, with CoE, visible in the mapped objects the master reads over SDO).
#include <gtest/gtest.h>

#include <array>

#include "device/esi_device.hpp"
#include "device/generic_device.hpp"

namespace rackcat::device {
namespace {

const std::string kFile = std::string(RACKCAT_DEVICE_TEST_DATA) + "/rackcat-test-devices.xml";

TEST(GenericDevice, DigitalOutputsReadBack) {
  GenericDevice dev(load_esi_device(kFile, DeviceSelector::named("RC2008")));
  EXPECT_EQ(dev.process_data_sizes().outputs, 1);
  EXPECT_EQ(dev.process_data_sizes().inputs, 0);
  const std::array<uint8_t, 1> out{0xA5};
  dev.on_outputs(out);
  EXPECT_EQ(dev.outputs(), std::vector<uint8_t>{0xA5});
}

TEST(GenericDevice, DigitalInputsFromOutside) {
  GenericDevice dev(load_esi_device(kFile, DeviceSelector::named("RC1008")));
  EXPECT_EQ(dev.process_data_sizes().inputs, 1);
  const std::array<uint8_t, 1> src{0x3C};
  dev.set_input_bits(0, 8, src, 0);
  std::array<uint8_t, 1> in{};
  dev.update_inputs(in);
  EXPECT_EQ(in[0], 0x3C);
}

TEST(GenericDevice, AnalogInputsThroughMappedObjects) {
  GenericDevice dev(load_esi_device(kFile, DeviceSelector::named("RC3102")));
  ASSERT_EQ(dev.process_data_sizes().inputs, 8);
  const std::array<uint8_t, 2> value{0x34, 0x12};
  dev.set_input_bits(16, 16, value, 0);  // channel 1 value
  std::array<uint8_t, 8> in{};
  dev.update_inputs(in);
  EXPECT_EQ(in[2], 0x34);
  EXPECT_EQ(in[3], 0x12);
  EXPECT_EQ(dev.dictionary().find(0x6000)->get_u(0x11), 0x1234u);
}

TEST(GenericDevice, SiiServed) {
  GenericDevice dev(load_esi_device(kFile, DeviceSelector::named("RC1100")));
  EXPECT_GE(dev.eeprom().size(), 256u);
  EXPECT_EQ(dev.process_data_sizes().inputs, 0);
  EXPECT_EQ(dev.process_data_sizes().outputs, 0);
}

// ETG.2010 §2: the categories start at word 0x40 and end with 0xFFFF within the EEPROM size of
// word 0x3E ((value + 1) Kbit); a master walks them up to that size (ethercrab does).
TEST(GenericDevice, SiiCategoriesEndWithinTheEepromSize) {
  for (const char* name : {"RC1100", "RC1008", "RC2008", "RC3102", "RC4004"}) {
    GenericDevice dev(load_esi_device(kFile, DeviceSelector::named(name)));
    const auto sii = dev.eeprom();
    auto word = [&](size_t w) { return static_cast<uint16_t>(sii[2 * w] | (sii[2 * w + 1] << 8)); };
    const size_t size_bytes = (static_cast<size_t>(word(0x3E)) + 1) * 1024 / 8;
    EXPECT_EQ(size_bytes, sii.size()) << name;
    size_t w = 0x40;
    while (2 * w + 4 <= size_bytes && word(w) != 0xFFFF) w += 2 + word(w + 1);
    EXPECT_LT(2 * w + 1, size_bytes) << name << ": no end marker within " << size_bytes;
    if (2 * w + 1 < size_bytes) {
      EXPECT_EQ(word(w), 0xFFFF) << name;
    }
  }
}

}  // namespace
}  // namespace rackcat::device
