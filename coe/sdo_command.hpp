// The first byte of an SDO request/response body (ETG.1000.6 §5.6.2, Tables 34-44): command
// specifier in bits 5-7 plus per-service flag bits. One table of constants, used by the server
// and its tests alike.
#pragma once

#include <cstddef>
#include <cstdint>

namespace rackcat::coe::sdo {

// Client command specifiers (requests, bits 5-7).
inline constexpr uint8_t kCcsDownloadSegment = 0;
inline constexpr uint8_t kCcsDownloadInitiate = 1;
inline constexpr uint8_t kCcsUploadInitiate = 2;
inline constexpr uint8_t kCcsUploadSegment = 3;
inline constexpr uint8_t kCcsAbort = 4;

// Server command specifiers (responses, bits 5-7).
inline constexpr uint8_t kScsUploadSegment = 0;
inline constexpr uint8_t kScsDownloadSegment = 1;
inline constexpr uint8_t kScsUploadInitiate = 2;
inline constexpr uint8_t kScsDownloadInitiate = 3;

// Flag bits of the initiate commands.
inline constexpr uint8_t kSizeIndicated = 0x01;   // bit 0
inline constexpr uint8_t kExpedited = 0x02;       // bit 1
inline constexpr uint8_t kCompleteAccess = 0x10;  // bit 4
// Segment commands: bit 0 = last segment ("no more segments"), bits 1-3 = 7 - data bytes when
// fewer than 7, bit 4 = toggle.
inline constexpr uint8_t kLastSegment = 0x01;
inline constexpr uint8_t kToggle = 0x10;

// The abort command byte, exactly (ETG.1000.6 §5.6.2.7: 0x80 with no other bits).
inline constexpr uint8_t kAbortCommand = 0x80;

// Body sizes after the CoE header.
inline constexpr size_t kInitiateBody = 8;    // cmd, index, subindex, 4 data/size bytes
inline constexpr size_t kSegmentMinBody = 8;  // cmd + 7 data bytes (minimum mailbox length 10)

constexpr uint8_t specifier(uint8_t command) {
  return static_cast<uint8_t>(command >> 5);
}

}  // namespace rackcat::coe::sdo
