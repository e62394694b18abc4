// The rackcat firmware container: what a firmware file written over FoE in BOOT holds, and what
// the emulated device "runs" after the next reset (docs/FOE.md). Little-endian, 128-byte header:
//
//   0   magic "RCATFW\r\n" (8 bytes)      32  payload CRC-32 (zlib polynomial) u32
//   8   format version u32 = 1             36  software version, 24 bytes, NUL-padded (0x100A)
//   12  header size u32 = 128              60  short version, 4 bytes, NUL-padded (0x2000:02)
//   16  vendor ID u32 (0x1018:01)          64  payload SHA-256 (32 bytes)
//   20  product code u32 (0x1018:02)       96  reserved, 28 bytes of 0
//   24  revision u32 (0x1018:03, SII 0x0C) 124 header CRC-32 over bytes 0..123
//   28  payload length u32
//   128 payload (payload length bytes)
//
// A file is accepted only whole: the header intact, written for this vendor and product, the
// payload exactly as long as the header says, CRC-32 and SHA-256 both matching.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "foe/foe_error.hpp"

namespace rackcat::mdp {

struct FirmwareInfo {
  uint32_t vendor_id = 0;
  uint32_t product_code = 0;
  uint32_t revision = 0;
  std::string software_version;  // at most 23 characters
  std::string short_version;     // at most 4 characters
};

inline constexpr size_t kFirmwareHeaderSize = 128;
inline constexpr size_t kFirmwareSoftwareVersionMax = 23;
inline constexpr size_t kFirmwareShortVersionMax = 4;

// Builds a container. Versions longer than their fields are an error (nullopt, `error` says).
std::optional<std::vector<uint8_t>> pack_firmware(const FirmwareInfo& info,
                                                  std::span<const uint8_t> payload,
                                                  std::string& error);

// Checks a complete file against the device identity; fills `info` when it is accepted.
// Errors: 0x8010 header missing or damaged (too short, magic, format, header CRC, version
// fields), 0x800D another vendor or product, 0x800C length differs from the header (truncated
// or padded) or CRC-32 / SHA-256 mismatch. `detail` says which, for the log.
foe::FoeError verify_firmware(std::span<const uint8_t> file, uint32_t vendor_id,
                              uint32_t product_code, FirmwareInfo& info, std::string& detail);

}  // namespace rackcat::mdp
