// The files a device from its ESI serves over FoE (ETG.1000.6 §5.8) when its ESI announces
// <Mailbox><FoE/>: a flat directory of its own (the line's state directory / "esi-<position>"),
// files written by the master are stored there and read back. The ESI does not say what a
// device's files mean, so they are kept as written, nothing is executed or interpreted.
//
// Rules (each refusal is the FoE error the master gets):
// - names: 1..48 of [A-Za-z0-9._-], not starting with '.' (0x8004 Illegal otherwise); they
//   never reach a path: each is one component beneath the directory's descriptor, opened with
//   O_NOFOLLOW, so a planted link is refused (never followed) and ".." is not a name;
// - the device's FoE password (rackcat run --foe-password, docs/FOE.md) on every read and
//   write request (0x800A No rights otherwise);
// - at most kMaxFiles files and kMaxFileBytes per file (0x8003 Disk full);
// - a write lands in a temporary file, fsync'ed and renamed over the old file on the last
//   packet (then the directory is fsync'ed): a reader sees the old file or the new one;
// - an unusable directory (not creatable, a link) refuses every request with 0x8000.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "foe/file_backend.hpp"

namespace rackcat::device {

class FoeFiles final : public foe::FileBackend {
 public:
  static constexpr size_t kMaxFiles = 64;
  static constexpr size_t kMaxFileBytes = 1u << 20;

  // The subdirectory `name` (one component) of the directory open as `parent_fd` (created
  // 0700 when missing; parent_fd < 0 or a link there: unusable).
  FoeFiles(int parent_fd, const std::string& name, uint32_t password);
  ~FoeFiles() override;
  FoeFiles(const FoeFiles&) = delete;
  FoeFiles& operator=(const FoeFiles&) = delete;

  bool usable() const { return dir_fd_ >= 0; }

  foe::FoeError read_file(std::string_view name, uint32_t password, size_t max_size,
                          std::vector<uint8_t>& contents) override;
  foe::FoeError begin_write(std::string_view name, uint32_t password) override;
  foe::FoeError write_data(std::span<const uint8_t> data) override;
  foe::CommitProgress commit() override;
  foe::CommitProgress poll_commit() override { return result_; }
  void abort_write() override;

  static bool valid_name(std::string_view name);

 private:
  foe::FoeError check(std::string_view name, uint32_t password) const;
  size_t file_count() const;

  int dir_fd_ = -1;
  uint32_t password_;
  int tmp_fd_ = -1;
  std::string name_;  // the file being written
  size_t written_ = 0;
  foe::CommitProgress result_;
};

}  // namespace rackcat::device
