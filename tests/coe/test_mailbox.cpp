// Mailbox (base/mailbox_header.hpp) and CoE headers and mailbox error messages
// (base/mailbox_error.hpp), from ETG.1000.4 §5.6 / ETG.1000.6 §5.2.
#include <gtest/gtest.h>

#include <vector>

#include "base/mailbox_error.hpp"
#include "base/mailbox_header.hpp"
#include "coe/coe_header.hpp"

namespace rackcat::coe {
namespace {

using mailbox::describe;
using mailbox::Header;
using mailbox::Type;
using mailbox::write_error;

TEST(MailboxHeader, EncodesLengthAddressChannelPriorityTypeCounter) {
  Header h;
  h.length = 0x000A;
  h.address = 0x1001;
  h.channel = 0;
  h.priority = 3;
  h.type = static_cast<uint8_t>(Type::CoE);
  h.counter = 5;
  std::vector<uint8_t> out(6);
  ASSERT_TRUE(h.encode(out));
  EXPECT_EQ(out, (std::vector<uint8_t>{0x0A, 0x00, 0x01, 0x10, 0xC0, 0x53}));
  std::vector<uint8_t> small(5);
  EXPECT_FALSE(h.encode(small));
}

TEST(MailboxHeader, DecodesAndIgnoresReservedBit) {
  const std::vector<uint8_t> in{0x0A, 0x00, 0x00, 0x00, 0x05, 0xF3};
  auto h = Header::decode(in);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->length, 10);
  EXPECT_EQ(h->channel, 5);
  EXPECT_EQ(h->priority, 0);
  EXPECT_EQ(h->mailbox_type(), Type::CoE);
  EXPECT_EQ(h->counter, 7);
  EXPECT_FALSE(Header::decode(std::vector<uint8_t>{0x0A, 0x00}).has_value());
}

TEST(MailboxHeader, CounterCyclesOneToSeven) {
  EXPECT_EQ(mailbox::next_counter(0), 1);
  EXPECT_EQ(mailbox::next_counter(6), 7);
  EXPECT_EQ(mailbox::next_counter(7), 1);
}

TEST(CoeHeader, NumberNineBitsServiceTopNibble) {
  std::vector<uint8_t> out(2);
  CoeHeader{0x1FF, 8}.encode(out);
  EXPECT_EQ(out, (std::vector<uint8_t>{0xFF, 0x81}));
  auto h = CoeHeader::decode(std::vector<uint8_t>{0x00, 0x20});
  ASSERT_TRUE(h);
  EXPECT_EQ(h->service, 2);
  EXPECT_EQ(h->number, 0);
}

TEST(MailboxErrorReply, ReplyIsTypeZeroServiceOneWithDetail) {
  std::vector<uint8_t> out(16, 0xEE);
  ASSERT_EQ(write_error(out, mailbox::Error::UnsupportedProtocol, 0, 2), 10u);
  out.resize(10);
  EXPECT_EQ(out,
            (std::vector<uint8_t>{0x04, 0x00, 0x00, 0x00, 0x00, 0x20, 0x01, 0x00, 0x02, 0x00}));
  std::vector<uint8_t> small(9);
  EXPECT_EQ(write_error(small, mailbox::Error::Syntax, 0, 1), 0u);
  EXPECT_EQ(describe(mailbox::Error::SizeTooShort), "Length of received mailbox data is too short");
}

}  // namespace
}  // namespace rackcat::coe
