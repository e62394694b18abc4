#include "coe/mailbox_error.hpp"

#include <array>

#include "coe/bits.hpp"
#include "coe/mailbox_header.hpp"

namespace rackcat::coe {
namespace {

struct ErrorText {
  MailboxError error;
  std::string_view text;
};
constexpr std::array<ErrorText, 8> kTexts{{
    {MailboxError::Syntax, "Syntax of 6 octet mailbox header is wrong"},
    {MailboxError::UnsupportedProtocol, "The mailbox protocol is not supported"},
    {MailboxError::InvalidChannel, "Field contains wrong value"},
    {MailboxError::ServiceNotSupported, "The service in the mailbox protocol is not supported"},
    {MailboxError::InvalidHeader, "The mailbox protocol header of the mailbox protocol is wrong"},
    {MailboxError::SizeTooShort, "Length of received mailbox data is too short"},
    {MailboxError::NoMoreMemory,
     "Mailbox protocol cannot be processed because of limited "
     "resources"},
    {MailboxError::InvalidSize, "The length of data is inconsistent"},
}};

}  // namespace

std::string_view describe(MailboxError error) {
  for (const auto& t : kTexts) {
    if (t.error == error) {
      return t.text;
    }
  }
  return "Unknown mailbox error";
}

size_t write_mailbox_error(std::span<uint8_t> out, MailboxError error, uint16_t address,
                           uint8_t counter) {
  constexpr size_t kTotal = MailboxHeader::kSize + kMailboxErrorLength;
  if (out.size() < kTotal) {
    return 0;
  }
  MailboxHeader h;
  h.length = kMailboxErrorLength;
  h.address = address;
  h.type = static_cast<uint8_t>(MailboxType::Error);
  h.counter = counter;
  h.encode(out);
  le::put16(&out[6], kMailboxErrorService);
  le::put16(&out[8], static_cast<uint16_t>(error));
  return kTotal;
}

}  // namespace rackcat::coe
