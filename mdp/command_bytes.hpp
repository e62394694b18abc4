// Byte sequences and status values of the command objects 0xF002 and 0xFBF0..0xFBF4 (ETG.5003.1
// command objects, guide Appendix A).
#pragma once

#include <array>
#include <cstdint>

namespace rackcat::mdp::cmd {

inline constexpr std::array<uint8_t, 5> kReset{0x74, 0x65, 0x73, 0x65, 0x72};  // 0xFBF0/0xFBF1
inline constexpr uint8_t kDeviceReset = 0x00;                                  // 0xFBF0 byte 5
inline constexpr uint8_t kFactoryReset = 0x66;
inline constexpr std::array<uint8_t, 4> kSave{0x73, 0x61, 0x76, 0x65};  // 0xFBF2 "save"
inline constexpr std::array<uint8_t, 4> kLoad{0x6C, 0x6F, 0x61, 0x64};  // 0xFBF4 "load"
inline constexpr std::array<uint8_t, 4> kScan{0x73, 0x63, 0x61, 0x6E};  // 0xF002 "scan"

// Read values of subindex 1: 0xFBF2/0xFBF4 bit 0 = executed on command; 0xFBF3 bit 0 = stored
// parameters exist, bits 1..3 = CRC-32, MD5, SHA-1 offered.
inline constexpr std::array<uint8_t, 4> kStoreCapabilities{0x01, 0, 0, 0};
inline constexpr std::array<uint8_t, 4> kLoadCapabilities{0x01, 0, 0, 0};
inline constexpr std::array<uint8_t, 4> kChecksumCapabilities{0x0F, 0, 0, 0};
inline constexpr uint8_t kChecksumDefault = 0x01;
inline constexpr uint8_t kChecksumCrc32 = 0x02;
inline constexpr uint8_t kChecksumMd5 = 0x04;
inline constexpr uint8_t kChecksumSha1 = 0x08;
// Status byte + 0 + up to 20 checksum bytes (SHA-1). The guide's ARRAY [0..17] holds MD5 but
// not the SHA-1 its own subindex 1 offers; ETG.5003.1 allows up to 64 checksum bytes.
inline constexpr uint16_t kChecksumResponseBytes = 22;

// Subindex 2 status values (ETG.5003.1).
inline constexpr uint8_t kStatusDoneNoResponse = 0;
inline constexpr uint8_t kStatusDoneWithResponse = 1;
inline constexpr uint8_t kStatusError = 2;
inline constexpr uint8_t kStatusExecuting = 255;
// 0xF002:02 (guide Appendix A): 0 only before the first command; 100..200 the progress in
// percent plus 100, so a completed scan reads 200.
inline constexpr uint8_t kStatusScanComplete = 200;

}  // namespace rackcat::mdp::cmd
