// Mailbox error replies (ETG.1000.4 §5.6 / ETG.1000.6 §5.2.3 Table 29): a message of mailbox
// type 0 whose data is Type = 0x0001 (mailbox command "error") and a 16-bit detail code. The
// MailboxServer sends them; a protocol that finds its own header wrong returns an Answer with
// the code instead of a reply.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "base/little_endian.hpp"
#include "base/mailbox_header.hpp"

namespace rackcat::mailbox {

enum class Error : uint16_t {
  None = 0x0000,                 // not an error: the protocol's reply (or no reply) stands
  Syntax = 0x0001,               // syntax of the 6-byte mailbox header is wrong
  UnsupportedProtocol = 0x0002,  // the mailbox type is not supported
  InvalidChannel = 0x0003,       // the channel field is not 0
  ServiceNotSupported = 0x0004,  // the service in the protocol header is not supported
  InvalidHeader = 0x0005,        // the protocol header is wrong (excluding the service)
  SizeTooShort = 0x0006,         // the mailbox data is too short for the service
  NoMoreMemory = 0x0007,         // the mailbox protocol cannot be processed: no resources
  InvalidSize = 0x0008,          // the length field does not fit the mailbox
};

inline constexpr uint16_t kErrorService = 0x0001;
inline constexpr size_t kErrorLength = 4;  // Type + Detail, after the mailbox header

// What a protocol answers one request with: `length` data bytes written after the mailbox
// header (0 = no reply), or a mailbox error the server sends instead.
struct Answer {
  size_t length = 0;
  Error error = Error::None;
};

inline std::string_view describe(Error error) {
  struct Text {
    Error error;
    std::string_view text;
  };
  static constexpr std::array<Text, 8> kTexts{{
      {Error::Syntax, "Syntax of 6 octet mailbox header is wrong"},
      {Error::UnsupportedProtocol, "The mailbox protocol is not supported"},
      {Error::InvalidChannel, "Field contains wrong value"},
      {Error::ServiceNotSupported, "The service in the mailbox protocol is not supported"},
      {Error::InvalidHeader, "The mailbox protocol header of the mailbox protocol is wrong"},
      {Error::SizeTooShort, "Length of received mailbox data is too short"},
      {Error::NoMoreMemory, "Mailbox protocol cannot be processed because of limited resources"},
      {Error::InvalidSize, "The length of data is inconsistent"},
  }};
  for (const auto& t : kTexts) {
    if (t.error == error) return t.text;
  }
  return "Unknown mailbox error";
}

// Writes a complete mailbox error message (header included) into `out`: returns 10, or 0 if
// `out` is shorter than 10 bytes.
inline size_t write_error(std::span<uint8_t> out, Error error, uint16_t address, uint8_t counter) {
  constexpr size_t kTotal = Header::kSize + kErrorLength;
  if (out.size() < kTotal) return 0;
  Header h;
  h.length = kErrorLength;
  h.address = address;
  h.type = static_cast<uint8_t>(Type::Error);
  h.counter = counter;
  h.encode(out);
  le::put16(&out[6], kErrorService);
  le::put16(&out[8], static_cast<uint16_t>(error));
  return kTotal;
}

}  // namespace rackcat::mailbox
