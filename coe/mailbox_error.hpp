// Mailbox error replies (ETG.1000.4 §5.6 / ETG.1000.6 §5.2.3 Table 29): mailbox type 0, then
// Type = 0x0001 (mailbox command "error") and a 16-bit detail code.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace rackcat::coe {

enum class MailboxError : uint16_t {
  Syntax = 0x0001,               // syntax of the 6-byte mailbox header is wrong
  UnsupportedProtocol = 0x0002,  // the mailbox type is not supported
  InvalidChannel = 0x0003,       // the channel field is not 0
  ServiceNotSupported = 0x0004,  // the service in the protocol header is not supported
  InvalidHeader = 0x0005,        // the protocol header is wrong (excluding the service)
  SizeTooShort = 0x0006,         // the mailbox data is too short for the service
  NoMoreMemory = 0x0007,         // the mailbox protocol cannot be processed: no resources
  InvalidSize = 0x0008,          // the length field does not fit the mailbox
};

inline constexpr uint16_t kMailboxErrorService = 0x0001;
inline constexpr size_t kMailboxErrorLength = 4;  // Type + Detail, after the mailbox header

std::string_view describe(MailboxError error);

// Writes a complete mailbox error message (header included) into `out`: returns 10, or 0 if
// `out` is shorter than 10 bytes.
size_t write_mailbox_error(std::span<uint8_t> out, MailboxError error, uint16_t address,
                           uint8_t counter);

}  // namespace rackcat::coe
