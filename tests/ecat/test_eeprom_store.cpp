// The firmware stores the device's EEPROM content through the PDI side of the SII EEPROM
// interface (ecat/slave/eeprom_store.cpp; ESC datasheet 0x0500-0x050F, ETG.1000.4 §6.4.5):
// after a device reset with a new firmware the master's next scan reads the new identity words
// (ETG.2010 Table 2, word 0x0C revision), the chip then holds exactly the device's image, and
// nothing is written while the master holds the EEPROM.
#include <gtest/gtest.h>

#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

constexpr uint16_t kStation = 0x1001;

void put16(std::vector<uint8_t>& v, size_t at, uint16_t x) {
  v[at] = static_cast<uint8_t>(x);
  v[at + 1] = static_cast<uint8_t>(x >> 8);
}

uint8_t crc8(const std::vector<uint8_t>& v) {  // ETG.2010: word 7, poly 0x07, init 0xFF
  uint8_t crc = 0xFF;
  for (int i = 0; i < 14; ++i) {
    crc ^= v[i];
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : crc << 1);
  }
  return crc;
}

struct EepromStoreTest : ::testing::Test {
  EepromStoreTest() : line(1) { line.to_preop(); }  // SOEM's scan ends with 0x0500 = 1
  Line line;
};

TEST_F(EepromStoreTest, NewRevisionIsWhatTheMasterReadsNext) {
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), kRevision & 0xFFFF);
  put16(line.app(0).sii, 0x0C * 2, 0x0100);
  put16(line.app(0).sii, 0x0D * 2, 0x0002);
  ASSERT_TRUE(line.fw(0).store_eeprom());
  EXPECT_EQ(line.esc(0).read8(0x0501) & 0x01, 0x00);  // given back
  line.to_preop();  // a new scan, as pysoem's config_init after the reset
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), 0x0100);
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0D), 0x0002);
  // Only the changed words were written.
  ASSERT_EQ(line.app(0).eeprom_writes.size(), 2u);
  EXPECT_EQ(line.app(0).eeprom_writes[0].first, 0x0C);
  EXPECT_EQ(line.app(0).eeprom_writes[1].first, 0x0D);
}

TEST_F(EepromStoreTest, TheChipHoldsExactlyTheImageAfterwards) {
  // A word the master wrote past the image is erased: the chip is what a power cycle loads.
  line.master->fpwr8(kStation, 0x0500, 0x00);
  line.master->fpwr(kStation, 0x0508, bytes16(0xBEEF));
  std::vector<uint8_t> cmd = {0x01, 0x02};
  const auto addr = bytes32(0x70);
  cmd.insert(cmd.end(), addr.begin(), addr.end());
  line.master->fpwr(kStation, 0x0502, cmd);
  ASSERT_EQ(line.master->sii_read_word(kStation, 0x70), 0xBEEF);
  line.master->fpwr8(kStation, 0x0500, 0x01);
  ASSERT_TRUE(line.fw(0).store_eeprom());
  const auto chip = line.esc(0).eeprom();
  const auto& image = line.app(0).sii;
  for (size_t i = 0; i < chip.size(); ++i) {
    ASSERT_EQ(chip[i], i < image.size() ? image[i] : 0xFF) << "byte " << i;
  }
}

TEST_F(EepromStoreTest, ConfigurationAreaChangeIsReloaded) {
  put16(line.app(0).sii, 4 * 2, 0x1234);  // configured station alias
  line.app(0).sii[14] = crc8(line.app(0).sii);
  ASSERT_TRUE(line.fw(0).store_eeprom());
  EXPECT_EQ(line.master->fprd16(kStation, 0x0012), 0x1234);  // reloaded (command 100b)
  EXPECT_EQ(line.master->fprd16(kStation, 0x0502) & 0x1800, 0);
}

TEST_F(EepromStoreTest, WaitsWhileTheMasterHoldsTheEeprom) {
  line.master->fpwr8(kStation, 0x0500, 0x00);
  put16(line.app(0).sii, 0x0C * 2, 0x0100);
  EXPECT_FALSE(line.fw(0).store_eeprom());
  EXPECT_TRUE(line.app(0).eeprom_writes.empty());
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), kRevision & 0xFFFF);
  // Offered to the PDI: the firmware's next poll (after this frame) stores it.
  line.master->fpwr8(kStation, 0x0500, 0x01);
  line.master->fprd8(kStation, 0x0130);
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), 0x0100);
}

TEST_F(EepromStoreTest, AnImageLargerThanTheChipIsRefused) {
  // Word 0x3E declares 2 Kbit (256 bytes); a 512-byte image does not fit.
  line.app(0).sii.resize(512, 0x00);
  EXPECT_FALSE(line.fw(0).store_eeprom());
  EXPECT_EQ(line.esc(0).read8(0x0501) & 0x01, 0x00);
}

}  // namespace
}  // namespace rackcat::ecat::test
