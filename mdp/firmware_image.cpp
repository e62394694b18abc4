// Packing and verification of the firmware container (firmware_image.hpp): CRC-32 from zlib,
// SHA-256 from OpenSSL's libcrypto.
#include "mdp/firmware_image.hpp"

#include <openssl/evp.h>
#include <zlib.h>

#include <algorithm>
#include <cstring>

#include "coe/bits.hpp"

namespace rackcat::mdp {
namespace {

constexpr char kMagic[8] = {'R', 'C', 'A', 'T', 'F', 'W', '\r', '\n'};
constexpr uint32_t kFormat = 1;
constexpr size_t kSoftwareVersionAt = 36, kSoftwareVersionField = 24;
constexpr size_t kShortVersionAt = 60;
constexpr size_t kShaAt = 64;
constexpr size_t kHeaderCrcAt = 124;

uint32_t crc32_of(std::span<const uint8_t> d) {
  return static_cast<uint32_t>(
      ::crc32(::crc32(0L, Z_NULL, 0), d.data(), static_cast<uInt>(d.size())));
}

bool sha256_of(std::span<const uint8_t> d, uint8_t out[32]) {
  unsigned int len = 0;
  return EVP_Digest(d.data(), d.size(), out, &len, EVP_sha256(), nullptr) == 1 && len == 32;
}

// A NUL-padded printable ASCII field: the text before the first NUL, nothing but NULs after.
bool read_text(const uint8_t* p, size_t field, std::string& out) {
  size_t n = 0;
  while (n < field && p[n] != 0) {
    if (p[n] < 0x20 || p[n] > 0x7E) return false;
    ++n;
  }
  for (size_t i = n; i < field; ++i) {
    if (p[i] != 0) return false;
  }
  out.assign(reinterpret_cast<const char*>(p), n);
  return true;
}

bool printable(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c <= 0x7E; });
}

}  // namespace

std::optional<std::vector<uint8_t>> pack_firmware(const FirmwareInfo& info,
                                                  std::span<const uint8_t> payload,
                                                  std::string& error) {
  if (info.software_version.size() > kFirmwareSoftwareVersionMax ||
      !printable(info.software_version)) {
    error = "software version must be at most 23 printable ASCII characters";
    return std::nullopt;
  }
  if (info.short_version.size() > kFirmwareShortVersionMax || !printable(info.short_version)) {
    error = "short version must be at most 4 printable ASCII characters";
    return std::nullopt;
  }
  if (payload.size() > 0xFFFFFFFFu - kFirmwareHeaderSize) {
    error = "payload too large";
    return std::nullopt;
  }
  std::vector<uint8_t> out(kFirmwareHeaderSize + payload.size(), 0);
  uint8_t* h = out.data();
  std::memcpy(h, kMagic, 8);
  le::put32(h + 8, kFormat);
  le::put32(h + 12, kFirmwareHeaderSize);
  le::put32(h + 16, info.vendor_id);
  le::put32(h + 20, info.product_code);
  le::put32(h + 24, info.revision);
  le::put32(h + 28, static_cast<uint32_t>(payload.size()));
  le::put32(h + 32, crc32_of(payload));
  // NUL-padded fields: the buffer is zero, the text goes in without a terminator of its own.
  std::copy(info.software_version.begin(), info.software_version.end(), h + kSoftwareVersionAt);
  std::copy(info.short_version.begin(), info.short_version.end(), h + kShortVersionAt);
  if (!sha256_of(payload, h + kShaAt)) {
    error = "SHA-256 failed";
    return std::nullopt;
  }
  le::put32(h + kHeaderCrcAt, crc32_of({h, kHeaderCrcAt}));
  std::copy(payload.begin(), payload.end(), out.begin() + kFirmwareHeaderSize);
  return out;
}

foe::FoeError verify_firmware(std::span<const uint8_t> file, uint32_t vendor_id,
                              uint32_t product_code, FirmwareInfo& info, std::string& detail) {
  using foe::FoeError;
  if (file.size() < kFirmwareHeaderSize) {
    detail = "shorter than the 128-byte firmware header";
    return FoeError::FileHeaderDoesNotExist;
  }
  const uint8_t* h = file.data();
  if (std::memcmp(h, kMagic, 8) != 0) {
    detail = "not a rackcat firmware file (magic)";
    return FoeError::FileHeaderDoesNotExist;
  }
  if (le::get32(h + kHeaderCrcAt) != crc32_of({h, kHeaderCrcAt})) {
    detail = "firmware header CRC-32 mismatch";
    return FoeError::FileHeaderDoesNotExist;
  }
  if (le::get32(h + 8) != kFormat || le::get32(h + 12) != kFirmwareHeaderSize) {
    detail = "unknown firmware format version or header size";
    return FoeError::FileHeaderDoesNotExist;
  }
  FirmwareInfo in;
  in.vendor_id = le::get32(h + 16);
  in.product_code = le::get32(h + 20);
  in.revision = le::get32(h + 24);
  if (!read_text(h + kSoftwareVersionAt, kSoftwareVersionField, in.software_version) ||
      in.software_version.size() > kFirmwareSoftwareVersionMax ||
      !read_text(h + kShortVersionAt, kFirmwareShortVersionMax, in.short_version)) {
    detail = "firmware version fields are not NUL-padded ASCII";
    return FoeError::FileHeaderDoesNotExist;
  }
  for (size_t i = 96; i < kHeaderCrcAt; ++i) {
    if (h[i] != 0) {
      detail = "reserved header bytes are not 0";
      return FoeError::FileHeaderDoesNotExist;
    }
  }
  if (in.vendor_id != vendor_id || in.product_code != product_code) {
    detail = "firmware for vendor/product " + std::to_string(in.vendor_id) + "/" +
             std::to_string(in.product_code) + ", this device is " + std::to_string(vendor_id) +
             "/" + std::to_string(product_code);
    return FoeError::FirmwareDoesNotFitHardware;
  }
  const uint32_t length = le::get32(h + 28);
  const auto payload = file.subspan(kFirmwareHeaderSize);
  if (payload.size() != length) {
    detail = "payload is " + std::to_string(payload.size()) + " bytes, the header says " +
             std::to_string(length);
    return FoeError::WrongChecksum;
  }
  if (crc32_of(payload) != le::get32(h + 32)) {
    detail = "payload CRC-32 mismatch";
    return FoeError::WrongChecksum;
  }
  uint8_t sha[32];
  if (!sha256_of(payload, sha) || std::memcmp(sha, h + kShaAt, 32) != 0) {
    detail = "payload SHA-256 mismatch";
    return FoeError::WrongChecksum;
  }
  info = std::move(in);
  return FoeError::None;
}

}  // namespace rackcat::mdp
