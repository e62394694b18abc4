// SII EEPROM interface (ETG.1000.4 §6.4.5, ESC datasheet 0x0500-0x050F): reads of 4 or 8
// bytes, writes with write enable, error and NACK bits, reload of the configuration area, and
// the hand-over to the PDI (0x0500 bit 0 offered by the master, 0x0501 bit 0 taken by the PDI).
#include <gtest/gtest.h>

#include "ecat/registers.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

constexpr uint16_t kStation = 0x1001;

std::vector<uint8_t> command(uint16_t control, uint32_t word) {
  auto c = bytes16(control);
  const auto a = bytes32(word);
  c.insert(c.end(), a.begin(), a.end());
  return c;
}

struct SiiTest : ::testing::Test {
  explicit SiiTest(EscOptions esc = {}) : line(1, SegmentOptions{.esc = esc}) {
    line.master->send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  }
  uint16_t status() { return line.master->fprd16(kStation, 0x0502); }
  Line line;
};

TEST_F(SiiTest, EightByteReadReturnsFourWords) {
  EXPECT_EQ(status() & 0x0040, 0x0040);  // 8-byte reads supported
  EXPECT_EQ(line.master->fpwr(kStation, 0x0502, command(0x0100, 0x08)).wkc, 1);
  EXPECT_EQ(status() & 0xF800, 0);  // not busy, no error
  const auto data = line.master->fprd(kStation, 0x0508, 8).data;
  EXPECT_EQ(get32(data, 0), kVendorId);
  EXPECT_EQ(get32(data, 4), kProductCode);
}

struct SiiFourByteTest : SiiTest {
  SiiFourByteTest() : SiiTest(EscOptions{.sii_read_bytes = 4}) {}
};

TEST_F(SiiFourByteTest, FourByteReadLeavesUpperDataAlone) {
  EXPECT_EQ(status() & 0x0040, 0);
  line.master->fpwr(kStation, 0x050C, {0xEE, 0xEE, 0xEE, 0xEE});
  line.master->fpwr(kStation, 0x0502, command(0x0100, 0x0A));
  const auto data = line.master->fprd(kStation, 0x0508, 8).data;
  EXPECT_EQ(get32(data, 0), kProductCode);
  EXPECT_EQ(get32(data, 4), 0xEEEEEEEEu);
}

TEST_F(SiiTest, WriteWithoutWriteEnableIsRefused) {
  line.master->fpwr(kStation, 0x0508, bytes16(0xBEEF));
  line.master->fpwr(kStation, 0x0502, command(0x0200, 0x40));
  EXPECT_EQ(status() & 0x4000, 0x4000);  // write enable error
  EXPECT_TRUE(line.app(0).eeprom_writes.empty());
  // A NOP command clears the error bits.
  line.master->fpwr(kStation, 0x0502, command(0x0000, 0));
  EXPECT_EQ(status() & 0x6000, 0);
}

TEST_F(SiiTest, WriteWithWriteEnableStoresTheWord) {
  line.master->fpwr(kStation, 0x0508, bytes16(0xBEEF));
  line.master->fpwr(kStation, 0x0502, command(0x0201, 0x70));
  EXPECT_EQ(status() & 0x6000, 0);
  ASSERT_EQ(line.app(0).eeprom_writes.size(), 1u);
  EXPECT_EQ(line.app(0).eeprom_writes[0], std::make_pair(uint16_t{0x70}, uint16_t{0xBEEF}));
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x70), 0xBEEF);
  EXPECT_EQ(line.esc(0).eeprom()[0xE0], 0xEF);
  // Write enable is self-clearing: it does not read back.
  EXPECT_EQ(status() & 0x0001, 0);
}

TEST_F(SiiTest, ImageIsPaddedToDeclaredSizeAndBeyondIsNack) {
  // Word 0x3E = 1: a 2 Kbit (256-byte) EEPROM; words past the image read as erased.
  EXPECT_EQ(line.esc(0).eeprom().size(), 256u);
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x7F), 0xFFFF);
  line.master->fpwr(kStation, 0x0502, command(0x0100, 0x80));
  EXPECT_EQ(status() & 0x2000, 0x2000);
}

TEST_F(SiiTest, InvalidCommandIsNack) {
  line.master->fpwr(kStation, 0x0502, command(0x0300, 0x00));
  EXPECT_EQ(status() & 0x2000, 0x2000);
}

TEST_F(SiiTest, ReloadLoadsAliasFromWordFour) {
  // New alias in word 4 and the matching CRC in word 7, then reload (command 100b).
  auto write_word = [&](uint16_t word, uint16_t value) {
    line.master->fpwr(kStation, 0x0508, bytes16(value));
    line.master->fpwr(kStation, 0x0502, command(0x0201, word));
  };
  std::vector<uint8_t> area(line.esc(0).eeprom().begin(), line.esc(0).eeprom().begin() + 16);
  area[8] = 0x34;
  area[9] = 0x12;
  uint8_t crc = 0xFF;
  for (int i = 0; i < 14; ++i) {
    crc ^= area[i];
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : crc << 1);
  }
  write_word(4, 0x1234);
  write_word(7, crc);
  EXPECT_EQ(line.master->fprd16(kStation, 0x0012), 0x0000);  // not before the reload
  line.master->fpwr(kStation, 0x0502, command(0x0400, 0));
  EXPECT_EQ(line.master->fprd16(kStation, 0x0012), 0x1234);
  EXPECT_EQ(status() & 0x1800, 0);
}

