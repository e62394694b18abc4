// The SII parser reads back what the encoder wrote, and refuses broken images with a message
// that names the problem.
#include <gtest/gtest.h>

#include "base/little_endian.hpp"
#include "esi/describe_dictionary.hpp"
#include "esi/sii_image.hpp"
#include "esi/sii_parser.hpp"
#include "tests/esi/sample_dictionary.hpp"

namespace rackcat::esi {
namespace {

DeviceDescription sample_description() {
  auto od = testing::sample_dictionary();
  return describe_dictionary(od, testing::sample_texts(), SmPlan{});
}

std::string parse_error(std::span<const uint8_t> image) {
  try {
    parse_sii(image);
  } catch (const SiiParseError& e) {
    return e.what();
  }
  return "";
}

TEST(SiiParser, RoundTripsEveryField) {
  auto d = sample_description();
  d.config.station_alias = 0x1234;
  auto img = encode_sii(d);
  auto info = parse_sii(img.span());
  EXPECT_EQ(info.pdi_control, d.config.pdi_control);
  EXPECT_EQ(info.pdi_config, d.config.pdi_config);
  EXPECT_EQ(info.sync_impulse_length, d.config.sync_impulse_length);
  EXPECT_EQ(info.station_alias, 0x1234);
  EXPECT_EQ(info.vendor_id, d.vendor_id);
  EXPECT_EQ(info.product_code, d.product_code);
  EXPECT_EQ(info.revision, d.revision);
  EXPECT_EQ(info.serial, d.serial);
  EXPECT_EQ(info.standard_receive_offset, d.sms[0].start);
  EXPECT_EQ(info.standard_receive_size, d.sms[0].default_size);
  EXPECT_EQ(info.standard_send_offset, d.sms[1].start);
  EXPECT_EQ(info.standard_send_size, d.sms[1].default_size);
  EXPECT_EQ(info.mailbox_protocol, sii::kProtoCoE);
  EXPECT_EQ(info.version, 1);
  ASSERT_TRUE(info.has_general);
  EXPECT_EQ(info.string(info.general.name_idx), d.device_name);
  EXPECT_EQ(info.string(info.general.order_idx), d.order_code);
  EXPECT_EQ(info.string(info.general.group_idx), d.group_type);
  ASSERT_EQ(info.sms.size(), d.sms.size());
  for (size_t i = 0; i < d.sms.size(); ++i) {
    EXPECT_EQ(info.sms[i].start, d.sms[i].start);
    EXPECT_EQ(info.sms[i].length, d.sms[i].default_size);
    EXPECT_EQ(info.sms[i].control, d.sms[i].control);
    EXPECT_EQ(info.sms[i].enable & 1, d.sms[i].enable ? 1 : 0);
    EXPECT_EQ(info.sms[i].type, static_cast<uint8_t>(d.sms[i].type));
  }
  EXPECT_EQ(info.fmmus, (std::vector<uint8_t>{1, 2, 3, 0}));
  ASSERT_EQ(info.tx_pdos.size(), 1u);
  ASSERT_EQ(info.rx_pdos.size(), 1u);
  const auto& tx = info.tx_pdos[0];
  EXPECT_EQ(tx.index, 0x1A00);
  EXPECT_EQ(tx.sm, 3);
  EXPECT_EQ(info.string(tx.name_idx), "TxPDO Mapping (AINx8)");
  ASSERT_EQ(tx.entries.size(), 5u);
  EXPECT_EQ(tx.entries[1].index, 0x6002);
  EXPECT_EQ(tx.entries[1].subindex, 2);
  EXPECT_EQ(info.string(tx.entries[1].name_idx), "AIN[2]");
  EXPECT_EQ(tx.entries[1].bit_length, 16);
  EXPECT_EQ(info.rx_pdos[0].entries[0].index, 0x7000);
  ASSERT_EQ(info.dc_modes.size(), 3u);
  EXPECT_EQ(info.string(info.dc_modes[2].name_idx), "DC");
  EXPECT_EQ(info.dc_modes[2].assign_activate, 0x0300);
  EXPECT_FALSE(format_sii(info).empty());
}

TEST(SiiParser, WrongCrcIsReported) {
  auto img = encode_sii(sample_description());
  img.bytes[2] ^= 0x01;  // flip a PDI configuration bit, keep the old CRC
  EXPECT_NE(parse_error(img.span()).find("CRC mismatch"), std::string::npos);
}

TEST(SiiParser, CategoryRunningPastTheEndIsReported) {
  auto img = encode_sii(sample_description());
  // Declare the General category (first, at word 0x40) longer than the whole image.
  le::put16(&img.bytes[2 * 0x41], static_cast<uint16_t>(img.bytes.size()));
  auto msg = parse_error(img.span());
  EXPECT_NE(msg.find("General category"), std::string::npos) << msg;
  EXPECT_NE(msg.find("runs past the end"), std::string::npos) << msg;
}

TEST(SiiParser, MissingEndIsReported) {
  auto img = encode_sii(sample_description());
  // Cut the image right after the last category, before the End word.
  auto info = parse_sii(img.span());
  const auto& last = info.categories.back();
  size_t end_word = last.word_address + 2u + last.length_words;
  std::vector<uint8_t> cut(img.bytes.begin(), img.bytes.begin() + 2 * end_word);
  EXPECT_NE(parse_error(cut).find("no End category"), std::string::npos);
}

TEST(SiiParser, OversizeShortAndOddImagesAreReported) {
  std::vector<uint8_t> huge(sii::kMaxBytes + 2, 0xFF);
  EXPECT_NE(parse_error(huge).find("more than"), std::string::npos);
  std::vector<uint8_t> shorty(100, 0);
  EXPECT_NE(parse_error(shorty).find("words 0x00-0x3F"), std::string::npos);
  auto img = encode_sii(sample_description());
  std::vector<uint8_t> odd(img.bytes.begin(), img.bytes.end() - 1);
  EXPECT_NE(parse_error(odd).find("not whole words"), std::string::npos);
}

TEST(SiiParser, MalformedCategoryBodiesAreReported) {
  auto img = encode_sii(sample_description());
  auto info = parse_sii(img.span());
  for (const auto& c : info.categories) {
    if (c.type != sii::kCatTxPdo) continue;
    // Claim 200 entries for the first TxPDO: they run past the category.
    img.bytes[2 * (c.word_address + 2) + 2] = 200;
  }
  auto msg = parse_error(img.span());
  EXPECT_NE(msg.find("TxPDO category"), std::string::npos) << msg;
}

}  // namespace
}  // namespace rackcat::esi
