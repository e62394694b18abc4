// SII image: golden bytes from ETG.2010 (Table 2 header words, category layouts) and the
// configuration-area CRC computed by hand (polynomial division, see comments).
#include <gtest/gtest.h>

#include "esi/describe_dictionary.hpp"
#include "esi/sii_crc.hpp"
#include "esi/sii_image.hpp"
#include "esi/sii_parser.hpp"
#include "tests/esi/sample_dictionary.hpp"

namespace rackcat::esi {
namespace {

using testing::sample_dictionary;
using testing::sample_texts;

DeviceDescription sample_description() {
  auto od = sample_dictionary();
  return describe_dictionary(od, sample_texts(), SmPlan{});
}

uint16_t word(const SiiImage& img, size_t w) {
  return img.word(static_cast<uint16_t>(w));
}

// Finds the category of `type`; returns its body byte offset and length in words.
std::pair<size_t, size_t> find_category(const SiiImage& img, uint16_t type) {
  size_t w = 0x40;
  while (word(img, w) != 0xFFFF) {
    if (word(img, w) == type) return {2 * (w + 2), word(img, w + 1)};
    w += 2 + word(img, w + 1);
  }
  return {0, 0};
}

TEST(SiiCrc, MatchesHandComputedPolynomialDivision) {
  // One zero byte: register 0xFF, eight shifts, each with bit 7 set except the 7th:
  // FF->F9->F5->ED->DD->BD->7D->FA->F3 (x^8+x^2+x+1 = 0x07 feedback).
  const uint8_t zero[1] = {0};
  EXPECT_EQ(sii_crc8(zero), 0xF3);
  // Remainder of (M(x) with the first byte complemented) * x^8 mod 0x107, by long division.
  const uint8_t fourteen_zeros[14] = {};
  EXPECT_EQ(sii_crc8(fourteen_zeros), 0x30);
  const uint8_t digits[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(sii_crc8(digits), 0xFB);
}

TEST(SiiImage, ConfigAreaGoldenBytes) {
  EscConfigArea c;
  c.pdi_control = 0x0C05;
  c.pdi_config = 0x6600;
  c.sync_impulse_length = 1000;
  c.extended_pdi_config = 0;
  c.station_alias = 7;
  // Words 0..6 little-endian, word 7 = CRC-8 (0x20 by long division) with high byte 0.
  const std::vector<uint8_t> expected = {0x05, 0x0C, 0x00, 0x66, 0xE8, 0x03, 0x00, 0x00,
                                         0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x20, 0x00};
  EXPECT_EQ(encode_config_area(c), expected);
}

TEST(SiiImage, HeaderWordsCarryIdentityMailboxAndVersion) {
  auto img = encode_sii(sample_description());
  EXPECT_EQ(word(img, 0x08), testing::kVendor & 0xFFFF);
  EXPECT_EQ(word(img, 0x09), testing::kVendor >> 16);
  EXPECT_EQ(word(img, 0x0A), testing::kProduct & 0xFFFF);
  EXPECT_EQ(word(img, 0x0B), testing::kProduct >> 16);
  EXPECT_EQ(word(img, 0x0C), testing::kRevision & 0xFFFF);
  EXPECT_EQ(word(img, 0x0D), testing::kRevision >> 16);
  EXPECT_EQ(word(img, 0x0E), testing::kSerial & 0xFFFF);
  EXPECT_EQ(word(img, 0x0F), testing::kSerial >> 16);
  // Receive mailbox = SM0 (master -> slave), send mailbox = SM1. No BOOT state: bootstrap
  // words 0 (the ESM refuses INIT->BOOT with 0x0013, ETG.1000.6 Table 11).
  EXPECT_EQ(word(img, 0x14), 0);
  EXPECT_EQ(word(img, 0x15), 0);
  EXPECT_EQ(word(img, 0x16), 0);
  EXPECT_EQ(word(img, 0x17), 0);
  EXPECT_EQ(word(img, 0x18), 0x1000);
  EXPECT_EQ(word(img, 0x19), 128);
  EXPECT_EQ(word(img, 0x1A), 0x1080);
  EXPECT_EQ(word(img, 0x1B), 128);
  EXPECT_EQ(word(img, 0x1C), 0x0004);  // CoE only
  EXPECT_EQ(word(img, 0x3F), 1);       // SII version
  // Size word: Kbit - 1 of the power-of-two image; erased cells after End read 0xFF.
  EXPECT_EQ((word(img, 0x3E) + 1u) * 128u, img.bytes.size());
  EXPECT_EQ(img.bytes.size() & (img.bytes.size() - 1), 0u);
  EXPECT_EQ(img.bytes.back(), 0xFF);
}

// A device with BOOT (ETG.2010 Table 2 words 0x14-0x17) and FoE (word 0x1C bit 3).
TEST(SiiImage, BootstrapMailboxWordsAndFoeBit) {
  auto d = sample_description();
  d.foe = true;
  d.bootstrap = {0x1000, 512, 0x1600, 512};
  auto img = encode_sii(d);
  EXPECT_EQ(word(img, 0x14), 0x1000);
  EXPECT_EQ(word(img, 0x15), 512);
  EXPECT_EQ(word(img, 0x16), 0x1600);
  EXPECT_EQ(word(img, 0x17), 512);
  EXPECT_EQ(word(img, 0x18), 0x1000);  // the standard mailbox is unchanged
  EXPECT_EQ(word(img, 0x19), 128);
  EXPECT_EQ(word(img, 0x1C), 0x000C);  // CoE | FoE
}

// General, FMMU, SyncManager and DC first (inside SOEM's 4 KiB SII cache whatever the rack
// size), then Strings and the PDO categories, then End.
TEST(SiiImage, ConfigurationCategoriesFirstThenStringsAndPdosThenEnd) {
  auto img = encode_sii(sample_description());
  std::vector<uint16_t> types;
  size_t w = 0x40;
  while (word(img, w) != 0xFFFF) {
    types.push_back(word(img, w));
    w += 2 + word(img, w + 1);
  }
  EXPECT_EQ(types, (std::vector<uint16_t>{30, 40, 41, 60, 10, 50, 51}));
}

TEST(SiiImage, GeneralCategoryCoeDetailsAndStrings) {
  auto img = encode_sii(sample_description());
  auto [at, len] = find_category(img, 30);
  ASSERT_EQ(len, 16u);  // 32 bytes
  const auto& b = img.bytes;
  // CoE details: SDO 0x01 | SDO info 0x02 | PDO assign 0x04 | PDO config 0x08 | CA 0x20.
  EXPECT_EQ(b[at + 5], 0x2F);
  EXPECT_EQ(b[at + 3], 1);  // the device name is string 1
  auto [sat, slen] = find_category(img, 10);
  ASSERT_GT(slen, 0u);
  const std::string name = "Sample rack";
  EXPECT_EQ(b[sat + 1], name.size());
  EXPECT_EQ(std::string(b.begin() + sat + 2, b.begin() + sat + 2 + name.size()), name);
  EXPECT_EQ(b[at + 16], 0x11);  // ports 0 and 1: MII
}

TEST(SiiImage, FmmuAndSyncManagerCategoryBytes) {
  auto img = encode_sii(sample_description());
  const auto& b = img.bytes;
  auto [fat, flen] = find_category(img, 40);
  ASSERT_EQ(flen, 2u);
  EXPECT_EQ(std::vector<uint8_t>(b.begin() + fat, b.begin() + fat + 4),
            (std::vector<uint8_t>{1, 2, 3, 0}));  // outputs, inputs, SM status, pad
  auto [sat, slen] = find_category(img, 41);
  ASSERT_EQ(slen, 16u);  // 4 SMs x 8 bytes
  // SM0: start 0x1000, 128 bytes, control 0x26, status 0, enable 1, type 1 (mailbox out).
  EXPECT_EQ(std::vector<uint8_t>(b.begin() + sat, b.begin() + sat + 8),
            (std::vector<uint8_t>{0x00, 0x10, 0x80, 0x00, 0x26, 0x00, 0x01, 0x01}));
  EXPECT_EQ(std::vector<uint8_t>(b.begin() + sat + 8, b.begin() + sat + 16),
            (std::vector<uint8_t>{0x80, 0x10, 0x80, 0x00, 0x22, 0x00, 0x01, 0x02}));
  // SM2: 2 output bytes (0x7000:00, 16 bits); SM3: 4 x 16 + 8 bits = 9 bytes.
  EXPECT_EQ(std::vector<uint8_t>(b.begin() + sat + 16, b.begin() + sat + 24),
            (std::vector<uint8_t>{0x00, 0x11, 0x02, 0x00, 0x64, 0x00, 0x01, 0x03}));
  EXPECT_EQ(std::vector<uint8_t>(b.begin() + sat + 24, b.begin() + sat + 32),
            (std::vector<uint8_t>{0x00, 0x51, 0x09, 0x00, 0x20, 0x00, 0x01, 0x04}));
}

TEST(SiiImage, TxPdoCategoryHoldsOnlyTheAssignedPdo) {
  auto img = encode_sii(sample_description());
  const auto& b = img.bytes;
  auto [at, len] = find_category(img, 50);
  ASSERT_EQ(len, (8u + 5u * 8u) / 2u);  // 0x1A00 only: 0x1A01 is not in 0x1C13
  // Header: index 0x1A00, 5 entries, SM3, sync 0, name index, flags 0x0002 (default PDO).
  EXPECT_EQ(b[at + 0], 0x00);
  EXPECT_EQ(b[at + 1], 0x1A);
  EXPECT_EQ(b[at + 2], 5);
  EXPECT_EQ(b[at + 3], 3);
  EXPECT_EQ(b[at + 4], 0);
  EXPECT_NE(b[at + 5], 0);
  EXPECT_EQ(b[at + 6], 0x02);
  EXPECT_EQ(b[at + 7], 0x00);
  // Entry 1: 0x6002:01, name, type 0x03 (INT), 16 bits, flags 0.
  EXPECT_EQ(b[at + 8], 0x02);
  EXPECT_EQ(b[at + 9], 0x60);
  EXPECT_EQ(b[at + 10], 0x01);
  EXPECT_NE(b[at + 11], 0);
  EXPECT_EQ(b[at + 12], 0x03);
  EXPECT_EQ(b[at + 13], 16);
  // Entry 5: the 8-bit gap 0x0000:00, no name, no type.
  EXPECT_EQ(std::vector<uint8_t>(b.begin() + at + 40, b.begin() + at + 48),
            (std::vector<uint8_t>{0, 0, 0, 0, 0, 8, 0, 0}));
}

TEST(SiiImage, DcCategoryHasThreeOpModes) {
  auto img = encode_sii(sample_description());
  auto [at, len] = find_category(img, 60);
  ASSERT_EQ(len, 3u * 24u / 2u);
  // Third mode: DC SYNC0, assign activate 0x0300 at bytes 14..15, SYNC0 factor 1.
  EXPECT_EQ(img.bytes[at + 48 + 14], 0x00);
  EXPECT_EQ(img.bytes[at + 48 + 15], 0x03);
  EXPECT_EQ(img.bytes[at + 48 + 16], 0x01);
}

TEST(SiiImage, OverlongImageIsRefused) {
  auto d = sample_description();
  // 40 PDOs x 255 entries x 8 bytes > 128 KiB.
  for (int i = 0; i < 80; ++i) {
    PdoDescription p;
    p.index = static_cast<uint16_t>(0x1A10 + i);
    p.sm = 3;
    p.entries.assign(255, PdoEntryDescription{0x6000, 1, "x", 5, 8});
    d.tx_pdos.push_back(p);
  }
  EXPECT_THROW(encode_sii(d), SiiEncodeError);
}

}  // namespace
}  // namespace rackcat::esi