TEST(Sii, BadChecksumIsReportedAndPdiStaysOff) {
  ManualClock clock;
  TestApplication app;
  app.sii[14] ^= 0xFF;  // corrupt the CRC of words 0-6
  Segment segment({&app}, clock);
  TestMaster master(segment);
  master.send(Command::Apwr, 0, 0x0010, bytes16(kStation));
  EXPECT_EQ(master.fprd16(kStation, 0x0502) & 0x1800, 0x1800);  // checksum error, not loaded
  EXPECT_EQ(master.fprd16(kStation, 0x0110) & 0x0001, 0);       // PDI not operational
  EXPECT_EQ(master.fprd8(kStation, 0x0140), 0x00);
}

TEST_F(SiiTest, ForcingEcatAccessClearsPdiAccess) {
  EXPECT_EQ(line.master->fpwr8(kStation, 0x0500, 0x02), 1);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0500), 0x00);  // bit 1 is an action, not stored
  EXPECT_EQ(line.master->fprd8(kStation, 0x0501) & 0x01, 0);
  line.master->fpwr8(kStation, 0x0500, 0x01);
  EXPECT_EQ(line.master->fprd8(kStation, 0x0500), 0x01);
}

struct SiiPdiTest : SiiTest {
  void pdi_write(uint16_t address, std::vector<uint8_t> v) {
    line.esc(0).pdi_write(address, v.data(), static_cast<uint16_t>(v.size()));
  }
  uint8_t pdi8(uint16_t address) {
    uint8_t v = 0;
    line.esc(0).pdi_read(address, &v, 1);
    return v;
  }
  uint16_t pdi16(uint16_t address) {
    uint8_t v[2] = {};
    line.esc(0).pdi_read(address, v, 2);
    return static_cast<uint16_t>(v[0] | v[1] << 8);
  }
  // What a µC writes: data, then control (write command 010b + write enable) with the address.
  void pdi_write_word(uint16_t word, uint16_t value) {
    pdi_write(0x0508, bytes16(value));
    pdi_write(0x0502, command(0x0201, word));
  }
};

TEST_F(SiiPdiTest, PdiTakesTheEepromOnlyWhenTheMasterOffersIt) {
  pdi_write(0x0501, {0x01});
  EXPECT_EQ(pdi8(0x0501), 0x00);  // 0x0500 bit 0 clear: the master keeps it
  pdi_write_word(0x0C, 0xBEEF);   // ignored: the interface is not the PDI's
  EXPECT_TRUE(line.app(0).eeprom_writes.empty());
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), kRevision & 0xFFFF);

  line.master->fpwr8(kStation, 0x0500, 0x01);  // offered
  pdi_write(0x0501, {0x01});
  EXPECT_EQ(pdi8(0x0501), 0x01);
}

TEST_F(SiiPdiTest, PdiWritesWordsWhileItHoldsTheEepromAndTheMasterReadsThemAfter) {
  line.master->fpwr8(kStation, 0x0500, 0x01);
  pdi_write(0x0501, {0x01});
  pdi_write_word(0x0C, 0x0100);  // revision low word
  EXPECT_EQ(pdi16(0x0502) & 0x6000, 0);
  ASSERT_EQ(line.app(0).eeprom_writes.size(), 1u);
  EXPECT_EQ(line.app(0).eeprom_writes[0], std::make_pair(uint16_t{0x0C}, uint16_t{0x0100}));
  // The PDI reads it back through the interface, 8 bytes a read.
  pdi_write(0x0502, command(0x0100, 0x0C));
  EXPECT_EQ(pdi16(0x0508), 0x0100);

  // The master's command is ignored while the PDI holds the EEPROM (ESC datasheet 0x0502).
  line.master->fpwr(kStation, 0x0502, command(0x0100, 0x08));
  EXPECT_EQ(line.master->fprd16(kStation, 0x0508), 0x0100);  // still the PDI's data

  pdi_write(0x0501, {0x00});  // released
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), 0x0100);
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x08), kVendorId & 0xFFFF);
}

TEST_F(SiiPdiTest, PdiWriteWithoutWriteEnableIsRefused) {
  line.master->fpwr8(kStation, 0x0500, 0x01);
  pdi_write(0x0501, {0x01});
  pdi_write(0x0508, bytes16(0xBEEF));
  pdi_write(0x0502, command(0x0200, 0x70));
  EXPECT_EQ(pdi16(0x0502) & 0x4000, 0x4000);
  EXPECT_TRUE(line.app(0).eeprom_writes.empty());
}

TEST_F(SiiPdiTest, ForcingEcatAccessTakesTheEepromFromThePdi) {
  line.master->fpwr8(kStation, 0x0500, 0x01);
  pdi_write(0x0501, {0x01});
  line.master->fpwr8(kStation, 0x0500, 0x02);  // SOEM's "EEPROM to master"
  EXPECT_EQ(pdi8(0x0501), 0x00);
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0A), kProductCode & 0xFFFF);
  pdi_write_word(0x0C, 0xBEEF);
  EXPECT_TRUE(line.app(0).eeprom_writes.empty());
  EXPECT_EQ(line.master->sii_read_word(kStation, 0x0C), kRevision & 0xFFFF);
}

TEST_F(SiiTest, EveryWordReadsAsTheImage) {
  const auto& image = line.app(0).sii;
  for (uint32_t w = 0; w < image.size() / 2; ++w) {
    ASSERT_EQ(line.master->sii_read_word(kStation, w), image[2 * w] | image[2 * w + 1] << 8)
        << "word " << w;
  }
}

}  // namespace
}  // namespace rackcat::ecat::test
