// The stored-parameter file behind 0xFBF2 (store), 0xFBF4 (load), 0xFBF3 (checksum) and 0xFBF0
// (factory reset). One file, replaced atomically and durably (temporary file, fsync, rename,
// fsync of the directory), so a crash at any point leaves either the old or the new file.
//
// Layout (little-endian): "RACKCATP" (8 bytes), format version u32 (1), fingerprint u32,
// payload length u32, payload, CRC-32 (zlib) u32 over everything before it. The fingerprint
// names the parameter layout (which entries, in which order, how long) so a file written for
// another rack is "foreign" and ignored as a whole, never half-loaded.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace rackcat::mdp {

class ParameterStore {
 public:
  enum class LoadResult { Loaded, Missing, Corrupt, Foreign };

  explicit ParameterStore(std::string path) : path_(std::move(path)) {}
  const std::string& path() const { return path_; }

  // Replaces the file (creating its directory, mode 0700). False with `error` on failure; the
  // previous file is then unchanged.
  bool save(uint32_t fingerprint, std::span<const uint8_t> payload, std::string& error) const;
  // Reads and checks the file; `payload` is filled only for Loaded. `detail` says why not.
  LoadResult load(uint32_t fingerprint, std::vector<uint8_t>& payload, std::string& detail) const;
  // Deletes the file durably (factory reset). Missing is success.
  bool remove(std::string& error) const;

  static std::vector<uint8_t> encode(uint32_t fingerprint, std::span<const uint8_t> payload);

 private:
  std::string path_;
};

}  // namespace rackcat::mdp
