// Parameter file format and checks (see parameter_store.hpp); the file system side is
// StateDirectory's.
#include "mdp/parameter_store.hpp"

#include <zlib.h>

#include <cstring>

#include "base/little_endian.hpp"

namespace rackcat::mdp {
namespace {

// Appends to the image being built: room for `n` bytes at its end, written by rackcat::le
// (ETG.2010 §2: words little-endian).
uint8_t* grow(std::vector<uint8_t>& out, size_t n) {
  out.resize(out.size() + n);
  return &out[out.size() - n];
}

constexpr char kMagic[8] = {'R', 'A', 'C', 'K', 'C', 'A', 'T', 'P'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeader = 8 + 4 + 4 + 4;

uint32_t crc32_of(const uint8_t* data, size_t n) {
  return static_cast<uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), data, static_cast<uInt>(n)));
}

}  // namespace

ParameterStore::ParameterStore(std::shared_ptr<const StateDirectory> dir) : dir_(std::move(dir)) {}

ParameterStore::ParameterStore(const std::string& dir) : dir_(StateDirectory::open(dir)) {}

std::vector<uint8_t> ParameterStore::encode(uint32_t fingerprint,
                                            std::span<const uint8_t> payload) {
  std::vector<uint8_t> out(kMagic, kMagic + 8);
  le::put32(grow(out, 4), kVersion);
  le::put32(grow(out, 4), fingerprint);
  le::put32(grow(out, 4), static_cast<uint32_t>(payload.size()));
  out.insert(out.end(), payload.begin(), payload.end());
  // The CRC covers everything before it: computed before the vector grows (the order in which
  // a call's arguments are evaluated is unspecified - clang grew first, gcc did not).
  const uint32_t crc = crc32_of(out.data(), out.size());
  le::put32(grow(out, 4), crc);
  return out;
}

bool ParameterStore::save(uint32_t fingerprint, std::span<const uint8_t> payload,
                          std::string& error, int* error_number) const {
  return dir_->replace(kFileName, encode(fingerprint, payload), 0600, error, error_number);
}

ParameterStore::LoadResult ParameterStore::load(uint32_t fingerprint, std::vector<uint8_t>& payload,
                                                std::string& detail) const {
  std::vector<uint8_t> bytes;
  std::string why;
  switch (dir_->read(kFileName, kMaxFileBytes, bytes, why)) {
    case StateDirectory::ReadResult::Missing:
      detail = "no stored parameters (" + why + ")";
      return LoadResult::Missing;
    case StateDirectory::ReadResult::Refused:
      detail = "ignored parameter file: " + why;
      return LoadResult::Corrupt;
    case StateDirectory::ReadResult::Ok:
      break;
  }
  return decode(bytes, fingerprint, payload, detail, path());
}

ParameterStore::LoadResult ParameterStore::decode(std::span<const uint8_t> bytes,
                                                  uint32_t fingerprint,
                                                  std::vector<uint8_t>& payload,
                                                  std::string& detail, const std::string& source) {
  if (bytes.size() < kHeader + 4 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    detail = "ignored foreign parameter file " + source + ": not a rackcat parameter file";
    return LoadResult::Foreign;
  }
  const uint32_t length = le::get32(&bytes[16]);
  if (bytes.size() != kHeader + static_cast<size_t>(length) + 4) {
    detail = "ignored corrupt parameter file " + source + ": length " +
             std::to_string(bytes.size()) + " does not match its header";
    return LoadResult::Corrupt;
  }
  if (crc32_of(bytes.data(), kHeader + length) != le::get32(&bytes[kHeader + length])) {
    detail = "ignored corrupt parameter file " + source + ": checksum mismatch";
    return LoadResult::Corrupt;
  }
  if (le::get32(&bytes[8]) != kVersion || le::get32(&bytes[12]) != fingerprint) {
    detail = "ignored foreign parameter file " + source +
             ": written for another rack configuration or format";
    return LoadResult::Foreign;
  }
  payload.assign(bytes.begin() + kHeader, bytes.begin() + static_cast<long>(kHeader + length));
  detail = "loaded stored parameters from " + source;
  return LoadResult::Loaded;
}

bool ParameterStore::remove(std::string& error) const {
  if (!dir_->usable()) return true;  // nothing can be stored there: nothing to delete
  return dir_->remove(kFileName, error);
}

}  // namespace rackcat::mdp
