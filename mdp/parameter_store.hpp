// The stored-parameter file behind 0xFBF2 (store), 0xFBF4 (load), 0xFBF3 (checksum) and 0xFBF0
// (factory reset): "parameters.bin" in the slave's state directory, reached only through the
// directory's descriptor (state_directory.hpp: no symlink followed, regular files only, size
// cap). Replaced atomically and durably, so a crash at any point leaves either the old or the
// new file.
//
// Layout (little-endian): "RACKCATP" (8 bytes), format version u32 (1), fingerprint u32,
// payload length u32, payload, CRC-32 (zlib) u32 over everything before it. The fingerprint
// names the parameter layout (which entries, in which order, how long) so a file written for
// another rack is "foreign" and ignored as a whole, never half-loaded.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "mdp/state_directory.hpp"

namespace rackcat::mdp {

class ParameterStore {
 public:
  enum class LoadResult { Loaded, Missing, Corrupt, Foreign };
  static constexpr const char* kFileName = "parameters.bin";
  // Far above any rack's parameter set (a few KiB); a larger file is refused unread.
  static constexpr size_t kMaxFileBytes = 1 << 20;

  explicit ParameterStore(std::shared_ptr<const StateDirectory> dir);
  // For tests and tools: the directory `dir` (created if missing).
  explicit ParameterStore(const std::string& dir);
  std::string path() const { return dir_->path() + "/" + kFileName; }
  const StateDirectory& directory() const { return *dir_; }

  // Replaces the file. False with `error` on failure; the previous file is then unchanged.
  // `error_number`: as StateDirectory::replace (ENOSPC for a full disk...).
  bool save(uint32_t fingerprint, std::span<const uint8_t> payload, std::string& error,
            int* error_number = nullptr) const;
  // Reads and checks the file; `payload` is filled only for Loaded. `detail` says why not
  // (never quoting the file's content). A symlink, directory, FIFO or oversized file is Corrupt.
  LoadResult load(uint32_t fingerprint, std::vector<uint8_t>& payload, std::string& detail) const;
  // Deletes the file durably (factory reset). Missing is success.
  bool remove(std::string& error) const;

  static std::vector<uint8_t> encode(uint32_t fingerprint, std::span<const uint8_t> payload);
  // Checks the bytes of a parameter file (as load() does with the stored one); `source` names
  // it in `detail`. Corrupt: length or CRC-32 wrong; Foreign: magic, format or fingerprint.
  static LoadResult decode(std::span<const uint8_t> bytes, uint32_t fingerprint,
                           std::vector<uint8_t>& payload, std::string& detail,
                           const std::string& source);

 private:
  std::shared_ptr<const StateDirectory> dir_;
};

}  // namespace rackcat::mdp
